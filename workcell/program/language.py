"""The command language: parse a line into commands, complete a partial line, explain.

:func:`parse_line` splits a line into commands (``;`` separates them, ``#`` starts a
comment) and matches each against the key tree (:data:`TREE`: the datamodel and solids
of :mod:`~workcell.program.grammar_model`, the cell and simulation of
:mod:`~workcell.program.grammar_sim`, and ``help``, ``quit``/``exit``, ``clear``).
Keywords may be shortened to any unambiguous prefix (``mo j a`` is ``move joints absolute``); the Simulator's own
method names (``move_joints_absolute`` ...) are accepted too. Values are for people:
angles in degrees and lengths in metres unless a unit says otherwise.

The whole line's syntax is checked before its first command is returned. With a context
(a :class:`~workcell.program.session.Session`), each command's names are checked when
that command is taken from :func:`parse_line`'s iterator, i.e. after the commands before
it on the line have run (``create cube c1; properties c1`` works), so an unknown robot or
entity is reported at its column with the known names; without a context, the commands
check them when they run.
"""

from __future__ import annotations

import textwrap
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from workcell.errors import ProgramError
from workcell.program.base import Command
from workcell.program.grammar_model import BRANCHES as MODEL_BRANCHES
from workcell.program.grammar_sim import ALIASES
from workcell.program.grammar_sim import BRANCHES as SIM_BRANCHES
from workcell.program.keytree import (
    CommandSyntaxError,
    Cursor,
    Keys,
    Leaf,
    Node,
    Seq,
    continuations,
    find_keyword,
    leaves,
    match,
)
from workcell.program.lexer import Token, split_commands, tokenize

__all__ = [
    "TREE",
    "UNITS_NOTE",
    "CommandSyntaxError",
    "Meta",
    "complete",
    "help_text",
    "parse_line",
]

UNITS_NOTE = (
    "Units: angles in degrees and lengths in metres unless you say otherwise: write a unit\n"
    "after a number (90 deg, 1.57 rad, 100 mm, 0.1 m, 0.3 rad/s, 20 ms) or glued to it\n"
    "(90deg, 100mm); a unit after a list of numbers applies to all of them. Speeds are\n"
    "deg/s (a tool's m/s: 250 mm/s), accelerations deg/s^2 (a tool's m/s^2), times\n"
    "seconds, overrides %. Keywords may be shortened to any unambiguous prefix."
)


@dataclass(frozen=True)
class Meta:
    """A front-end command that is no part of the vocabulary: ``help``, ``quit`` (also
    ``exit``) or ``clear``."""

    kind: str
    topic: tuple[str, ...] = ()


class _Rest(Node):
    """Every remaining token, as words (the topic of ``help``)."""

    def expects(self, cur: Cursor) -> list[str]:
        return list(TREE.visible())

    def match(self, cur: Cursor) -> None:
        if cur.completing and cur.peek() is None:
            cur.fail("", self.expects(cur) if not cur.values.get("topic") else [])
        words = []
        while cur.peek() is not None:
            words.append(cur.take().text)
        cur.values["topic"] = tuple(words)


_META: dict[str, Node] = {
    "help": Seq(
        _Rest(),
        Leaf(
            lambda v: Meta("help", v["topic"]),
            "help [COMMAND WORDS]",
            "list the commands, or explain the ones starting with these words",
            "help move joints",
        ),
    ),
    "quit": Leaf(lambda v: Meta("quit"), "quit", "leave the shell", "quit"),
    "exit": Leaf(lambda v: Meta("quit"), "exit", "leave the shell (same as quit)", "exit"),
    "clear": Leaf(lambda v: Meta("clear"), "clear", "clear the screen (on a terminal)", "clear"),
}

TREE = Keys({**MODEL_BRANCHES, **SIM_BRANCHES, **_META, **ALIASES}, hidden=tuple(ALIASES))


