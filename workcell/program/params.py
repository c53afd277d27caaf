"""Parameter nodes of the key tree: names, entity references, file names, keyword
choices, and numbers and vectors with units (converted to SI: rad, m, s, rad/s).

Numbers take their unit glued on (``90deg``) or as the next word (``90 deg``); a unit
word after a vector applies to the numbers without their own. Defaults are for people:
degrees, metres, seconds, degrees per second.
"""

from __future__ import annotations

from typing import Any

from workcell.program.args import MAX_COUNT
from workcell.program.keytree import Cursor, Node, find_keyword
from workcell.program.lexer import ALL_UNITS, CANONICAL, DEFAULT_UNIT, UNITS, Token

__all__ = ["LEVEL_WORDS", "MAX_COUNT", "Choice", "Name", "Number", "Ref", "Text", "Vector"]

LEVEL_WORDS = ("surface", "block", "object", "scene")


def _text_token(cur: Cursor, what: str) -> Token:
    tok = cur.peek()
    if tok is None:
        cur.fail(f"incomplete command: {what} missing", [f"<{what}>"])
    if tok.kind == "number":
        cur.fail(f"expected {what}, got the number {tok.text}", [f"<{what}>"])
    return tok


class Name(Node):
    """A name; with ``kind`` (a :meth:`Session.names` kind) and a context, a known one,
    unless ``new`` (a name being created)."""

    def __init__(
        self, key: str, kind: str | None = None, new: bool = False, what: str = ""
    ) -> None:
        self.key, self.kind, self.new = key, kind, new
        self.what = what or (f"new {kind} name" if new else (kind or "name"))

    def expects(self, cur: Cursor) -> list[str]:
        known = None if self.new or self.kind is None else cur.names(self.kind)
        return known if known else [f"<{self.what}>"]

    def match(self, cur: Cursor) -> None:
        if cur.peek() is None and cur.completing:
            cur.fail("", self.expects(cur))
        tok = _text_token(cur, self.what)
        known = None if self.new or self.kind is None else cur.names(self.kind)
        if known is not None and tok.content not in known:
            cur.fail(f"unknown {self.what} '{tok.content}'", known or [self._none(cur)])
        cur.values[self.key] = cur.take().content

    def _none(self, cur: Cursor) -> str:
        """What "valid here" says when no name is known: why there is none."""
        kind, _, key = (self.kind or "").partition(":")
        owner = cur.values.get(key) if key else None
        if kind == "pose" and owner:
            return f"none (robot '{owner}' has no named poses)"
        if kind == "relation" and owner:
            return f"none ('{owner}' has no relations)"
        return f"none (no {kind} yet)"


class Ref(Node):
    """An entity: ``[LEVEL] NAME`` (the level keyword when the name is used at several)."""

    def __init__(self, key: str, kind: str = "entity", what: str = "") -> None:
        self.key, self.kind, self.what = key, kind, what or kind

    def expects(self, cur: Cursor) -> list[str]:
        return [*LEVEL_WORDS, *(cur.names(self.kind) or [f"<{self.what}>"])]

    def match(self, cur: Cursor) -> None:
        tok, nxt = cur.peek(), cur.peek(1)
        if tok is None and cur.completing:
            cur.fail("", self.expects(cur))
        level = None
        if (
            tok is not None
            and tok.kind == "word"
            and tok.text in LEVEL_WORDS
            and (nxt is not None or cur.completing)
        ):
            level = cur.take().text
        kind = level or self.kind
        if cur.peek() is None and cur.completing:
            cur.fail("", cur.names(kind) or [f"<{level or self.what} name>"])
        tok = _text_token(cur, f"{level or self.what} name")
        known = cur.names(kind)
        if known is not None and tok.content not in known:
            cur.fail(f"unknown {level or self.what} '{tok.content}'", known or ["none yet"])
        name = cur.take().content
        cur.values[self.key] = (level, name) if level else name


class Text(Node):
    """A word or a quoted string (a file name)."""

    def __init__(self, key: str, what: str = "file") -> None:
        self.key, self.what = key, what

    def expects(self, cur: Cursor) -> list[str]:
        return [f"<{self.what}>"]

    def match(self, cur: Cursor) -> None:
        if cur.peek() is None and cur.completing:
            cur.fail("", self.expects(cur))
        tok = cur.peek()
        if tok is None:
            cur.fail(f"incomplete command: {self.what} missing", self.expects(cur))
        cur.values[self.key] = cur.take().content if tok.kind != "number" else tok.text


class Choice(Node):
    """One word of ``options`` (word -> value; prefixes accepted)."""

    def __init__(self, key: str, options: dict[str, Any]) -> None:
        self.key, self.options = key, options

    def expects(self, cur: Cursor) -> list[str]:
        return list(self.options)

    def match(self, cur: Cursor) -> None:
        tok = cur.peek()
        if tok is None:
            cur.fail("incomplete command", self.expects(cur))
        try:
            key = find_keyword(tok.text, list(self.options)) if tok.kind == "word" else None
        except ValueError as exc:
            cur.fail(f"'{tok.text}' is ambiguous", exc.args[0])
        if key is None:
            cur.fail(f"unexpected '{tok.text}'", self.expects(cur))
        cur.take()
        cur.values[self.key] = self.options[key]


