"""The key tree matcher (thesis §2.2): match a command's tokens against a tree of keywords.

The tree is made of nodes: :class:`Keys` (a keyword picks a branch; any unambiguous
prefix of a keyword is accepted, case-insensitively), :class:`Seq`, :class:`Options`
(keyword-introduced parts in any order), :class:`Set`, the parameter nodes of
:mod:`workcell.program.params` (names, numbers with units, vectors, file names) and
:class:`Leaf` (the end of a command, which builds it from the collected values).

Matching never backtracks: at each token the valid continuations are known, so a
mismatch raises :class:`CommandSyntaxError` pointing at the token (its column) and
listing what is valid there, and the same walk in *completion* mode lists the
continuations at the end of a partial line. With a context (a
:class:`~workcell.program.session.Session`) names are checked against the known ones.
"""

from __future__ import annotations

import abc
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, NoReturn

from workcell.errors import ProgramError
from workcell.program.lexer import Token

__all__ = [
    "CommandSyntaxError",
    "Cursor",
    "Keys",
    "Leaf",
    "Match",
    "Node",
    "Options",
    "Seq",
    "Set",
    "continuations",
    "find_keyword",
    "leaves",
    "match",
]


class CommandSyntaxError(ProgramError):
    """A command that does not match the language: ``column`` (1-based) of the offending
    token (one past the end when the command is incomplete) and the ``expected`` words."""

    def __init__(self, message: str, column: int, expected: list[str], line: str = "") -> None:
        self.reason, self.column, self.expected, self.line = message, column, expected, line
        self.where = ""
        super().__init__(self._text())

    def _text(self) -> str:
        valid = f"; valid here: {', '.join(self.expected)}" if self.expected else ""
        text = f"{self.where}column {self.column}: {self.reason}{valid}"
        if self.line:
            shown, caret = _window(self.line, self.column - 1)
            text += f"\n  {shown}\n  {' ' * caret}^"
        return text

    def locate(self, where: str, line: str) -> CommandSyntaxError:
        """Say where the line came from (``"file.wcl:3: "``) and show it; returns self."""
        self.where, self.line = where, line
        self.args = (self._text(),)
        return self


