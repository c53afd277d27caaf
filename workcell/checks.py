"""Small input checks shared by the modules that validate user values."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["is_finite_number"]


def is_finite_number(x: object) -> bool:
    """True for a finite int or float (numpy scalars too), False for bools and the rest."""
    return (
        isinstance(x, (int, float, np.integer, np.floating))
        and not isinstance(x, (bool, np.bool_))
        and math.isfinite(float(x))
    )
