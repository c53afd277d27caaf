"""Joint axis lines of a chain, and the geometric tests the closed-form families run on them.

A closed-form family (OPW, UR) is recognised from the robot's geometry, never from its
name: the joint axes at q = 0, as lines (a point and a unit direction) in frame 0 of the
chain (the robot's ``base`` transform left out), must be parallel, perpendicular or
meet as the family requires. Each family then reads its parameters off these lines and
trusts them only after :func:`verify_fk` has compared its own forward kinematics with the
robot's at random joint values. Lengths in m, angles in rad.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from workcell.errors import KinematicsError
from workcell.robots.robot import Robot
from workcell.spatial import invert

__all__ = [
    "GEOMETRY_TOL",
    "VERIFY_TOL",
    "AxisModel",
    "axis_lines",
    "base_frame",
    "fitted",
    "line_gap",
    "straight_value",
    "verify_fk",
]

Array = NDArray[np.float64]
GEOMETRY_TOL = 1e-9
"""m, and cosines: axes closer than this to parallel, perpendicular or meeting are so."""
VERIFY_TOL = 1e-9
"""m and rotation-matrix entries: a family's FK must match the robot's this closely."""
VERIFY_SAMPLES = 64  # random joint vectors compared (plus q = 0)


@dataclass(frozen=True, eq=False)
class AxisModel:
    """What every family model has: joint ``offsets`` (rad) and ``signs`` mapping joint
    values to the model's angles, ``q_i = sign_i (theta_i + offset_i)``; ``base`` (4x4)
    the model's base frame in frame 0 of the chain; ``end`` (4x4) the robot's tool frame
    in the model's end frame."""

    offsets: tuple[float, ...]
    signs: tuple[int, ...]
    base: Array
    end: Array

    def theta(self, Q: Array) -> Array:
        """The model's angles (..., 6) of joint values Q (rad): ``sign * q - offset``."""
        return np.asarray(Q) * np.array(self.signs) - np.array(self.offsets)


M = TypeVar("M", bound=AxisModel)


def fitted(robot: Robot, draft: M, fk: Callable[[M, Array], Array], where: str) -> M:
    """``draft`` (its ``end`` the identity) with the ``end`` that puts its end frame on
    the robot's tool frame at q = 0, trusted only when its FK then matches the robot's
    (:func:`verify_fk` within ``VERIFY_TOL``); KinematicsError saying by how much not."""
    zero = fk(draft, np.zeros((1, robot.dof)))[0]
    end = invert(zero) @ np.linalg.inv(robot.base) @ robot.fk(np.zeros(robot.dof))
    model = dataclasses.replace(draft, end=end)
    err = verify_fk(robot, lambda Q: fk(model, Q))
    if err > VERIFY_TOL:
        raise KinematicsError(
            f"{where}: the model read from its axes misses its FK by {err:.3g} (m or rotation "
            "entries) at random joint values"
        )
    return model


def axis_lines(robot: Robot, q: Array | None = None) -> tuple[Array, Array]:
    """Points (n, 3, m) and unit directions (n, 3) of the joint axes at q (default 0),
    in frame 0 of the chain (``robot.base`` left out)."""
    q = np.zeros(robot.dof) if q is None else np.asarray(q, dtype=np.float64)
    A = robot._joint_matrices(q[None])[0]
    F = np.eye(4)
    P, U = np.empty((robot.dof, 3)), np.empty((robot.dof, 3))
    for i, j in enumerate(robot.joints):
        F = F @ A[i]
        U[i] = F[:3, :3] @ j.axis
        P[i] = F[:3, :3] @ j.axis_point + F[:3, 3]
    return P, U


def line_gap(p1: Array, u1: Array, p2: Array, u2: Array) -> tuple[float, Array, Array]:
    """Distance (m) between two lines and their closest points (for parallel lines: the
    foot on line 2 of p1, and p1)."""
    w = p1 - p2
    b = float(u1 @ u2)
    d, e = float(u1 @ w), float(u2 @ w)
    den = 1.0 - b * b
    if den < GEOMETRY_TOL**2:
        s, t = 0.0, e
    else:
        s, t = (b * e - d) / den, (e - b * d) / den
    c1, c2 = p1 + s * u1, p2 + t * u2
    return float(np.linalg.norm(c1 - c2)), c1, c2


def base_frame(p1: Array, u1: Array) -> tuple[Array, int]:
    """A family's base frame W (4x4, in frame 0) on axis 1, and the sign of joint 1.

    z is axis 1 (the frame-0 z axis, when axis 1 is parallel to it: the sign says whether
    the joint turns about +z or -z); the origin is the foot of frame 0's origin on axis 1;
    x is frame 0's x (else y) made perpendicular to z. A robot whose axis 1 is frame 0's
    z axis gets W = identity.
    """
    ez = np.array([0.0, 0.0, 1.0])
    if np.linalg.norm(np.cross(u1, ez)) <= GEOMETRY_TOL:
        z, sign = ez, (1 if u1 @ ez > 0 else -1)
    else:
        z, sign = u1 / np.linalg.norm(u1), 1
    origin = p1 - (p1 @ z) * z
    x = np.array([1.0, 0.0, 0.0]) - z[0] * z
    if np.linalg.norm(x) < 1e-6:
        x = np.array([0.0, 1.0, 0.0]) - z[1] * z
    x /= np.linalg.norm(x)
    W = np.eye(4)
    W[:3, 0], W[:3, 1], W[:3, 2], W[:3, 3] = x, np.cross(z, x), z, origin
    if np.abs(W - np.eye(4)).max() < 1e-15:
        W = np.eye(4)
    return W, sign


def straight_value(robot: Robot, joint: int, angle_plus: float) -> tuple[float, int]:
    """The value of revolute ``joint`` (0-based) at which two axes it turns relative to
    each other are parallel and point the same way (``angle_plus`` plus a multiple of
    2 pi) or opposite ways (plus pi): whichever lies nearest the middle of its limits.

    Returns (value rad, +1 when that is the same-way value, -1 when opposite). This fixes
    which aligned wrist is "straight" (its limits allow it) and which is folded back.
    """
    lo, hi = robot.joints[joint].limits
    mid = 0.5 * (lo + hi)
    near = [
        (a + 2.0 * math.pi * round((mid - a) / (2.0 * math.pi)), sign)
        for sign, a in ((1, angle_plus), (-1, angle_plus + math.pi))
    ]
    return near[0] if abs(near[0][0] - mid) <= abs(near[1][0] - mid) + 1e-12 else near[1]


def verify_fk(
    robot: Robot, fk: Callable[[Array], Array], *, samples: int = VERIFY_SAMPLES
) -> float:
    """Largest difference between ``fk(Q)`` (N, 4, 4) and the robot's FK (base left out)
    over q = 0 and ``samples`` seeded random joint vectors within the limits (m and
    rotation-matrix entries)."""
    rng = np.random.default_rng(7)
    lo, hi = robot.lower, robot.upper
    Q = np.vstack([np.zeros(robot.dof), rng.uniform(lo, hi, (samples, robot.dof))])
    mine = fk(Q)
    ref = np.linalg.inv(robot.base) @ robot._fk_unchecked(Q)
    return float(np.abs(mine - ref).max())