def _unit_of(cur: Cursor, tok: Token, quantity: str | None, at: int) -> float:
    """Factor to SI for the number ``tok`` (token ``at``): its glued unit, or the default."""
    if not tok.unit:
        return 1.0 if quantity is None else UNITS[quantity][DEFAULT_UNIT[quantity]]
    if quantity is None:
        cur.fail(f"'{tok.text}': this number takes no unit", [tok.text[: -len(tok.unit)]], at)
    f = UNITS[quantity].get(tok.unit)
    if f is None:
        cur.fail(f"unit '{tok.unit}' is not a unit of {quantity}", list(CANONICAL[quantity]), at)
    return f


def _trailing_unit(cur: Cursor, quantities: list[str | None]) -> dict[str, float] | None:
    """A separate unit word after numbers: its factor per quantity, or None when absent."""
    tok = cur.peek()
    if tok is None or tok.kind != "word" or tok.text not in ALL_UNITS:
        return None
    wanted = {q for q in quantities if q is not None}
    factors = {q: UNITS[q][tok.text] for q in wanted if tok.text in UNITS[q]}
    if not factors:
        valid = sorted({u for q in wanted for u in CANONICAL[q]}) or ["no unit"]
        cur.fail(f"unit '{tok.text}' does not fit here", valid)
    cur.take()
    return factors


class Number(Node):
    """A number of ``quantity`` (angle, length, time, speed; None: plain) in SI, with its
    unit glued on or following (defaults: deg, m, s, deg/s); ``integer``: a whole number
    in 0 .. MAX_COUNT (a count of facets, slices, sides)."""

    def __init__(
        self, key: str, quantity: str | None = None, integer: bool = False, what: str = ""
    ) -> None:
        self.key, self.quantity, self.integer = key, quantity, integer
        self.what = what or (quantity or ("whole number" if integer else "number"))

    def expects(self, cur: Cursor) -> list[str]:
        return [f"<{self.what}>"]

    def match(self, cur: Cursor) -> None:
        tok = cur.peek()
        if tok is None or tok.kind != "number":
            got = "incomplete command" if tok is None else f"expected a number, got '{tok.text}'"
            cur.fail(got, cur.also + self.expects(cur) if tok is None else self.expects(cur))
        if self.integer:
            if tok.unit or not 0 <= tok.value <= MAX_COUNT or tok.value != int(tok.value):
                cur.fail(
                    f"'{tok.text}' is not a whole number in 0 .. {MAX_COUNT}", self.expects(cur)
                )
            cur.take()
            cur.values[self.key] = int(tok.value)
            return
        f = _unit_of(cur, tok, self.quantity, cur.i)
        cur.take()
        if not tok.unit:
            f = (_trailing_unit(cur, [self.quantity]) or {}).get(self.quantity, f)  # type: ignore[arg-type]
        cur.values[self.key] = tok.value * f


class Vector(Node):
    """``n`` numbers (None: one or more) of ``quantity`` in SI; a unit word after them
    applies to those without their own. Quantity "joints": per joint of the robot named by
    value ``robot_key``, angle (revolute) or length (prismatic)."""

    def __init__(
        self, key: str, n: int | None, quantity: str | None, robot_key: str = "", what: str = ""
    ) -> None:
        self.key, self.n, self.quantity, self.robot_key = key, n, quantity, robot_key
        self.what = what or f"{n or 'some'} numbers"

    def expects(self, cur: Cursor) -> list[str]:
        return [f"<{self.what}>"]

    def _quantities(self, cur: Cursor, k: int) -> list[str | None]:
        if self.quantity != "joints":
            return [self.quantity] * k
        kinds = None
        if cur.ctx is not None and self.robot_key in cur.values:
            kinds = cur.ctx.joint_kinds(cur.values[self.robot_key])
        if kinds is None or len(kinds) != k:
            kinds = [True] * k  # unknown robot or wrong count: angles (the simulator checks)
        return ["angle" if r else "length" for r in kinds]

    def match(self, cur: Cursor) -> None:
        first = cur.i
        toks: list[Token] = []
        while (self.n is None or len(toks) < self.n) and (t := cur.peek()) is not None:
            if t.kind != "number":
                break
            toks.append(cur.take())
        if not toks or (self.n is not None and len(toks) < self.n):
            tok = cur.peek()
            got = "incomplete command" if tok is None else f"unexpected '{tok.text}'"
            cur.fail(f"{got}: expected {self.what}, got {len(toks)}", self.expects(cur))
        qs = self._quantities(cur, len(toks))
        own = [
            _unit_of(cur, t, q, first + k) if t.unit else None
            for k, (t, q) in enumerate(zip(toks, qs, strict=True))
        ]
        trailing = _trailing_unit(cur, qs) if any(f is None for f in own) else None
        out = []
        for t, q, f in zip(toks, qs, own, strict=True):
            if f is None:
                f = 1.0 if q is None else UNITS[q][DEFAULT_UNIT[q]]
                if trailing is not None and q in trailing:
                    f = trailing[q]
            out.append(t.value * f)
        cur.values[self.key] = tuple(out)
        if self.n is None and trailing is None:  # more numbers, or their unit, may follow
            units = [u for q in dict.fromkeys(qs) if q is not None for u in CANONICAL[q]]
            cur.also = ["<number>", *units]
