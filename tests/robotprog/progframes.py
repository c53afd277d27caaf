"""Rotation formulas written out for the robot-program tests (independent of the code)."""

from __future__ import annotations

import math

import numpy as np


def Rx(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def Ry(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def Rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rodrigues(v: np.ndarray) -> np.ndarray:
    """R = I + sin(t) K + (1 - cos(t)) K^2, K the cross matrix of the unit axis."""
    t = float(np.linalg.norm(v))
    if t == 0:
        return np.eye(3)
    k = v / t
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(t) * K + (1 - math.cos(t)) * K @ K


def quat_matrix(w: float, x: float, y: float, z: float) -> np.ndarray:
    """The textbook rotation matrix of a unit quaternion (Hamilton, w first)."""
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def kuka_frame(x: float, y: float, z: float, a: float, b: float, c: float) -> np.ndarray:
    """A KUKA frame (mm, deg; A, B, C about Z, Y', X'') as a 4x4 in m."""
    T = np.eye(4)
    T[:3, :3] = Rz(math.radians(a)) @ Ry(math.radians(b)) @ Rx(math.radians(c))
    T[:3, 3] = np.array([x, y, z]) / 1000.0
    return T
