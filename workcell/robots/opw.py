"""The OPW family: ortho-parallel base, spherical wrist (Brandstötter, Angerer, Hofbaur 2014).

M. Brandstötter, A. Angerer, M. Hofbaur, "An analytical solution of the inverse
kinematics problem of industrial serial manipulators with an ortho-parallel basis and a
spherical wrist", Austrian Robotics Workshop 2014. Pumas, KUKA KR, ABB IRB, Fanuc and
Stäubli six-axis arms have this geometry.

The model. In its base frame W, at OPW angles theta (all zero: the arm stretched
upward), axis 1 is z, axes 2 and 3 are parallel to y(theta1), axis 4 runs along the
forearm, axes 4, 5, 6 meet at the wrist centre C:

    x = a1 + c2 sin t2 + c3 sin t23 + a2 cos t23,   z = c1 + c2 cos t2 + c3 cos t23 - a2 sin t23
    C = Rz(t1) (x, b, z),   R = Rz(t1) Ry(t23) Rz(t4) Ry(t5) Rz(t6),   t23 = t2 + t3

(a1: axis 2 ahead of axis 1; b: the arm plane beside axis 1; c1: height of axis 2; c2:
upper arm; c3, a2: the wrist centre along and across the forearm; c4: wrist centre to
flange along axis 6). Joint values map to OPW angles as ``q_i = sign_i (theta_i +
offset_i)``, the convention of the published parameter sets (KUKA KR 6 R700 sixx: a1
0.025, a2 -0.035, b 0, c1 0.400, c2 0.315, c3 0.365, c4 0.080 m, offsets (0, -pi/2, 0,
0, 0, 0), signs (-1, 1, 1, -1, 1, -1)). The robot's tool frame is ``end`` in the frame
at C with R's orientation (``end = Tz(c4)`` for a robot whose tool is the OPW flange).

Reading the parameters off a chain (:func:`opw_model`, never from a name): the axis
lines at q = 0 must satisfy axis 1 perpendicular to 2, 2 parallel to 3, 4 perpendicular
to 2, 4 and 5 and 5 and 6 perpendicular, 4, 5 and 6 through one point. W comes from
:func:`~workcell.robots.axes.base_frame`; the forward direction e of the arm plane
points from axis 1 to axis 2 (a1 >= 0; with a1 = 0, towards the wrist centre at q = 0);
c2, c3 > 0 fix the zeros of theta2 and t23; axis 5's own direction is OPW's y there;
theta5 = 0 is the aligned wrist that lies nearest the middle of joint 5's limits (the
straight wrist, not the folded one); theta6's offset is 0 (``end`` takes the rest).
The parameters are trusted only when the model's FK matches the robot's at random q
(:func:`~workcell.robots.axes.verify_fk`, 1e-9); the axis tests accept the rounding of
published files (axes within 1e-6 rad, lines within 1e-7 m: see
:mod:`workcell.robots.axes`), and a model that then matches only to within that rounding
has its solutions refined on the robot's chain.

Configuration letters, as for the Puma (see :mod:`workcell.robots.ik_closed`): ``r``
when the wrist centre lies ahead of axis 1 (along e(theta1)), ``u`` when the elbow
(axis 3) lies above the line from the shoulder (axis 2) to the wrist centre, ``n`` when
joint 5 lies below its straight-wrist value (sin(q5 - straight) < 0). The solvers are in
:mod:`workcell.robots.opw_solve`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

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

__all__ = ["OPWModel", "opw_fk", "opw_model"]

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class OPWModel(AxisModel):
    """The seven OPW parameters of a robot (m), with :class:`AxisModel`'s joint offsets
    (rad) and signs and the frames that place the model: ``base`` (W) in frame 0 of the
    chain and ``end`` the robot's tool frame in the wrist-centre frame (module doc)."""

    a1: float
    a2: float
    b: float
    c1: float
    c2: float
    c3: float
    family: str = "opw"

    @cached_property
    def forearm(self) -> tuple[float, float]:
        """(L, gamma): the wrist centre's distance from axis 3, sqrt(c3^2 + a2^2) (m), and
        its angle off the forearm, atan2(a2, c3) (rad); computed once per model."""
        return math.hypot(self.c3, self.a2), math.atan2(self.a2, self.c3)

    @property
    def c4(self) -> float:
        """Wrist centre to the tool frame along axis 6 (m): ``end[2, 3]``."""
        return float(self.end[2, 3])

    def parameters(self) -> dict[str, float]:
        """The seven parameters by their published names (m)."""
        return {
            "a1": self.a1,
            "a2": self.a2,
            "b": self.b,
            "c1": self.c1,
            "c2": self.c2,
            "c3": self.c3,
            "c4": self.c4,
        }


