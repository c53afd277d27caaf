"""Small input checks shared by the modules that validate user values."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["is_finite_number", "quote_angle", "quote_length"]


def is_finite_number(x: object) -> bool:
    """True for a finite int or float (numpy scalars too), False for bools and the rest."""
    return (
        isinstance(x, (int, float, np.integer, np.floating))
        and not isinstance(x, (bool, np.bool_))
        and math.isfinite(float(x))
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
