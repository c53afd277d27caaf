"""Tokens of the command language, with their columns, and the units numbers may carry.

A script's lines end at ``\n`` only (:func:`split_lines`; a ``\r`` before it is dropped).
A control character, a Unicode line or paragraph separator or a bidirectional-text
control anywhere else on a line is refused with its column: each could make a line look
different from what runs (a command hidden behind a comment, text drawn over text).

A line is split at blanks; ``,`` ``(`` ``)`` ``[`` ``]`` also separate (so ``(0, 0, -90)``
reads as three numbers), ``;`` ends a command (several on one line), ``#`` starts a
comment and ``"..."`` quotes a string (a file name with blanks; ``\\"`` inside). A chunk
that reads as a number, optionally with a unit glued on (``90deg``, ``100mm``,
``0.3rad/s``), is a number; anything else is a word.

Units (people's defaults: degrees and metres): angle ``deg`` (default), ``rad``;
length ``m`` (default), ``mm``, ``cm``; time ``s`` (default), ``ms``; angular speed
``deg/s`` (default), ``rad/s``; angular acceleration ``deg/s^2`` (default), ``rad/s^2``;
tool speed ``m/s`` (default), ``mm/s``; tool acceleration ``m/s^2`` (default),
``mm/s^2``; a fraction ``%`` (default: a number is a percentage).
"""

from __future__ import annotations

import math
import re
import unicodedata
from dataclasses import dataclass

from workcell import limits
from workcell.errors import ProgramError

__all__ = [
    "CANONICAL",
    "DEFAULT_UNIT",
    "UNITS",
    "Token",
    "split_commands",
    "split_lines",
    "tokenize",
    "unit_factor",
]

# quantity -> unit -> factor to SI
UNITS: dict[str, dict[str, float]] = {
    "angle": {
        "deg": math.pi / 180,
        "degree": math.pi / 180,
        "degrees": math.pi / 180,
        "°": math.pi / 180,
        "rad": 1.0,
        "radian": 1.0,
        "radians": 1.0,
    },
    "length": {"m": 1.0, "mm": 1e-3, "cm": 1e-2},
    "time": {"s": 1.0, "ms": 1e-3},
    "speed": {"deg/s": math.pi / 180, "rad/s": 1.0},
    "angular_acceleration": {
        "deg/s^2": math.pi / 180,
        "deg/s2": math.pi / 180,
        "rad/s^2": 1.0,
        "rad/s2": 1.0,
    },
    "tool_speed": {"m/s": 1.0, "mm/s": 1e-3, "cm/s": 1e-2},
    "tool_acceleration": {"m/s^2": 1.0, "m/s2": 1.0, "mm/s^2": 1e-3, "mm/s2": 1e-3},
    "fraction": {"%": 0.01, "percent": 0.01},
}
DEFAULT_UNIT = {
    "angle": "deg",
    "length": "m",
    "time": "s",
    "speed": "deg/s",
    "angular_acceleration": "deg/s^2",
    "tool_speed": "m/s",
    "tool_acceleration": "m/s^2",
    "fraction": "%",
}
# the spellings named in messages (the others are accepted too)
CANONICAL = {
    "angle": ("deg", "rad"),
    "length": ("m", "mm", "cm"),
    "time": ("s", "ms"),
    "speed": ("deg/s", "rad/s"),
    "angular_acceleration": ("deg/s^2", "rad/s^2"),
    "tool_speed": ("m/s", "mm/s"),
    "tool_acceleration": ("m/s^2", "mm/s^2"),
    "fraction": ("%",),
}
ALL_UNITS = {u for table in UNITS.values() for u in table}
_NUMBER = re.compile(
    r"([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)((?:[A-Za-z°/%][A-Za-z°/%^2]*)?)$"
)
_SEPARATORS = " \t\r\n\f\v,()[]"
# C0 controls but tab and newline, DEL, C1 controls, line/paragraph separators, bidi controls
_HIDING = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]")


@dataclass(frozen=True)
class Token:
    """One token: ``kind`` "word", "number" or "string"; ``col`` 1-based column of its start.

    A number has ``value`` and ``unit`` (the glued unit, "" when none); a string its
    unquoted ``content`` (a word: its text).
    """

    kind: str
    text: str
    col: int
    value: float = 0.0
    unit: str = ""
    content: str = ""

    @property
    def end(self) -> int:
        """Column just after the token."""
        return self.col + len(self.text)


def _chunk(text: str, col: int) -> Token:
    m = _NUMBER.match(text)
    if m is not None:
        value = float(m.group(1))
        if math.isfinite(value):
            return Token("number", text, col, value, m.group(2))
    return Token("word", text, col, content=text)


def split_lines(text: str) -> list[str]:
    """The lines of a script: split at ``\n`` only, one ``\r`` before it dropped (never at
    the other characters ``str.splitlines`` splits at: U+2028, U+0085, form feed ...)."""
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return [ln[:-1] if ln.endswith("\r") else ln for ln in lines]


def _check_characters(line: str) -> None:
    m = _HIDING.search(line.rstrip("\n"))
    if m is not None:
        ch = m.group()
        what = unicodedata.name(ch, "a control character")
        raise ProgramError(
            f"column {m.start() + 1}: character U+{ord(ch):04X} ({what}) is not allowed: it "
            "can hide what a line does (lines end only at a newline)"
        )


def split_commands(line: str) -> list[list[Token]]:
    """Tokens of each command on ``line`` (commands separated by ';'; empty ones dropped).

    Raises ProgramError (with the column) for an unterminated string or a character
    that could hide what the line does (see the module doc).
    """
    limits.check("max_line_chars", len(line), "a command line")  # before any parsing
    _check_characters(line)
    commands: list[list[Token]] = [[]]
    i, n = 0, len(line)
    while i < n:
        ch = line[i]
        if ch in _SEPARATORS:
            i += 1
        elif ch == "#":
            break
        elif ch == ";":
            commands.append([])
            i += 1
        elif ch == '"':
            j, buf = i + 1, []
            while j < n and line[j] != '"':
                if line[j] == "\\" and j + 1 < n and line[j + 1] in '"\\':
                    j += 1
                buf.append(line[j])
                j += 1
            if j >= n:
                raise ProgramError(
                    f"column {i + 1}: string not closed: add a '\"' at the end\n"
                    f"  {line}\n  {' ' * i}^"
                )
            commands[-1].append(Token("string", line[i : j + 1], i + 1, content="".join(buf)))
            i = j + 1
        else:
            j = i
            while j < n and line[j] not in _SEPARATORS and line[j] not in ';#"':
                j += 1
            commands[-1].append(_chunk(line[i:j], i + 1))
            i = j
    return [c for c in commands if c]


def tokenize(line: str) -> list[Token]:
    """All tokens of ``line`` (';' separators dropped)."""
    return [t for c in split_commands(line) for t in c]


def unit_factor(quantity: str, unit: str) -> float | None:
    """The factor to SI of ``unit`` for ``quantity`` (None when it is no such unit)."""
    return UNITS.get(quantity, {}).get(unit)