def opw_fk(model: OPWModel, Q: Array) -> Array:
    """Tool poses (N, 4, 4) in frame 0 of the chain for joint values Q (N, 6) rad."""
    t = model.theta(np.atleast_2d(Q))
    t1, t2, t4, t5, t6 = t[:, 0], t[:, 1], t[:, 3], t[:, 4], t[:, 5]
    t23 = t2 + t[:, 2]
    s2, c2_, s23, c23 = np.sin(t2), np.cos(t2), np.sin(t23), np.cos(t23)
    x = model.a1 + model.c2 * s2 + model.c3 * s23 + model.a2 * c23
    z = model.c1 + model.c2 * c2_ + model.c3 * c23 - model.a2 * s23
    c1, s1 = np.cos(t1), np.sin(t1)
    N = len(t)
    T = np.zeros((N, 4, 4))
    T[:, 0, 3] = c1 * x - s1 * model.b
    T[:, 1, 3] = s1 * x + c1 * model.b
    T[:, 2, 3] = z
    T[:, 3, 3] = 1.0
    T[:, :3, :3] = _rz(t1) @ _ry(t23) @ _rz(t4) @ _ry(t5) @ _rz(t6)
    return model.base @ T @ model.end


def _rz(t: Array) -> Array:
    c, s = np.cos(t), np.sin(t)
    R = np.zeros((len(t), 3, 3))
    R[:, 0, 0], R[:, 0, 1], R[:, 1, 0], R[:, 1, 1], R[:, 2, 2] = c, -s, s, c, 1.0
    return R


def _ry(t: Array) -> Array:
    c, s = np.cos(t), np.sin(t)
    R = np.zeros((len(t), 3, 3))
    R[:, 0, 0], R[:, 0, 2], R[:, 2, 0], R[:, 2, 2], R[:, 1, 1] = c, s, -s, c, 1.0
    return R


def _sign(x: float) -> int:
    return 1 if x >= 0 else -1


