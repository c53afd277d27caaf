"""Reading program text: positions, errors at file:line:column, a lexer and a parser base.

Every reader (:mod:`workcell.robotprog.read_krl` and the others) turns text into tokens
with :func:`tokenize` (one regular expression per token kind, tried in order) and reads
them with :class:`Parser`; every error is a :class:`~workcell.errors.ProgramError` whose
message starts with ``file:line:column:``.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import NamedTuple

from workcell.errors import ProgramError

__all__ = ["NUMBER", "Loc", "Parser", "Token", "error", "tokenize"]

NUMBER = r"(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?"  # every language's numbers: 12, 1.5, .5, 1e-3


class Loc(NamedTuple):
    """A place in a program file: ``path``, 1-based ``line`` and ``col``."""

    path: str
    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.path}:{self.line}:{self.col}"


def error(loc: Loc, message: str) -> ProgramError:
    """A ProgramError saying ``file:line:column: message``."""
    return ProgramError(f"{loc}: {message}")


class Token(NamedTuple):
    """``kind`` (the rule's name, "nl" for a line end, "eof"), ``text`` and where it starts."""

    kind: str
    text: str
    loc: Loc

    @property
    def upper(self) -> str:
        return self.text.upper()


def tokenize(
    text: str, path: str, rules: Sequence[tuple[str, str]], *, flags: int = 0
) -> list[Token]:
    """Tokens of ``text`` by ``rules`` ((kind, regex), first match wins; kinds starting
    with "_" are dropped, "nl" marks line ends). A character no rule matches is a
    ProgramError at its place."""
    pattern = re.compile("|".join(f"(?P<{k}>{r})" for k, r in rules), flags)
    out: list[Token] = []
    line, start, pos = 1, 0, 0
    n = len(text)
    while pos < n:
        m = pattern.match(text, pos)
        if m is None or m.end() == pos:
            loc = Loc(path, line, pos - start + 1)
            raise error(loc, f"unexpected character {text[pos]!r}")
        kind = m.lastgroup or ""
        tok = m.group()
        if not kind.startswith("_"):
            out.append(Token(kind, tok, Loc(path, line, pos - start + 1)))
        breaks = tok.count("\n")
        if breaks:
            line += breaks
            start = pos + tok.rindex("\n") + 1
        pos = m.end()
    out.append(Token("eof", "", Loc(path, line, pos - start + 1)))
    return out


class Parser:
    """A cursor over tokens with the checks every reader needs (``language`` names the
    language in messages)."""

    def __init__(self, tokens: list[Token], language: str) -> None:
        self.toks = tokens
        self.i = 0
        self.language = language

    @property
    def tok(self) -> Token:
        return self.toks[self.i]

    def peek(self, k: int = 1) -> Token:
        return self.toks[min(self.i + k, len(self.toks) - 1)]

    def next(self) -> Token:
        t = self.toks[self.i]
        if t.kind != "eof":
            self.i += 1
        return t

    def at(self, *words: str) -> bool:
        """The current token is one of ``words`` (case-insensitive text)."""
        return self.tok.kind != "str" and self.tok.upper in {w.upper() for w in words}

    def accept(self, *words: str) -> Token | None:
        return self.next() if self.at(*words) else None

    def expect(self, word: str, what: str | None = None) -> Token:
        if not self.at(word):
            raise self.fail(f"expected {what or repr(word)}")
        return self.next()

    def expect_kind(self, kind: str, what: str) -> Token:
        if self.tok.kind != kind:
            raise self.fail(f"expected {what}")
        return self.next()

    def skip_nl(self) -> None:
        while self.tok.kind == "nl":
            self.next()

    def end_line(self) -> None:
        """The statement ends here: a line end (or the file's end)."""
        if self.tok.kind not in ("nl", "eof"):
            raise self.fail("expected the end of the line")
        self.skip_nl()

    def fail(self, message: str, tok: Token | None = None) -> ProgramError:
        t = tok or self.tok
        got = (
            "the end of the file"
            if t.kind == "eof"
            else ("the end of the line" if t.kind == "nl" else repr(t.text))
        )
        return error(t.loc, f"{message}, got {got}")

    def unsupported(self, what: str, tok: Token | None = None) -> ProgramError:
        t = tok or self.tok
        return error(t.loc, f"{what} is not supported by workcell's {self.language} reader")
