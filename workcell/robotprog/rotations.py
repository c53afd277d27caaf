"""The vendors' orientation conventions, both ways, and number formatting.

- KUKA A, B, C (deg): rotations about Z, then the new Y', then the newest X''
  (R = Rz(A) Ry(B) Rx(C)), of KUKA's tool frames, whose x axis points out of the tool
  (:func:`to_kuka_frame`: our tool frames have z out, KUKA's are ours turned by
  Ry(-90 deg): the ROS-Industrial ``flange`` link, not ``tool0``).
- FANUC W, P, R (deg): rotations about the fixed X, then Y, then Z axes (R = Rz(R) Ry(P)
  Rx(W), the same matrix as KUKA's A = R, B = P, C = W).
- ABB quaternions q1..q4 = w, x, y, z (w >= 0 written).
- Universal Robots rotation vectors rx, ry, rz (rad): axis x angle, angle in [0, pi].

At gimbal lock (|B| = 90 deg) the first angle takes the whole turn about z and the
third is 0. Every function works on 3x3 rotations or the rotation part of a 4x4.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.spatial import matrix_from_quat, quat_from_matrix, rot_y

__all__ = [
    "KUKA_FROM_OURS",
    "fmt",
    "from_kuka_frame",
    "from_rotvec",
    "from_zyx",
    "quat_wxyz",
    "rotvec",
    "to_kuka_frame",
    "zyx",
]

Array = NDArray[np.float64]
KUKA_FROM_OURS = rot_y(-math.pi / 2)  # our tool frame (z out) -> KUKA's (x out)
_LOCK = 1e-12  # |cos B| below which the decomposition is at gimbal lock


def zyx(T: ArrayLike) -> tuple[float, float, float]:
    """(A, B, C) in degrees with R = Rz(A) Ry(B) Rx(C); B in [-90, 90]."""
    R = np.asarray(T, dtype=np.float64)[:3, :3]
    sb = -float(R[2, 0])
    cb = math.hypot(float(R[0, 0]), float(R[1, 0]))
    b = math.atan2(sb, cb)
    if cb > _LOCK:
        a = math.atan2(float(R[1, 0]), float(R[0, 0]))
        c = math.atan2(float(R[2, 1]), float(R[2, 2]))
    else:  # B = +-90: only A -+ C is defined; put it all in A
        c = 0.0
        a = math.atan2(-float(R[0, 1]), float(R[1, 1]))
    return math.degrees(a), math.degrees(b), math.degrees(c)


def from_zyx(a: float, b: float, c: float) -> Array:
    """The 4x4 rotation Rz(a) Ry(b) Rx(c), angles in degrees."""
    ca, sa = math.cos(math.radians(a)), math.sin(math.radians(a))
    cb, sb = math.cos(math.radians(b)), math.sin(math.radians(b))
    cc, sc = math.cos(math.radians(c)), math.sin(math.radians(c))
    T = np.eye(4)
    T[:3, :3] = [
        [ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc],
        [sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc],
        [-sb, cb * sc, cb * cc],
    ]
    return T


def to_kuka_frame(T: ArrayLike) -> Array:
    """A tool pose in our convention (z out of the tool) as KUKA's (x out)."""
    return np.asarray(T, dtype=np.float64) @ KUKA_FROM_OURS


def from_kuka_frame(T: ArrayLike) -> Array:
    """A KUKA tool pose (x out of the tool) in our convention (z out)."""
    return np.asarray(T, dtype=np.float64) @ KUKA_FROM_OURS.T


def quat_wxyz(T: ArrayLike) -> Array:
    """The unit quaternion (w, x, y, z), w >= 0."""
    return quat_from_matrix(np.asarray(T, dtype=np.float64)[:3, :3])


def rotvec(T: ArrayLike) -> Array:
    """The rotation vector (rad): unit axis x angle, angle in [0, pi]."""
    w, x, y, z = quat_wxyz(T)
    s = math.sqrt(x * x + y * y + z * z)
    if s < 1e-300:
        return np.zeros(3)
    angle = 2.0 * math.atan2(s, w)
    return np.array([x, y, z]) * (angle / s)


def from_rotvec(v: ArrayLike) -> Array:
    """The 4x4 rotation of rotation vector ``v`` (rad)."""
    r = np.asarray(v, dtype=np.float64)
    angle = float(np.linalg.norm(r))
    if angle < 1e-300:
        return np.eye(4)
    axis = r / angle
    h = 0.5 * angle
    return matrix_from_quat(np.concatenate([[math.cos(h)], axis * math.sin(h)]))


def fmt(v: float, decimals: int) -> str:
    """``v`` with ``decimals`` decimals, without a negative zero."""
    s = f"{float(v):.{decimals}f}"
    return s[1:] if s.startswith("-") and float(s) == 0.0 else s
