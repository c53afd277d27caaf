"""KRL values: structures as dicts of upper-case fields, frames, and KUKA's system
variables as the KRL reader (:mod:`workcell.robotprog.read_krl`) runs them.

A KRL structure (FRAME, POS, E6POS, AXIS, E6AXIS, and KUKA's FDAT/PDAT/LDAT) is a dict;
an aggregate ``{X 1, Y 2}`` is a dict of the fields it names; assigning one to a declared
variable changes those fields only, and a motion to an aggregate takes the fields it
leaves out from where the robot is (as KUKA's controller does).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell.errors import ProgramError
from workcell.robotprog.exprs import number
from workcell.robotprog.rotations import (
    KUKA_FROM_OURS,
    from_kuka_frame,
    from_zyx,
    to_kuka_frame,
    zyx,
)

__all__ = [
    "FRAME_FIELDS",
    "STRUCT_TYPES",
    "frame_dict",
    "frame_matrix",
    "geometric",
    "joints_of",
    "tcp_of_tool",
    "tool_of_tcp",
]

Array = NDArray[np.float64]
FRAME_FIELDS = ("X", "Y", "Z", "A", "B", "C")
STRUCT_TYPES = {"FRAME", "POS", "E6POS", "AXIS", "E6AXIS", "FDAT", "PDAT", "LDAT", "LOAD"}
SIMPLE_TYPES = {"INT", "REAL", "BOOL", "CHAR"}


def frame_matrix(d: dict[str, Any], what: str = "a frame") -> Array:
    """The 4x4 of a KRL frame (X, Y, Z mm; A, B, C deg): translation in m."""
    missing = [k for k in FRAME_FIELDS if k not in d]
    if missing:
        raise ProgramError(f"{what} has no {', '.join(missing)}")
    T = from_zyx(*(number(d[k], f"{k} of {what}") for k in ("A", "B", "C")))
    T[:3, 3] = [number(d[k], f"{k} of {what}") / 1000.0 for k in ("X", "Y", "Z")]
    return T


def frame_dict(T: Array) -> dict[str, Any]:
    """The KRL frame (mm, deg) of a 4x4 (m)."""
    a, b, c = zyx(T)
    x, y, z = (1000.0 * float(v) for v in T[:3, 3])
    return {"X": x, "Y": y, "Z": z, "A": a, "B": b, "C": c}


def geometric(a: Any, b: Any) -> dict[str, Any]:
    """KRL's geometric operator ``a : b``: frame b expressed in frame a."""
    if not (isinstance(a, dict) and isinstance(b, dict)):
        raise ProgramError("the geometric operator ':' joins two frames (X, Y, Z, A, B, C)")
    out = frame_dict(frame_matrix(a, "the left frame") @ frame_matrix(b, "the right frame"))
    for k in ("S", "T"):
        if k in b:
            out[k] = b[k]
    return out


def joints_of(d: dict[str, Any], current: Array, what: str) -> Array:
    """Joint values (rad) of an AXIS/E6AXIS structure (deg), the ones it leaves out from
    ``current`` (rad)."""
    q = np.array(current, dtype=np.float64)
    for i in range(len(q)):
        k = f"A{i + 1}"
        if k in d:
            q[i] = math.radians(number(d[k], f"{k} of {what}"))
    return q


def tcp_of_tool(d: dict[str, Any]) -> Array:
    """The TCP (our convention, z out) of a KRL ``$TOOL`` frame (x out of the flange)."""
    return KUKA_FROM_OURS @ frame_matrix(d, "$TOOL") @ KUKA_FROM_OURS.T


def tool_of_tcp(T: Array) -> dict[str, Any]:
    """The KRL ``$TOOL`` frame of a TCP in our convention."""
    return frame_dict(KUKA_FROM_OURS.T @ T @ KUKA_FROM_OURS)


def program_pose(d: dict[str, Any], what: str) -> Array:
    """A KRL position (KUKA's tool convention) as our tool pose (z out)."""
    return from_kuka_frame(frame_matrix(d, what))


def pose_dict(T: Array) -> dict[str, Any]:
    """Our tool pose as a KRL position."""
    return frame_dict(to_kuka_frame(T))
