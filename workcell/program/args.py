"""Argument converters of the command vocabulary: plain (JSON) values in, checked values out.

Every command field declares one converter (:func:`arg`). A converter takes the value a
front end handed in (a Python value or decoded JSON) and the field's description, and
returns the value the command keeps (floats, tuples, nested tuples: frozen and hashable),
or raises :class:`~workcell.errors.ProgramError` saying what was wrong and what is valid.
Units are SI throughout: metres, radians, seconds.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import field
from typing import Any

import numpy as np

from workcell.checks import is_finite_number
from workcell.checks import shown as _show
from workcell.errors import ProgramError

__all__ = [
    "LEVELS",
    "MAX_COUNT",
    "Converter",
    "arg",
    "boolean",
    "choice",
    "colour",
    "count",
    "file_name",
    "label",
    "list_of",
    "matrix",
    "name",
    "number",
    "optional",
    "points",
    "ref",
    "sized",
    "text",
    "vector",
]

Converter = Callable[[Any, str], Any]
LEVELS = ("surface", "block", "object", "scene")
MAX_COUNT = 10_000  # the largest count of facets, slices, sides a command takes
_MISSING: Any = object()


def arg(convert: Converter, default: Any = _MISSING, doc: str = "") -> Any:
    """A command field converted by ``convert``; without ``default`` the field is required."""
    meta = {"convert": convert, "doc": doc}
    if default is _MISSING:
        return field(metadata=meta)
    return field(default=default, metadata=meta)


def _is_number(v: object) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(
        v, (bool, np.bool_)
    )


def text(v: object, what: str) -> str:
    """Any string (a file path, a free text)."""
    if not isinstance(v, str):
        raise ProgramError(f"{what} must be a string, got {_show(v)}")
    return v


def file_name(v: object, what: str) -> str:
    """A file name: a non-empty string without NUL or a lone surrogate (which no file
    system can store), at most 4096 characters (the session resolves it; a server keeps
    it inside its root folder)."""
    if not isinstance(v, str) or not v.strip() or "\x00" in v or len(v) > 4096:
        raise ProgramError(f"{what} must be a file name (a non-empty string), got {_show(v)}")
    try:
        os.fsencode(v)
    except UnicodeEncodeError:
        raise ProgramError(
            f"{what} must be a file name of valid text (no lone surrogate such as '\\ud800'), "
            f"got {_show(v)}"
        ) from None
    return v


def name(v: object, what: str) -> str:
    """A non-empty string naming something (the owner checks the characters)."""
    if not isinstance(v, str) or not v:
        raise ProgramError(f"{what} must be a non-empty name (a string), got {_show(v)}")
    return v


def ref(v: object, what: str) -> str | tuple[str, str]:
    """An entity reference: a name, or ``[level, name]`` with a level of the datamodel."""
    if isinstance(v, str) and v:
        return v
    if (
        isinstance(v, (list, tuple))
        and len(v) == 2
        and v[0] in LEVELS
        and isinstance(v[1], str)
        and v[1]
    ):
        return (v[0], v[1])
    raise ProgramError(
        f"{what} must be a name or [level, name] with a level in {', '.join(LEVELS)}, "
        f"got {_show(v)}"
    )


def number(v: object, what: str) -> float:
    """A finite number (int or float; not a bool)."""
    if not is_finite_number(v):
        raise ProgramError(f"{what} must be a finite number, got {_show(v)}")
    return float(v)  # type: ignore[arg-type]


def count(v: object, what: str) -> int:
    """A whole number in 0 .. 10000 (an integral float such as 3.0 is accepted)."""
    if (
        is_finite_number(v)
        and float(v) == int(v)  # type: ignore[arg-type]
        and 0 <= int(v) <= MAX_COUNT  # type: ignore[arg-type]
    ):
        return int(v)  # type: ignore[arg-type]
    raise ProgramError(f"{what} must be a whole number in 0 .. {MAX_COUNT}, got {_show(v)}")


def boolean(v: object, what: str) -> bool:
    """true or false."""
    if not isinstance(v, (bool, np.bool_)):
        raise ProgramError(f"{what} must be true or false, got {_show(v)}")
    return bool(v)


def vector(v: object, what: str, n: int | None = None) -> tuple[float, ...]:
    """A list of finite numbers (exactly ``n`` when given)."""
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if not isinstance(v, (list, tuple)) or not all(_is_number(x) for x in v):
        raise ProgramError(f"{what} must be a list of numbers, got {_show(v)}")
    if not all(is_finite_number(x) for x in v):  # nan, inf, an int too large for a float
        raise ProgramError(f"{what} must hold finite numbers, got {_show(v)}")
    out = tuple(float(x) for x in v)
    if n is not None and len(out) != n:
        raise ProgramError(f"{what} must be {n} numbers, got {len(out)}")
    return out


def colour(v: object, what: str) -> tuple[float, ...]:
    """An RGB or RGBA colour: 3 or 4 numbers in [0, 1]."""
    c = vector(v, what)
    if len(c) not in (3, 4) or not all(0.0 <= x <= 1.0 for x in c):
        raise ProgramError(f"{what} must be 3 or 4 numbers in [0, 1] (RGB[A]), got {_show(v)}")
    return c


def matrix(v: object, what: str) -> tuple[tuple[float, ...], ...]:
    """A 4x4 homogeneous transform: 4 rows of 4 numbers (or 16 numbers, row by row)."""
    if isinstance(v, np.ndarray):
        v = v.tolist()
    rows: Sequence[Any]
    if isinstance(v, (list, tuple)) and len(v) == 16 and all(_is_number(x) for x in v):
        rows = [v[4 * i : 4 * i + 4] for i in range(4)]
    elif isinstance(v, (list, tuple)) and len(v) == 4:
        rows = v
    else:
        raise ProgramError(f"{what} must be a 4x4 matrix (4 rows of 4 numbers), got {_show(v)}")
    return tuple(vector(r, f"{what} row {i + 1}", 4) for i, r in enumerate(rows))


def points(v: object, what: str) -> tuple[tuple[float, float], ...]:
    """A polygon: a list of at least 3 ``[x, y]`` points (m)."""
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if not isinstance(v, (list, tuple)) or len(v) < 3:
        raise ProgramError(f"{what} must be a list of at least 3 [x, y] points, got {_show(v)}")
    return tuple(vector(p, f"{what} point {i + 1}", 2) for i, p in enumerate(v))  # type: ignore[misc]


def optional(convert: Converter) -> Converter:
    """``convert``, or None (JSON null) for "not given"."""

    def conv(v: object, what: str) -> Any:
        return None if v is None else convert(v, what)

    conv.__doc__ = f"{convert.__doc__} Or null."
    conv.label = f"{label(convert)} | null"  # type: ignore[attr-defined]
    return conv


def choice(*options: str) -> Converter:
    """One of ``options`` (exact strings)."""

    def conv(v: object, what: str) -> str:
        if v not in options:
            raise ProgramError(f"{what} must be one of {', '.join(options)}; got {_show(v)}")
        return v  # type: ignore[return-value]

    conv.__doc__ = f"One of {', '.join(options)}."
    conv.label = " | ".join(f'"{o}"' for o in options)  # type: ignore[attr-defined]
    return conv


def sized(n: int) -> Converter:
    """A list of exactly ``n`` numbers."""

    def conv(v: object, what: str) -> tuple[float, ...]:
        return vector(v, what, n)

    conv.__doc__ = f"A list of {n} numbers."
    conv.label = f"number[{n}]"  # type: ignore[attr-defined]
    return conv


def list_of(convert: Converter) -> Converter:
    """A list of values each converted by ``convert``."""

    def conv(v: object, what: str) -> tuple[Any, ...]:
        if not isinstance(v, (list, tuple)):
            raise ProgramError(f"{what} must be a list, got {_show(v)}")
        return tuple(convert(x, f"{what} item {i + 1}") for i, x in enumerate(v))

    conv.__doc__ = f"A list; each item: {convert.__doc__}"
    conv.label = f"({label(convert)})[]"  # type: ignore[attr-defined]
    return conv


_LABELS = {
    "text": "string",
    "file_name": "file",
    "name": "name",
    "ref": "ref",
    "number": "number",
    "count": "integer",
    "boolean": "bool",
    "vector": "number[]",
    "colour": "colour",
    "matrix": "matrix4",
    "points": "points",
}


def label(convert: Converter) -> str:
    """A short name of the JSON type ``convert`` takes (for the protocol's ``commands``)."""
    return getattr(convert, "label", None) or _LABELS.get(getattr(convert, "__name__", ""), "any")