def _window(line: str, at: int, width: int = 120) -> tuple[str, int]:
    """At most ``width`` characters of ``line`` around index ``at`` (cut ends shown as
    '...'), and where ``at`` falls in them: a long line is never echoed whole."""
    if len(line) <= width:
        return line, at
    start = max(0, min(at - width // 2, len(line) - width))
    head = "..." if start > 0 else ""
    tail = "..." if start + width < len(line) else ""
    return f"{head}{line[start : start + width]}{tail}", at - start + len(head)


class _Mismatch(Exception):  # noqa: N818 - control flow inside the matcher, never escapes
    def __init__(self, index: int, message: str, expected: list[str]) -> None:
        self.index, self.message, self.expected = index, message, expected


class Cursor:
    """Matching state: the tokens, the position, the values collected, the context."""

    def __init__(self, tokens: list[Token], ctx: Any = None, completing: bool = False) -> None:
        self.tokens, self.i, self.values, self.ctx = tokens, 0, {}, ctx
        self.completing = completing
        self.also: list[str] = []  # continuations passed over at this position
        self.leaf: Leaf | None = None

    def peek(self, k: int = 0) -> Token | None:
        j = self.i + k
        return self.tokens[j] if j < len(self.tokens) else None

    def take(self) -> Token:
        tok = self.tokens[self.i]
        self.i += 1
        self.also = []
        return tok

    def fail(self, message: str, expected: list[str], at: int | None = None) -> NoReturn:
        raise _Mismatch(self.i if at is None else at, message, expected)

    def names(self, kind: str) -> list[str] | None:
        """Known names of ``kind`` (None without a context: names are not checked).

        Kind ``relation:KEY``: the relations of the owner collected under value KEY;
        ``pose:KEY``: the named poses of the robot collected under KEY.
        """
        if self.ctx is None:
            return None
        if kind.startswith("relation:"):
            owner = self.values.get(kind.split(":", 1)[1])
            return None if owner is None else list(self.ctx.relation_names(owner))
        if kind.startswith("pose:"):
            robot = self.values.get(kind.split(":", 1)[1])
            return None if robot is None else self.ctx.pose_names(robot)
        return list(self.ctx.names(kind))


class Node(abc.ABC):
    """A node of the key tree."""

    @abc.abstractmethod
    def match(self, cur: Cursor) -> None:
        """Consume this node's tokens, store its values; raise _Mismatch on a mismatch."""

    @abc.abstractmethod
    def expects(self, cur: Cursor) -> list[str]:
        """What may come at this node's start (words, or <placeholders>)."""


def find_keyword(word: str, keys: list[str], hidden: tuple[str, ...] = ()) -> str | None:
    """The keyword ``word`` names: exact, or the one visible keyword it is a prefix of."""
    w = word.lower()
    if w in keys or w in hidden:
        return w
    hits = [k for k in keys if k.startswith(w)]
    if len(hits) > 1:
        raise ValueError(hits)
    return hits[0] if hits else None


class Keys(Node):
    """A keyword chooses the branch; ``other`` matches when the token is no keyword, and
    ``empty`` when the command ends here."""

    def __init__(
        self,
        branches: dict[str, Node],
        other: Node | None = None,
        hidden: tuple[str, ...] = (),
        empty: Node | None = None,
    ) -> None:
        self.branches, self.other, self.hidden, self.empty = branches, other, hidden, empty

    def visible(self) -> list[str]:
        return [k for k in self.branches if k not in self.hidden]

    def expects(self, cur: Cursor) -> list[str]:
        return self.visible() + (self.other.expects(cur) if self.other else [])

    def match(self, cur: Cursor) -> None:
        tok = cur.peek()
        if tok is None:
            if self.empty is not None and not cur.completing:
                self.empty.match(cur)
                return
            cur.fail("incomplete command", cur.also + self.expects(cur))
        key = None
        if tok.kind == "word":
            try:
                key = find_keyword(tok.text, self.visible(), self.hidden)
            except ValueError as exc:
                cur.fail(f"'{tok.text}' is ambiguous", exc.args[0])
        if key is None:
            if self.other is not None:
                cur.also = [*cur.also, *self.visible()]
                self.other.match(cur)
                return
            cur.fail(f"unexpected '{tok.text}'", cur.also + self.expects(cur))
        cur.take()
        self.branches[key].match(cur)


class Seq(Node):
    """Nodes one after another."""

    def __init__(self, *nodes: Node) -> None:
        self.nodes = nodes

    def expects(self, cur: Cursor) -> list[str]:
        return self.nodes[0].expects(cur) if self.nodes else []

    def match(self, cur: Cursor) -> None:
        for n in self.nodes:
            n.match(cur)


class Set(Node):
    """Store ``value`` under ``key`` without consuming a token."""

    def __init__(self, key: str, value: Any) -> None:
        self.key, self.value = key, value

    def expects(self, cur: Cursor) -> list[str]:
        return []

    def match(self, cur: Cursor) -> None:
        cur.values[self.key] = self.value


class Options(Node):
    """Keyword-introduced parts in any order, each at most once, all optional."""

    def __init__(self, branches: dict[str, Node]) -> None:
        self.branches = branches

    def expects(self, cur: Cursor) -> list[str]:
        return list(self.branches)

    def match(self, cur: Cursor) -> None:
        used: list[str] = []
        while True:
            unused = [k for k in self.branches if k not in used]
            tok = cur.peek()
            if tok is None and cur.completing:
                cur.fail("", unused)
            key = None
            if tok is not None and tok.kind == "word":
                try:
                    key = find_keyword(tok.text, list(self.branches))
                except ValueError as exc:
                    cur.fail(f"'{tok.text}' is ambiguous", exc.args[0])
            if key is None:
                cur.also = [*cur.also, *unused] if not used else unused
                return
            if key in used:
                cur.fail(f"'{key}' given twice", unused)
            used.append(key)
            cur.take()
            self.branches[key].match(cur)


class Leaf(Node):
    """The end of a command: ``build(values)`` makes it; ``syntax``, ``summary``,
    ``example`` document it (``help``)."""

    def __init__(
        self, build: Callable[[dict[str, Any]], Any], syntax: str, summary: str, example: str
    ) -> None:
        self.build, self.syntax, self.summary, self.example = build, syntax, summary, example

    def expects(self, cur: Cursor) -> list[str]:
        return ["end of command"]

    def match(self, cur: Cursor) -> None:
        tok = cur.peek()
        if cur.completing and tok is None:
            cur.fail("", cur.also)
        if tok is not None:
            cur.fail(f"unexpected '{tok.text}'", [*cur.also, "end of command"])
        cur.leaf = self


@dataclass(frozen=True)
class Match:
    """A matched command: its leaf and the values collected."""

    leaf: Leaf
    values: dict[str, Any]


def match(tree: Node, tokens: list[Token], ctx: Any = None) -> Match:
    """Match one command's tokens; CommandSyntaxError (column, expected) on a mismatch."""
    cur = Cursor(tokens, ctx)
    try:
        tree.match(cur)
    except _Mismatch as f:
        col = (
            tokens[f.index].col if f.index < len(tokens) else (tokens[-1].end + 1 if tokens else 1)
        )
        raise CommandSyntaxError(f.message, col, _unique(f.expected)) from None
    if cur.leaf is None:  # a tree whose branch does not end in a leaf: our bug
        raise RuntimeError("key tree branch without a leaf")
    return Match(cur.leaf, cur.values)


def continuations(tree: Node, tokens: list[Token], ctx: Any = None) -> list[str]:
    """What may follow ``tokens`` (words and <placeholders>); [] after a mismatch."""
    cur = Cursor(tokens, ctx, completing=True)
    try:
        tree.match(cur)
    except _Mismatch as f:
        return _unique(f.expected) if f.index >= len(tokens) else []
    return []


def _unique(items: list[str]) -> list[str]:
    return list(dict.fromkeys(i for i in items if i))


def leaves(node: Node, path: tuple[str, ...] = ()) -> Iterator[tuple[tuple[str, ...], Leaf]]:
    """Every leaf with the keywords leading to it (hidden keywords skipped)."""
    if isinstance(node, Leaf):
        yield path, node
    elif isinstance(node, Keys):
        if node.empty is not None:
            yield from leaves(node.empty, path)
        for k in node.visible():
            yield from leaves(node.branches[k], (*path, k))
        if node.other is not None:
            yield from leaves(node.other, path)
    elif isinstance(node, Seq):
        for n in node.nodes:
            if isinstance(n, (Keys, Seq, Leaf)):
                yield from leaves(n, path)
