"""The UR family: three parallel axes and an offset wrist (Universal Robots UR3/5/10/16 and e-Series).

The model is UR's own standard-DH structure, alpha = (90, 0, 0, 90, -90, 0) deg,
a = (0, a2, a3, 0, 0, 0), d = (d1, 0, 0, d4, d5, d6), with joint values mapped to DH angles
as ``q_i = sign_i (theta_i + offset_i)``; W (``base``) places DH frame 0 in frame 0 of
the chain and ``end`` the robot's tool frame in the frame at the meeting point of axes
5 and 6 with DH frame 6's orientation (``end = Tz(d6)`` for a UR arm with its flange as
the tool). A UR5e from UR's table reads back as d1 0.1625, a2 -0.425, a3 -0.3922, d4
0.1333, d5 0.0997, d6 0.0996 m, offsets and signs 0 and +1.

Reading it off a chain (:func:`ur_model`, never from a name): at q = 0, axes 1 and 2
meet at right angles, axes 2, 3 and 4 are parallel, axis 5 meets axis 4 and axis 6 meets
axis 5, each at right angles (and the arm is not OPW: see :mod:`workcell.robots.opw`).
d1 is the height of the meeting point of axes 1 and 2; a2 and a3 the distances between
axes 2, 3 and 4 in the arm plane, signed so that theta2 and theta3 at q = 0 lie within
+-90 deg (UR's own zero); d4 the offset of axis 5 along the parallel axes; d5 the distance
along axis 5 from axis 4 to axis 6. theta5 = 0 where axis 6 is parallel to axis 4; the
straight wrist (the letters' reference) is the parallel value nearest the middle of
joint 5's limits. The parameters are trusted only when the model's FK matches the
robot's at random q (:func:`~workcell.robots.axes.verify_fk`, 1e-9; a rounded file's model within its
rounding, its solutions then refined on the robot's chain: :mod:`workcell.robots.axes`).
The solvers are in
:mod:`workcell.robots.ur_solve`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from workcell.errors import KinematicsError
from workcell.robots.axes import (
    ANGLE_TOL,
    OFFSET_TOL,
    AxisModel,
    axis_lines,
    base_frame,
    fitted,
    line_gap,
    straight_value,
)
from workcell.robots.robot import Robot
from workcell.spatial import invert

__all__ = ["URModel", "ur_fk", "ur_model"]

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class URModel(AxisModel):
    """UR DH lengths (m), with :class:`AxisModel`'s joint offsets (rad) and signs and
    the frames ``base`` (W) and ``end`` (module doc); ``forward`` (+1 or -1: the arm
    faces +x1 or -x1 at q = 0) and ``straight`` (+1 or -1: the straight wrist has
    theta5 = 0 or pi)."""

    d1: float
    a2: float
    a3: float
    d4: float
    d5: float
    forward: int = 1
    straight: int = 1
    family: str = "ur"

    @property
    def d6(self) -> float:
        """The meeting point of axes 5 and 6 to the tool frame along axis 6 (m)."""
        return float(self.end[2, 3])

    def parameters(self) -> dict[str, float]:
        """The DH lengths by UR's names (m)."""
        return {
            "d1": self.d1,
            "a2": self.a2,
            "a3": self.a3,
            "d4": self.d4,
            "d5": self.d5,
            "d6": self.d6,
        }


def _dh(theta: Array, d: float, a: float, alpha: float) -> Array:
    c, s = np.cos(theta), np.sin(theta)
    ca, sa = math.cos(alpha), math.sin(alpha)
    A = np.zeros((len(theta), 4, 4))
    A[:, 0, 0], A[:, 0, 1], A[:, 0, 2], A[:, 0, 3] = c, -s * ca, s * sa, a * c
    A[:, 1, 0], A[:, 1, 1], A[:, 1, 2], A[:, 1, 3] = s, c * ca, -c * sa, a * s
    A[:, 2, 1], A[:, 2, 2], A[:, 2, 3], A[:, 3, 3] = sa, ca, d, 1.0
    return A


def ur_fk(model: URModel, Q: Array) -> Array:
    """Tool poses (N, 4, 4) in frame 0 of the chain for joint values Q (N, 6) rad."""
    t = model.theta(np.atleast_2d(Q))
    rows = (
        (model.d1, 0.0, math.pi / 2),
        (0.0, model.a2, 0.0),
        (0.0, model.a3, 0.0),
        (model.d4, 0.0, math.pi / 2),
        (model.d5, 0.0, -math.pi / 2),
        (0.0, 0.0, 0.0),
    )
    T = np.broadcast_to(model.base, (len(t), 4, 4)).copy()
    for i, (d, a, alpha) in enumerate(rows):
        T = T @ _dh(t[:, i], d, a, alpha)
    return T @ model.end