def opw_model(robot: Robot) -> OPWModel:
    """The verified OPW model of ``robot`` (module doc); KinematicsError saying which
    condition fails for a robot outside the family."""
    where = f"robot '{robot.name}' is not an OPW arm"
    if robot.dof != 6 or any(j.kind != "revolute" for j in robot.joints):
        raise KinematicsError(f"{where}: it needs 6 revolute joints")
    P, U = axis_lines(robot)
    tol = OFFSET_TOL  # lengths (m); angles are tested against ANGLE_TOL (rad)
    checks = [
        ("axes 1 and 2 are not perpendicular", abs(U[0] @ U[1])),
        ("axes 2 and 3 are not parallel", np.linalg.norm(np.cross(U[1], U[2]))),
        ("axes 3 and 4 are not perpendicular", abs(U[2] @ U[3])),
        ("axes 4 and 5 are not perpendicular", abs(U[3] @ U[4])),
        ("axes 5 and 6 are not perpendicular", abs(U[4] @ U[5])),
    ]  # sines of the angles off perpendicular or parallel
    bad = [f"{what} ({math.asin(min(v, 1.0)):.3g} rad off)" for what, v in checks if v > ANGLE_TOL]
    gap45, c, _ = line_gap(P[3], U[3], P[4], U[4])
    gap56, _, c6 = line_gap(P[4], U[4], P[5], U[5])
    skew46 = np.linalg.norm(np.cross(U[3], U[5])) > ANGLE_TOL
    gap46 = line_gap(P[3], U[3], P[5], U[5])[0] if skew46 else 0.0
    for what, g in (("4 and 5", gap45), ("5 and 6", gap56), ("4 and 6", gap46)):
        if g > tol:
            bad.append(f"axes {what} miss each other by {g * 1e3:.4g} mm (no spherical wrist)")
    if not bad and np.linalg.norm(c - c6) > tol:
        bad.append("axes 4, 5 and 6 do not meet in one point (no spherical wrist)")
    if bad:
        raise KinematicsError(f"{where}: " + "; ".join(bad))
    W, s1 = base_frame(P[0], U[0])
    Wi = invert(W)
    p = (Wi[:3, :3] @ P.T).T + Wi[:3, 3]
    u = (Wi[:3, :3] @ U.T).T
    C = Wi[:3, :3] @ c + Wi[:3, 3]
    # the arm plane's forward direction e: horizontal, across axis 2, from axis 1 to axis 2
    e = np.cross(u[1], [0.0, 0.0, 1.0])
    e /= np.linalg.norm(e)
    a1 = float(p[1] @ e)
    if a1 < -tol or (abs(a1) <= tol and C @ e < 0):
        e, a1 = -e, -a1
    a1 = max(a1, 0.0) if abs(a1) <= tol else a1
    y = np.cross([0.0, 0.0, 1.0], e)
    phi1 = math.atan2(e[1], e[0])
    c1 = float(p[1][2])

    def plane(v: Array) -> tuple[float, float, float]:
        return float(v @ e), float(v @ y), float(v[2])

    x3, _, z3 = plane(p[2])
    c2 = math.hypot(x3 - a1, z3 - c1)
    t2 = math.atan2(x3 - a1, z3 - c1)
    xc, b, zc = plane(C)
    d4 = np.array(plane(u[3]))  # axis 4 in arm-plane coordinates (x, y ~ 0, z)
    along = (xc - x3) * d4[0] + (zc - z3) * d4[2]
    if along < 0:
        d4 = -d4
    t23 = math.atan2(d4[0], d4[2])
    c3 = abs(along)
    a2 = (xc - x3) * math.cos(t23) - (zc - z3) * math.sin(t23)
    if c2 <= tol:
        raise KinematicsError(f"{where}: axes 2 and 3 coincide (no upper arm)")
    s4 = _sign(float(np.array(plane(u[3])) @ d4))
    # the wrist: the forearm frame Rz(t1) Ry(t23); axis 5 is its y after theta4
    Rc = _rz(np.array([phi1]))[0] @ _ry(np.array([t23]))[0]
    v5 = Rc.T @ u[4]
    t4 = math.atan2(-v5[0], v5[1])
    # joint 5 turns axis 6; at its straight value axis 6 points out along axis 4 (OPW z)
    d4w = Rc[:, 2]
    plus = math.atan2(float(np.cross(u[5], d4w) @ u[4]), float(u[5] @ d4w))
    q5, s6 = straight_value(robot, 4, plus)
    signs = (s1, _sign(float(u[1] @ y)), _sign(float(u[2] @ y)), s4, 1, s6)
    theta0 = (phi1, t2, t23 - t2, t4, -q5, 0.0)  # OPW angles at q = 0 (theta5 = -q5)
    offsets = tuple(-t for t in theta0)
    draft = OPWModel(
        offsets=offsets, signs=signs, base=W, end=np.eye(4),
        a1=a1, a2=a2, b=float(b), c1=c1, c2=c2, c3=c3,
    )  # fmt: skip
    return fitted(robot, draft, opw_fk, where)