def parse_line(line: str, ctx: Any = None) -> Iterator[Command | Meta]:
    """The commands on one line, in order (none for a blank or comment line).

    The whole line is checked first, without names: a syntax error anywhere on it raises
    here, before any command is returned. With ``ctx`` (a Session) each command is then
    matched again against the context when it is taken from the iterator, so names made
    by the commands before it on the line (once they have run) are known::

        for command in parse_line("create cube c1 size 40 mm; properties c1", session):
            session.execute(command)

    Raises CommandSyntaxError (a ProgramError) with the column of the offending token and
    the words valid there; or ProgramError when values do not fit together (e.g. a
    matrix and SRT factors at once); a command's own argument checks raise ProgramError.
    """
    commands = split_commands(line)
    built = [_build(tokens, line, None) for tokens in commands]
    if ctx is None:
        return iter(built)
    return (_build(tokens, line, ctx) for tokens in commands)


def _build(tokens: list[Token], line: str, ctx: Any) -> Command | Meta:
    try:
        m = match(TREE, tokens, ctx)
    except CommandSyntaxError as exc:
        exc.line = line
        exc.args = (exc._text(),)
        raise
    return m.leaf.build(m.values)


def complete(text: str, ctx: Any = None) -> tuple[list[str], int]:
    """Completions at the end of ``text`` and the length of the word they replace.

    Offers keywords and known names (placeholders such as <number> are not offered).
    """
    try:
        commands = split_commands(text)
    except ProgramError:  # an open string: nothing to complete
        return [], 0
    ended = (text and text[-1] == ";") or not commands
    tokens = [] if ended else commands[-1]
    partial = ""
    if tokens and text and text[-1] not in " \t,()[]":
        partial = tokens[-1].text
        tokens = tokens[:-1]
    words = continuations(TREE, tokens, ctx)
    hits = [w for w in words if not w.startswith("<") and " " not in w and w.startswith(partial)]
    if not hits:
        low = partial.lower()
        hits = [w for w in words if not w.startswith("<") and w.lower().startswith(low)]
    return hits, len(partial)


def help_text(topic: tuple[str, ...] | list[str] = ()) -> str:
    """``help``: every command's syntax and summary, or the commands starting with ``topic``."""
    rows = [(path, leaf) for path, leaf in leaves(TREE) if leaf.syntax]
    if topic:
        chosen = []
        for path, leaf in rows:
            ok = len(topic) <= len(path)
            for word, key in zip(topic, path, strict=False):
                try:
                    ok = ok and find_keyword(word, [key]) == key
                except ValueError:
                    ok = False
            if ok and all(leaf is not other for _, other in chosen):
                chosen.append((path, leaf))
        if not chosen:
            top = ", ".join(TREE.visible())
            return f"no command starts with '{' '.join(topic)}'; commands: {top}"
        return "\n\n".join(_explain(leaf) for _, leaf in chosen) + "\n\n" + UNITS_NOTE
    width = max(len(leaf.syntax.split(" | ")[0]) for _, leaf in rows)
    width = min(width, 44)
    lines = ["Commands (help WORDS for one command, with an example):", ""]
    seen = set()
    for _path, leaf in rows:
        if id(leaf) in seen:
            continue
        seen.add(id(leaf))
        syntax = leaf.syntax if len(leaf.syntax) <= width else leaf.syntax[: width - 3] + "..."
        lines.append(f"  {syntax:{width}s}  {leaf.summary}")
    return "\n".join([*lines, "", UNITS_NOTE])


def _explain(leaf: Leaf) -> str:
    summary = textwrap.fill(leaf.summary, 88, initial_indent="    ", subsequent_indent="    ")
    return f"{leaf.syntax}\n{summary}\n    example: {leaf.example}"


def tokens_of(text: str) -> list[str]:
    """The token texts of ``text`` (for tests and tools)."""
    return [t.text for t in tokenize(text)]
