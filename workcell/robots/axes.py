"""Joint axis lines of a chain, and the geometric tests the closed-form families run on them.

A closed-form family (OPW, UR) is recognised from the robot's geometry, never from its
name: the joint axes at q = 0, as lines (a point and a unit direction) in frame 0 of the
chain (the robot's ``base`` transform left out), must be parallel, perpendicular or
meet as the family requires. Each family then reads its parameters off these lines and
trusts them only after :func:`verify_fk` has compared its own forward kinematics with the
robot's at random joint values. Lengths in m, angles in rad.

Published robot files round their numbers (the ROS Puma 560 URDF writes pi/2 as
1.570796325: its axes are 1.8e-9 rad off perpendicular). The tests therefore accept axes
within :data:`ANGLE_TOL` of parallel or perpendicular and lines within
:data:`OFFSET_TOL` of meeting; the family's model is then the nearest exact geometry.
When that model's FK matches the robot's within :data:`VERIFY_TOL` it is exact; when it
matches only within :func:`rounding_bound` it is marked ``exact=False`` and every
closed-form solution is refined on the robot's own chain
(:mod:`workcell.robots.ik_refine`) before it is returned.
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
    "ANGLE_TOL",
    "GEOMETRY_TOL",
    "OFFSET_TOL",
    "VERIFY_TOL",
    "AxisModel",
    "axis_lines",
    "base_frame",
    "fitted",
    "line_gap",
    "max_reach",
    "rounding_bound",
    "straight_value",
    "verify_fk",
]

Array = NDArray[np.float64]
GEOMETRY_TOL = 1e-9
"""m, and cosines: below this, lines are parallel for :func:`line_gap` and axis 1 is the
frame-0 z axis for :func:`base_frame`."""
ANGLE_TOL = 1e-6
"""rad: axes closer than this to parallel or perpendicular are taken as such (rounded files)."""
OFFSET_TOL = 1e-7
"""m: axes closer than this to meeting meet; family lengths closer than this to 0 are 0."""
VERIFY_TOL = 1e-9
"""m and rotation-matrix entries: a family's FK must match the robot's this closely."""
VERIFY_SAMPLES = 64  # random joint vectors compared (plus q = 0)


@dataclass(frozen=True, eq=False)
class AxisModel:
    """What every family model has: joint ``offsets`` (rad) and ``signs`` mapping joint
    values to the model's angles, ``q_i = sign_i (theta_i + offset_i)``; ``base`` (4x4)
    the model's base frame in frame 0 of the chain; ``end`` (4x4) the robot's tool frame
    in the model's end frame; ``deviation``: how far the model's FK is from the robot's
    (m and rotation entries, the largest over :func:`verify_fk`'s samples); ``exact``
    when that is within ``VERIFY_TOL`` (else the solutions need refining on the robot)."""

    offsets: tuple[float, ...]
    signs: tuple[int, ...]
    base: Array
    end: Array
    deviation: float = dataclasses.field(default=0.0, kw_only=True)
    slack: float = dataclasses.field(default=0.0, kw_only=True)
    """m: added to the solvers' reach tests; for a rounded chain's model 10x its
    deviation (the real chain's reach boundary lies within it; its refinement decides)."""

    @property
    def exact(self) -> bool:
        """True when the model's FK is the robot's to within ``VERIFY_TOL``."""
        return self.deviation <= VERIFY_TOL

    def theta(self, Q: Array) -> Array:
        """The model's angles (..., 6) of joint values Q (rad): ``sign * q - offset``."""
        return np.asarray(Q) * np.array(self.signs) - np.array(self.offsets)


M = TypeVar("M", bound=AxisModel)


def max_reach(robot: Robot) -> float:
    """Upper bound (m) on the distance from the origin of frame 0 (``robot.base``) to the tool point.

    Sum over the joints of the largest translation each joint's transform can make
    (:meth:`~workcell.robots.chain.Joint.max_translation`: ``sqrt(a^2 + d^2)`` for a DH
    row, with d over its limits for a prismatic joint) plus the tool offset. Any target
    farther than this is out of reach whatever the joint limits.
    """
    r = sum(j.max_translation() for j in robot.joints)
    return r + float(np.linalg.norm(robot.tool[:3, 3]))


def rounding_bound(robot: Robot) -> float:
    """How far (m and rotation entries) a family model may be from the robot's FK and
    still count as the same geometry rounded: every joint's axis tilted by ``ANGLE_TOL``
    over the robot's reach bound (:func:`max_reach`), plus ``OFFSET_TOL`` per joint."""
    return robot.dof * (ANGLE_TOL * max(max_reach(robot), 1.0) + OFFSET_TOL)


def fitted(robot: Robot, draft: M, fk: Callable[[M, Array], Array], where: str) -> M:
    """``draft`` (its ``end`` the identity) with the ``end`` that puts its end frame on
    the robot's tool frame at q = 0, trusted when its FK then matches the robot's
    (:func:`verify_fk`): within ``VERIFY_TOL`` exactly, within :func:`rounding_bound`
    as the nearest exact geometry of a rounded chain (``deviation`` records which);
    KinematicsError saying by how much not."""
    zero = fk(draft, np.zeros((1, robot.dof)))[0]
    end = invert(zero) @ np.linalg.inv(robot.base) @ robot.fk(np.zeros(robot.dof))
    model = dataclasses.replace(draft, end=end)
    err = verify_fk(robot, lambda Q: fk(model, Q))
    bound = rounding_bound(robot)
    if err > bound:
        raise KinematicsError(
            f"{where}: the model read from its axes misses its FK by {err:.3g} (m or rotation "
            f"entries) at random joint values (a rounded file may miss by {bound:.2g})"
        )
    slack = 0.0 if err <= VERIFY_TOL else 10.0 * err
    return dataclasses.replace(model, deviation=err, slack=slack)


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
