"""Small input checks shared by the modules that validate user values."""

from __future__ import annotations

import math
import re

import numpy as np

from workcell.errors import DegenerateError, ModelError

__all__ = [
    "MIN_LENGTH",
    "check_size",
    "checked_name",
    "is_finite_number",
    "quote_angle",
    "quote_length",
    "shown",
]

MIN_LENGTH = 1e-6  # m: the smallest side, radius or length of a solid or shape


def is_finite_number(x: object) -> bool:
    """True for a finite int or float (numpy scalars too), False for bools and the rest
    (an integer too large for a float, 10**400, is not a finite number here)."""
    if not isinstance(x, (int, float, np.integer, np.floating)) or isinstance(x, (bool, np.bool_)):
        return False
    try:
        return math.isfinite(float(x))
    except OverflowError:
        return False


def check_size(what: str, key: str, v: float) -> None:
    """DegenerateError unless the length ``v`` (m, already a positive number) is at least
    :data:`MIN_LENGTH` = 1 micrometre. Below it a solid has (almost) no volume: convex
    hulls fail and the convex decomposition aborts (a cylinder of radius 1e-8 m, a box
    side of 1e-320 m), while sizes from 1 um up, with any other side up to 1e6 m, were
    checked to mesh, hull, decompose and compile in MuJoCo."""
    if v < MIN_LENGTH:
        raise DegenerateError(
            f"{what}: {key} {float(v):.3g} m is too small: a solid's sizes must be at least "
            f"{MIN_LENGTH:g} m (1 micrometre)"
        )


def quote_angle(rad: object, per: str = "") -> str:
    """An angle (rad; ``per="/s"`` for a speed) as people type it, with the SI value after:
    ``"600 deg/s (10.47 rad/s)"``. Error messages quote values this way, so the command
    language's users (degrees) and Python's (radians) both recognise what they gave."""
    if not is_finite_number(rad):
        return repr(rad)
    r = float(rad)
    return f"{math.degrees(r):.6g} deg{per} ({r:.4g} rad{per})"


def quote_length(m: object) -> str:
    """A length (m) in millimetres with the SI value after: ``"5 mm (0.005 m)"``."""
    if not is_finite_number(m):
        return repr(m)
    v = float(m)
    return f"{v * 1e3:.6g} mm ({v:.4g} m)"


def shown(v: object) -> str:
    """``repr(v)`` for an error message, cut to 60 characters (a value a user gave may
    be a megabyte long)."""
    try:
        s = repr(v)
    except ValueError:  # an integer of more than 4300 digits
        s = f"an integer of {v.bit_length() if isinstance(v, int) else '?'} bits"
    return s if len(s) <= 60 else s[:57] + "..."


def checked_name(name: object, pattern: re.Pattern[str], what: str, rule: str, most: int) -> str:
    """``name`` when it is a string matching ``pattern`` of at most ``most`` characters,
    else ModelError: "invalid {what} {name}: {rule}, at most {most} characters"."""
    if not isinstance(name, str) or len(name) > most or not pattern.fullmatch(name):
        raise ModelError(f"invalid {what} {shown(name)}: {rule}, at most {most} characters")
    return name