def _half_turn(angle: float, length: float) -> tuple[float, float]:
    """(angle, length) or (angle + pi, -length), whichever puts the angle within +-90 deg."""
    a = math.remainder(angle, 2.0 * math.pi)
    if abs(a) > math.pi / 2 + 1e-12:
        return math.remainder(a + math.pi, 2.0 * math.pi), -length
    return a, length


def ur_model(robot: Robot) -> URModel:
    """The verified UR model of ``robot`` (module doc); KinematicsError saying which
    condition fails for a robot outside the family."""
    where = f"robot '{robot.name}' is not a UR-type arm"
    if robot.dof != 6 or any(j.kind != "revolute" for j in robot.joints):
        raise KinematicsError(f"{where}: it needs 6 revolute joints")
    P, U = axis_lines(robot)
    tol = OFFSET_TOL  # lengths (m); angles are tested against ANGLE_TOL (rad)
    checks = [
        ("axes 1 and 2 are not perpendicular", abs(U[0] @ U[1])),
        ("axes 2 and 3 are not parallel", np.linalg.norm(np.cross(U[1], U[2]))),
        ("axes 3 and 4 are not parallel", np.linalg.norm(np.cross(U[2], U[3]))),
        ("axes 4 and 5 are not perpendicular", abs(U[3] @ U[4])),
        ("axes 5 and 6 are not perpendicular", abs(U[4] @ U[5])),
    ]  # sines of the angles off perpendicular or parallel
    bad = [f"{what} ({math.asin(min(v, 1.0)):.3g} rad off)" for what, v in checks if v > ANGLE_TOL]
    gap12, p12, _ = line_gap(P[0], U[0], P[1], U[1])
    gap45, p45, _ = line_gap(P[3], U[3], P[4], U[4])
    gap56, p56, _ = line_gap(P[4], U[4], P[5], U[5])
    for what, g in (("1 and 2", gap12), ("4 and 5", gap45), ("5 and 6", gap56)):
        if g > tol:
            bad.append(f"axes {what} miss each other by {g * 1e3:.4g} mm")
    if bad:
        raise KinematicsError(f"{where}: " + "; ".join(bad))
    W, s1 = base_frame(P[0], U[0])
    Wi = invert(W)
    u = (Wi[:3, :3] @ U.T).T
    p = (Wi[:3, :3] @ P.T).T + Wi[:3, 3]
    p1, p45, p56 = (Wi[:3, :3] @ v + Wi[:3, 3] for v in (p12, p45, p56))
    z1 = u[1] / np.linalg.norm(u[1])  # DH z1 = axis 2 (sign 2 = +1)
    t1 = math.atan2(z1[0], -z1[1])  # z1 = (sin t1, -cos t1, 0)
    x1, up = np.array([math.cos(t1), math.sin(t1), 0.0]), np.array([0.0, 0.0, 1.0])
    d1 = float(p1[2])

    def plane(v: Array) -> tuple[float, float]:
        w = v - p1
        return float(w @ x1), float(w @ up)

    e3, e4 = plane(p[2]), plane(p[3])
    t2, a2 = _half_turn(math.atan2(e3[1], e3[0]), math.hypot(*e3))
    t23, a3 = _half_turn(math.atan2(e4[1] - e3[1], e4[0] - e3[0]), math.hypot(*np.subtract(e4, e3)))
    if abs(a2) <= tol or abs(a3) <= tol:
        raise KinematicsError(f"{where}: two of the parallel axes 2, 3, 4 coincide")
    d4 = float((p45 - p1) @ z1)
    d5 = float((p56 - p45) @ u[4])
    # frame 3 = Rz(t1) Rx(90) Rz(t23); axis 5 = z4 = R03 (sin t4, -cos t4, 0) (sign 5 = +1)
    x3 = math.cos(t23) * x1 + math.sin(t23) * up
    y3 = -math.sin(t23) * x1 + math.cos(t23) * up
    t4 = math.atan2(float(u[4] @ x3), -float(u[4] @ y3))
    # theta5 = 0 where axis 6 points along z1 (axis 4's DH direction): q5 = plus
    plus = math.atan2(float(np.cross(u[5], z1) @ u[4]), float(u[5] @ z1))
    _, straight = straight_value(robot, 4, plus)
    signs = (s1, 1, int(np.sign(u[2] @ z1)), int(np.sign(u[3] @ z1)), 1, 1)
    theta0 = (t1, t2, t23 - t2, t4, -plus, 0.0)
    offsets = tuple(-t for t in theta0)
    forward = 1 if (p56 - p1) @ x1 >= 0 else -1
    draft = URModel(
        offsets=offsets, signs=signs, base=W, end=np.eye(4),
        d1=d1, a2=a2, a3=a3, d4=d4, d5=d5, forward=forward, straight=straight,
    )  # fmt: skip
    return fitted(robot, draft, ur_fk, where)
