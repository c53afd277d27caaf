"""Closed-form inverse kinematics of the Puma family (thesis §4.3).

A Puma-family robot is a 6R arm in standard DH with the Puma 560 convention:
alpha = (90, 0, -90, 90, -90, 0) deg, a1 = 0, d2 = 0, a4 = a5 = a6 = 0, d5 = d6 = 0
(a spherical wrist: the axes of joints 4, 5, 6 meet at the wrist centre, the origin of
frames 4, 5 and 6). Free parameters, read from the robot: d1 (shoulder height), a2
(upper arm), a3 and d4 (forearm), d3 (shoulder offset) and the joint offsets; the DH
angle is theta_i = q_i + offset_i. Units: metres and radians.

Derivation (frame i follows joint i; theta23 = theta2 + theta3). Strip base and tool:
T6 = inv(base) @ T @ inv(tool); its position p is the wrist centre. Relative to the
shoulder (the origin of frame 1, at height d1 on the joint 1 axis), with
r = |(px, py)| and z = pz - d1:

- joint 1: the wrist centre lies d3 along z1 = (sin theta1, -cos theta1, 0), so
  px sin theta1 - py cos theta1 = d3 and theta1 = atan2(py, px) + atan2(d3, h) with
  h = +-sqrt(r^2 - d3^2), the reach of the wrist centre along x1 (h >= 0: right arm).
- joints 2, 3: in the arm plane (x1, y1; y1 is z of frame 0) the wrist centre is
  (h, z) = a2 (c2, s2) + Rot(theta23) (a3, d4). The law of cosines gives the angle psi
  between the upper arm and the shoulder-wrist line, cos psi = (a2^2 + rho^2 - L^2) /
  (2 a2 rho) with rho = |(h, z)| and L = sqrt(a3^2 + d4^2), so theta2 = atan2(z, h) +- psi
  and theta23 = atan2(z - a2 s2, h - a2 c2) - atan2(d4, a3).
- joints 4, 5, 6: M = R03^T R06 = Rz(theta4) Ry(-theta5) Rz(theta6) (ZYZ Euler angles
  with the middle angle negated), so theta5 = atan2(-+sqrt(M02^2 + M12^2), M22),
  theta4 = atan2(M12, M02) for sin theta5 < 0, and theta6 from
  Ry(theta5) Rz(-theta4) M = Rz(theta6). The twin (theta4 + pi, -theta5, theta6 + pi)
  gives the same wrist rotation.

Configuration letters (``IKSolution.config``), defined as P. Corke's Robotics Toolbox
does for the Puma 560 (``ikine6s`` / ``ikine_a``, after Paul and Zhang 1986), on the DH
angles:

- arm ``r`` (right) when h >= 0, i.e. the wrist centre lies on the +x1 side of the
  joint 1 axis (theta1 = atan2(py, px) + asin(d3 / r)); ``l`` (left) when h < 0
  (theta1 = atan2(py, px) + pi - asin(d3 / r)). The Puma 560's zero pose is right-armed.
- elbow ``u`` (up) when the elbow (origin of frame 2) lies above the straight line from
  the shoulder (origin of frame 1) to the wrist centre in the arm plane, "above" being
  the +z side of frame 0 (theta2 = atan2(z, h) + psi for a right arm, - psi for a left
  arm); ``d`` (down) when below.
- wrist ``n`` (no flip) when sin(theta5) < 0; ``f`` (flip) when sin(theta5) > 0 (with
  an explicit ``n`` the toolbox takes theta4 = atan2(V323, V313), which makes
  sin theta5 negative; ``f`` adds pi to theta4; the Python toolbox's ``ikine_a`` agrees:
  its unflipped ZYZ angle is >= 0 and is negated into theta5). An arm/elbow branch whose
  wrist is aligned (sin theta5 = 0) gives one solution, marked ``n``.

Examples: the Puma 560's zero pose qz is ``rd`` (the elbow lies below the line from the
shoulder to the wrist centre; wrist aligned); its nominal pose qn = (0, 45, -180, 0, 45,
0) deg is ``ruf``. (The MATLAB toolbox, given neither ``n`` nor ``f``, takes the ``f``
branch, its default n4 = -1.)

Wrist singularity: ``|sin theta5| < SINGULAR_TOL`` (1e-6) sets ``singular=True``; the
solution is still exact (theta4 comes from the pose, theta6 is solved from theta4). When
the wrist axes 4 and 6 are aligned to machine precision (``|sin theta5| <
ALIGNED_TOL`` = 1e-12, orientation error at most ~1e-12 rad), only theta4 + theta6 (or
theta6 - theta4) is determined: q4 is set to the current q4 (or 0) and q6 solved so the
pose is exact. (Rounding puts |sin theta5| of a pose made with q5 = 0 near 1e-16 to 3e-13;
a pose that lands above 1e-12 is solved as merely near-singular: exact, flagged, with q4
taken from the pose.) A wrist centre on the joint 1 axis of an arm with d3 = 0 leaves q1
free: it is set to the current q1 (or 0) and the solutions are flagged singular.

Speed: :func:`puma_ik_report` (one pose, where per-call overhead is everything) works on
Python floats, which beat numpy calls on arrays of eight rows: the joint values go through
the arithmetic of ``Robot.wrap_batch`` written out per joint (:func:`_joint_rows`, the
same bits), and every returned q is checked by forward kinematics of the Puma chain
written out in frame 0 (:func:`_fk_errors`; the robot's own numpy chain when base or tool
is rigid only to within 1e-9). :func:`puma_ik_batch` vectorises over poses instead.
"""

from __future__ import annotations

import functools
import math
import weakref
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell import spatial
from workcell.errors import GeometryError, KinematicsError
from workcell.robots.robot import IKSolution, Robot

__all__ = [
    "ALIGNED_TOL",
    "CONFIGS",
    "SINGULAR_TOL",
    "puma_config",
    "puma_ik",
    "puma_ik_batch",
    "puma_ik_report",
]

Array = NDArray[np.float64]

CONFIGS: tuple[str, ...] = ("lun", "luf", "ldn", "ldf", "run", "ruf", "rdn", "rdf")
"""Slot order of :func:`puma_ik_batch` and the default order of :func:`puma_ik`."""
SINGULAR_TOL = 1e-6
"""|sin theta5| below which a solution is flagged ``singular``."""
ALIGNED_TOL = 1e-12
"""|sin theta5| below which the wrist axes 4 and 6 count as aligned (q4 then chosen)."""
DEDUPE_TOL = 1e-9  # rad: solutions closer than this (modulo 2 pi) are the same
REACH_TOL = 1e-12  # m: slack on the reach tests (points on the boundary are reachable)
EXACT_TOL = 1e-9  # m and rad: a solution is exact when FK(q) is this close to T
_ORTHO_TOL = 1e-13  # |R^T R - I| of base and tool below which they count as exact rotations
_DEGENERATE = 1e-6  # branch separation below which duplicates are looked for
_ALPHA = np.radians([90.0, 0.0, -90.0, 90.0, -90.0, 0.0])
_TWO_PI = 2.0 * math.pi
_CF = "closed-form"  # IKSolution.method
_INV_TWO_PI = 1.0 / _TWO_PI  # as Robot.wrap_batch computes turns
_PI = math.pi


@dataclass(frozen=True)
class _Puma:
    """The parameters a Puma solver needs, read once per robot (its joints tuple)."""

    a2: float
    a3: float
    d1: float
    d3: float
    d4: float
    L: float  # forearm length sqrt(a3^2 + d4^2), m
    gamma: float  # atan2(d4, a3), rad
    offset: Array  # (6,) rad
    off: tuple[float, ...]  # the same as floats, rad
    base_eye: bool  # the base is the identity
    tool_eye: bool  # the tool is the identity
    # base and tool rotations orthonormal to rounding (ORTHO_TOL): FK errors can be
    # measured in frame 0 (see _fk_errors); else FK runs through the robot's own chain
    frame0: bool
    base_inv: Array  # (4, 4)
    tool_inv: Array  # (4, 4)
    tool_t: tuple[float, float, float] | None  # the tool's translation (m); None when 0
    # per joint, as floats: offset, limits (lo, hi) in rad and in turns with the 1e-12 wrap
    # slack (lo_t, hi_t): exactly the numbers Robot.wrap_batch uses
    joints: tuple[tuple[float, float, float, float, float], ...]


_CACHE: weakref.WeakKeyDictionary[Robot, _Puma] = weakref.WeakKeyDictionary()
_LAST: tuple[weakref.ref[Robot] | None, _Puma | None] = (None, None)  # the last robot seen


def _check_structure(robot: Robot) -> _Puma:
    """Validate the Puma 560 DH structure; raise KinematicsError saying what differs."""
    where = f"robot '{robot.name}' is not a Puma-family arm"
    if any(j.dh is None or j.dh.convention != "standard" for j in robot.joints):
        raise KinematicsError(f"{where}: closed-form IK needs standard DH rows")
    if robot.dof != 6 or any(j.kind != "revolute" for j in robot.joints):
        kinds = [j.kind for j in robot.joints]
        raise KinematicsError(f"{where}: closed-form IK needs 6 revolute joints, got {kinds}")
    J = [j.dh for j in robot.joints]
    bad = []
    for i, j in enumerate(J):
        if abs(j.alpha - _ALPHA[i]) > 1e-9:
            bad.append(
                f"alpha{i + 1} = {math.degrees(j.alpha):.6g} deg "
                f"(need {math.degrees(_ALPHA[i]):.0f})"
            )
    need_zero = [("a1", J[0].a), ("d2", J[1].d), ("a4", J[3].a), ("a5", J[4].a), ("a6", J[5].a)]
    need_zero += [("d5", J[4].d), ("d6", J[5].d)]
    bad += [f"{n} = {v:.6g} m (need 0)" for n, v in need_zero if abs(v) > 1e-12]
    a2, a3, d4 = J[1].a, J[2].a, J[3].d
    L = math.hypot(a3, d4)
    if a2 <= 0.0 or L <= 0.0:
        bad.append(f"a2 = {a2:.6g} m and sqrt(a3^2 + d4^2) = {L:.6g} m (both need > 0)")
    if bad:
        raise KinematicsError(
            f"{where} (standard DH, alpha = (90, 0, -90, 90, -90, 0) deg, a1 = d2 = 0, "
            f"spherical wrist a4 = a5 = a6 = d5 = d6 = 0): " + "; ".join(bad)
        )
    offset = np.array([j.offset for j in J])
    base_eye = bool((robot.base == np.eye(4)).all())
    tool_eye = bool((robot.tool == np.eye(4)).all())
    Rs = np.stack([robot.base[:3, :3], robot.tool[:3, :3]])
    deviation = np.abs(Rs.transpose(0, 2, 1) @ Rs - np.eye(3)).max()
    lo, hi = robot._lo.tolist(), robot._hi.tolist()
    lo_t, hi_t = robot._lo_turns.tolist(), robot._hi_turns.tolist()
    return _Puma(
        a2=float(a2),
        a3=float(a3),
        d1=float(J[0].d),
        d3=float(J[2].d),
        d4=float(d4),
        L=L,
        gamma=math.atan2(d4, a3),
        offset=offset,
        off=tuple(offset.tolist()),
        base_eye=base_eye,
        tool_eye=tool_eye,
        frame0=bool(deviation <= _ORTHO_TOL),
        base_inv=spatial.invert(robot.base),
        tool_inv=spatial.invert(robot.tool),
        tool_t=tuple(robot.tool[:3, 3].tolist()) if robot.tool[:3, 3].any() else None,
        joints=tuple(zip(offset.tolist(), lo, hi, lo_t, hi_t, strict=True)),
    )


def _params(robot: Robot) -> _Puma:
    """The robot's Puma parameters (validated once per robot: robots are immutable)."""
    global _LAST
    last, P = _LAST  # one read: another thread may replace the pair, never half of it
    if last is not None and last() is robot and P is not None:
        return P  # the same robot again: skips building a weak reference per call
    if not isinstance(robot, Robot):
        raise KinematicsError(f"puma_ik needs a Robot, got {type(robot).__name__}")
    P = _CACHE.get(robot)
    if P is None:
        P = _CACHE[robot] = _check_structure(robot)
    _LAST = (weakref.ref(robot), P)
    return P


def _reference(robot: Robot, q_current: ArrayLike | None) -> Array | None:
    if q_current is None:
        return None
    q = np.asarray(q_current, dtype=np.float64)
    if q.shape != (6,) or not np.all(np.isfinite(q)):
        raise KinematicsError(
            f"robot '{robot.name}': q_current must be 6 finite joint values (rad), got {q_current!r}"
        )
    return q


def _wrap_pi(q: Array) -> Array:
    """Angles wrapped to (-pi, pi] (rad)."""
    return _PI - np.mod(_PI - q, _TWO_PI)


def _distinct(Q: Array) -> NDArray[np.bool_]:
    """Mask of rows of Q (m, 6) that differ (modulo 2 pi, by DEDUPE_TOL) from every earlier row."""
    D = np.abs(_wrap_pi(Q[:, None, :] - Q[None, :, :])).max(axis=-1)
    same = np.tril(D < DEDUPE_TOL, k=-1)
    return ~same.any(axis=1)


# ---------------------------------------------------------------- the single-pose solver
def _unreachable(P: _Puma, r: float, z: float, rho: float) -> str:
    """Why the wrist centre at horizontal radius r, height z over the shoulder is out of reach."""
    d3 = abs(P.d3)
    dist = math.hypot(r, z)
    if r < d3 - REACH_TOL:
        return (
            f"out of reach: the wrist centre is {r:.4g} m from the joint 1 axis, inside the "
            f"shoulder-offset cylinder of radius |d3| = {d3:.4g} m"
        )
    far = P.a2 + P.L
    if rho > far + REACH_TOL:
        return (
            f"out of reach: the wrist centre is {dist:.4g} m from the shoulder, beyond the "
            f"arm's reach of {math.hypot(far, d3):.4g} m"
        )
    near = abs(P.a2 - P.L)
    return (
        f"out of reach: the wrist centre is {dist:.4g} m from the shoulder, closer than the "
        f"arm's minimum reach of {math.hypot(near, d3):.4g} m"
    )


_Branch = tuple[int, tuple[float, float, float], bool, list[tuple[float, float, float]]]
"""One arm/elbow branch: (slot of its first wrist in CONFIGS, DH angles theta1..3 (rad),
singular, [DH angles theta4..6 (rad) of the wrist, then of its flip twin if distinct])."""


def _solve_one(
    P: _Puma, T6: list[list[float]], ref: list[float] | None
) -> tuple[list[_Branch], bool, str]:
    """DH angles of every branch of one stripped pose T6 (rows as lists; ``ref`` the
    current q as floats, rad, or None).

    Returns (branches, maybe_duplicates, reason); the solutions come in CONFIGS order.
    """
    (r00, _, r02, px), (r10, _, r12, py), (r20, _, r22, pz) = T6[0], T6[1], T6[2]
    z = pz - P.d1
    r2 = px * px + py * py
    d3 = P.d3
    hr2 = r2 - d3 * d3
    rho2 = max(hr2, 0.0) + z * z
    rho = math.sqrt(rho2)
    r = math.sqrt(r2)
    if r < abs(d3) - REACH_TOL or rho > P.a2 + P.L + REACH_TOL or rho < abs(P.a2 - P.L) - REACH_TOL:
        return [], False, _unreachable(P, r, z, rho)
    hr = math.sqrt(max(hr2, 0.0))
    shoulder_free = r < REACH_TOL  # only reachable with d3 = 0: theta1 is free
    q1 = 0.0 if ref is None else ref[0]
    phi = q1 + P.off[0] if shoulder_free else math.atan2(py, px)
    delta = math.atan2(d3, hr)
    a2, L, gamma = P.a2, P.L, P.gamma
    cpsi = (a2 * a2 + rho2 - L * L) / (2.0 * a2 * rho) if rho > 0.0 else 0.0
    psi = math.acos(min(1.0, max(-1.0, cpsi)))
    maybe_dup = hr < _DEGENERATE * max(r, 1e-300) or min(psi, _PI - psi) < _DEGENERATE
    ref4 = (0.0 if ref is None else ref[3]) + P.off[3]
    cos, sin, atan2 = math.cos, math.sin, math.atan2
    out: list[_Branch] = []
    slot = 0
    for right in (False, True):
        if right:
            t1, h = phi + delta, hr
        else:
            t1, h = phi + _PI - delta, -hr
        c1, s1 = cos(t1), sin(t1)
        beta = atan2(z, h)
        ax1 = c1 * r02 + s1 * r12  # approach and normal vectors along x1 and -z1
        ay3 = c1 * r12 - s1 * r02
        nx1 = c1 * r00 + s1 * r10
        ny3 = c1 * r10 - s1 * r00
        for up in (True, False):
            t2 = beta + psi if up == right else beta - psi
            t23 = atan2(z - a2 * sin(t2), h - a2 * cos(t2)) - gamma
            c23, s23 = cos(t23), sin(t23)
            m02 = c23 * ax1 + s23 * r22
            m12 = ay3
            m22 = c23 * r22 - s23 * ax1
            m00 = c23 * nx1 + s23 * r20
            m10 = ny3
            m20 = c23 * r20 - s23 * nx1
            s5abs = math.hypot(m02, m12)
            if s5abs < ALIGNED_TOL:
                t4, t5 = ref4, (0.0 if m22 > 0.0 else _PI)
            else:
                t4, t5 = atan2(m12, m02), atan2(-s5abs, m22)
            c4, s4, c5, s5 = cos(t4), sin(t4), cos(t5), sin(t5)
            t6 = atan2(-s4 * m00 + c4 * m10, c5 * (c4 * m00 + s4 * m10) + s5 * m20)
            wrists = [(t4, t5, t6)]
            if s5abs >= ALIGNED_TOL:
                wrists.append((t4 + _PI, -t5, t6 + _PI))
            singular = s5abs < SINGULAR_TOL or shoulder_free
            out.append((slot, (t1, t2, t23 - t2), singular, wrists))
            slot += 2
    return out, maybe_dup or shoulder_free, ""


def _shift(P: _Puma, j: int, q: float, near_t: float | None) -> float | None:
    """:meth:`Robot.wrap_batch` for the value ``q`` (rad) of joint ``j`` (0-based), in floats.

    The 2 pi-equivalent of q within the joint's limits nearest to ``near_t`` (turns; None:
    to q itself), or None when there is none. The same operations as ``wrap_batch``
    (limits in turns with its slack, k rounded half to even like np.rint), so the same
    number to the bit.
    """
    _, lo, hi, lo_t, hi_t = P.joints[j]
    t = q * _INV_TWO_PI
    k_lo = math.ceil(lo_t - t)
    k_hi = math.floor(hi_t - t)
    if k_lo > k_hi:
        return None
    k = 0 if near_t is None else round(near_t - t)
    k = k_lo if k < k_lo else k_hi if k > k_hi else k
    x = q + _TWO_PI * k
    return lo if x < lo else hi if x > hi else x


_Rows = tuple[
    list[int], list[bool], list[list[float]], list[list[float]], list[tuple[bool, ...] | None]
]


def _joint_rows(
    P: _Puma, branches: list[_Branch], near: tuple[float | None, ...], want_Q: bool
) -> _Rows:
    """The joint values of every solution in ``branches``, in CONFIGS order.

    ``near`` (6,) is q_current in turns (q / 2 pi), or all None. Returns lists over the
    solutions: slot in CONFIGS, singular, ``Q`` (theta - offset wrapped to (-pi, pi],
    rad, as :func:`_wrap_pi`; empty unless ``want_Q``), the returned q (rad) and
    ``flags``. The returned q is each joint's in-limit representative, nearest to
    ``near`` (else to its Q value), exactly as ``Robot.wrap_batch(Q, near)`` gives it,
    when every joint has one; else it is Q, and ``flags`` says per joint whether it has
    one (None when all do). A value within its limits and within half a turn of ``near``
    is its own representative (wrap_batch's k = 0); :func:`_shift` does the others.
    Written out joint by joint: this runs for every pose.
    """
    (o1, l1, h1, _, _), (o2, l2, h2, _, _), (o3, l3, h3, _, _) = P.joints[:3]
    (o4, l4, h4, _, _), (o5, l5, h5, _, _), (o6, l6, h6, _, _) = P.joints[3:]
    n1, n2, n3, n4, n5, n6 = near
    pi, two_pi, inv = _PI, _TWO_PI, _INV_TWO_PI
    slots: list[int] = []
    singular: list[bool] = []
    Qs: list[list[float]] = []
    rows: list[list[float]] = []
    flags: list[tuple[bool, ...] | None] = []
    for slot, (t1, t2, t3), sing, wrists in branches:
        q1 = pi - (pi - (t1 - o1)) % two_pi
        q2 = pi - (pi - (t2 - o2)) % two_pi
        q3 = pi - (pi - (t3 - o3)) % two_pi
        w1, w2, w3 = q1, q2, q3
        if not (l1 <= q1 <= h1 and (n1 is None or -0.5 <= n1 - q1 * inv <= 0.5)):
            w1 = _shift(P, 0, q1, n1)
        if not (l2 <= q2 <= h2 and (n2 is None or -0.5 <= n2 - q2 * inv <= 0.5)):
            w2 = _shift(P, 1, q2, n2)
        if not (l3 <= q3 <= h3 and (n3 is None or -0.5 <= n3 - q3 * inv <= 0.5)):
            w3 = _shift(P, 2, q3, n3)
        for k, (t4, t5, t6) in enumerate(wrists):
            q4 = pi - (pi - (t4 - o4)) % two_pi
            q5 = pi - (pi - (t5 - o5)) % two_pi
            q6 = pi - (pi - (t6 - o6)) % two_pi
            w4, w5, w6 = q4, q5, q6
            if not (l4 <= q4 <= h4 and (n4 is None or -0.5 <= n4 - q4 * inv <= 0.5)):
                w4 = _shift(P, 3, q4, n4)
            if not (l5 <= q5 <= h5 and (n5 is None or -0.5 <= n5 - q5 * inv <= 0.5)):
                w5 = _shift(P, 4, q5, n5)
            if not (l6 <= q6 <= h6 and (n6 is None or -0.5 <= n6 - q6 * inv <= 0.5)):
                w6 = _shift(P, 5, q6, n6)
            slots.append(slot + k)
            singular.append(sing)
            if want_Q:
                Qs.append([q1, q2, q3, q4, q5, q6])
            if w1 is None or w2 is None or w3 is None or w4 is None or w5 is None or w6 is None:
                rows.append([q1, q2, q3, q4, q5, q6])
                flags.append(
                    (
                        w1 is not None,
                        w2 is not None,
                        w3 is not None,
                        w4 is not None,
                        w5 is not None,
                        w6 is not None,
                    )
                )
            else:
                rows.append([w1, w2, w3, w4, w5, w6])
                flags.append(None)
    return slots, singular, Qs, rows, flags


def _fk_errors(
    P: _Puma,
    rows: list[list[float]],
    T6: list[list[float]],
    tool_point: tuple[float, float, float],
) -> list[tuple[float, float]]:
    """Position (m) and orientation (rad) errors of FK(q) against the target T, per q (rad)
    of ``rows``, measured in frame 0 (needs ``P.frame0``).

    FK(q) = base A1(q1) ... A6(q6) tool is the tool pose in the base-reference frame and
    T = base T6 tool (T6 the flange pose in frame 0, ``tool_point`` = (inv(base) T)[:3, 3]
    its tool point in frame 0, m). The errors, the distance between the tool points and
    2 asin(|R_FK - R_T|_F / sqrt(8)), do not change under the base and tool rotations, so
    they are those of A1 ... A6 against T6: the tool points w + R06 t (t the tool's
    translation) against ``tool_point``, the rotations R06 against R6. The Puma's DH
    chain written out (``a1 = d2 = a4 = a5 = a6 = d5 = d6 = 0``, the alphas of
    :func:`_check_structure`): wrist centre w = Rz(theta1) Rx(90) (a2 c2 + a3 c23 -
    d4 s23, a2 s2 + a3 s23 + d4 c23, d3) + (0, 0, d1); R06 = R03 R36, and
    |R06 - R6|_F = |R36 - R03^T R6|_F, |w + R06 t - g| = |R03^T (w - g) + R36 t|.
    Consecutive rows with the same q1..q3 (wrist twins) share the arm terms.
    """
    b00, b01, b02 = T6[0][:3]
    b10, b11, b12 = T6[1][:3]
    b20, b21, b22 = T6[2][:3]
    tool = P.tool_t is not None
    tx, ty, tz = P.tool_t or (0.0, 0.0, 0.0)
    gx, gy, gz = tool_point
    o1, o2, o3, o4, o5, o6 = P.off
    a2, a3, d1, d3, d4 = P.a2, P.a3, P.d1, P.d3, P.d4
    cos, sin, sqrt, asin = math.cos, math.sin, math.sqrt, math.asin
    out: list[tuple[float, float]] = []
    p1 = p2 = p3 = None  # q1..q3 of the previous row (the same objects: the same values)
    for q1, q2, q3, q4, q5, q6 in rows:
        if q1 is not p1 or q2 is not p2 or q3 is not p3:
            p1, p2, p3 = q1, q2, q3
            t1, t2 = q1 + o1, q2 + o2
            t23 = t2 + (q3 + o3)
            c1, s1, c23, s23 = cos(t1), sin(t1), cos(t23), sin(t23)
            x = a2 * cos(t2) + a3 * c23 - d4 * s23
            # R03 = [[c1 c23, -s1, -c1 s23], [s1 c23, c1, -s1 s23], [s23, 0, c23]]
            u00, u10, u02, u12 = c1 * c23, s1 * c23, -c1 * s23, -s1 * s23
            # N = R03^T R6: the wrist rotation the target asks for
            n00 = u00 * b00 + u10 * b10 + s23 * b20
            n01 = u00 * b01 + u10 * b11 + s23 * b21
            n02 = u00 * b02 + u10 * b12 + s23 * b22
            n10 = c1 * b10 - s1 * b00
            n11 = c1 * b11 - s1 * b01
            n12 = c1 * b12 - s1 * b02
            n20 = u02 * b00 + u12 * b10 + c23 * b20
            n21 = u02 * b01 + u12 * b11 + c23 * b21
            n22 = u02 * b02 + u12 * b12 + c23 * b22
            # e = R03^T (w - g): the wrist centre's offset from the target tool point
            ex = c1 * x + s1 * d3 - gx
            ey = s1 * x - c1 * d3 - gy
            ez = a2 * sin(t2) + a3 * s23 + d4 * c23 + d1 - gz
            e0 = u00 * ex + u10 * ey + s23 * ez
            e1 = c1 * ey - s1 * ex
            e2 = u02 * ex + u12 * ey + c23 * ez
        t4, t5, t6 = q4 + o4, q5 + o5, q6 + o6
        c4, s4, c5, s5, c6, s6 = cos(t4), sin(t4), cos(t5), sin(t5), cos(t6), sin(t6)
        c4c5, s4c5 = c4 * c5, s4 * c5
        # R36 = Rz(theta4) Rx(90) Rz(theta5) Rx(-90) Rz(theta6), by columns
        v00, v10, v20 = c4c5 * c6 - s4 * s6, s4c5 * c6 + c4 * s6, s5 * c6
        v01, v11, v21 = -c4c5 * s6 - s4 * c6, c4 * c6 - s4c5 * s6, -s5 * s6
        v02, v12, v22 = -c4 * s5, -s4 * s5, c5
        if tool:  # R03^T (tool point - target tool point)
            dx = e0 + v00 * tx + v01 * ty + v02 * tz
            dy = e1 + v10 * tx + v11 * ty + v12 * tz
            dz = e2 + v20 * tx + v21 * ty + v22 * tz
        else:
            dx, dy, dz = e0, e1, e2
        f0, f1, f2 = v00 - n00, v01 - n01, v02 - n02  # |R36 - N|_F^2, by rows
        f = f0 * f0 + f1 * f1 + f2 * f2
        f0, f1, f2 = v10 - n10, v11 - n11, v12 - n12
        f += f0 * f0 + f1 * f1 + f2 * f2
        f0, f1, f2 = v20 - n20, v21 - n21, v22 - n22
        f += f0 * f0 + f1 * f1 + f2 * f2
        f = math.sqrt(f / 8.0)
        angle = 2.0 * asin(f if f < 1.0 else 1.0)
        out.append((sqrt(dx * dx + dy * dy + dz * dz), angle))
    return out


def _fk_errors_batch(robot: Robot, Q: Array, T: Array) -> list[tuple[float, float]]:
    """:func:`_fk_errors` through ``Robot._fk_unchecked`` (the robot's DH chain with its
    base and tool) for joint vectors Q (m, 6) rad against the tool pose T (4, 4)."""
    D = robot._fk_unchecked(Q)[:, :3, :] - T[:3, :]  # Q is the solver's own, finite
    out = []
    for ex, ey, ez, ep in (D * D).sum(axis=1).tolist():  # squared column distances, m^2
        out.append((math.sqrt(ep), 2.0 * math.asin(min(1.0, math.sqrt((ex + ey + ez) / 8.0)))))
    return out


def _pose(
    robot: Robot, P: _Puma, T: ArrayLike
) -> tuple[Array, list[list[float]], tuple[float, float, float]]:
    """Validate T (4x4 rigid, tool pose in the base frame); return it, T6 = inv(base) T
    inv(tool) (the flange pose in frame 0) as nested lists and the tool point of T in
    frame 0, (inv(base) T)[:3, 3] (m)."""
    M = None
    if type(T) is np.ndarray and T.shape == (4, 4) and T.dtype == np.float64:
        rows = T.tolist()  # the common case: checked in floats, no copy needed
        if rows[3] == [0.0, 0.0, 0.0, 1.0] and spatial._valid_single(rows, True):
            M = T
    if M is None:
        M = spatial.as_transforms(T, rigid=True, what=f"robot '{robot.name}': the target pose")
        if M.shape != (4, 4):
            raise GeometryError(f"robot '{robot.name}': the target pose must be one 4x4 matrix")
        rows = M.tolist()
    if not P.base_eye:
        G = P.base_inv @ M
        rows = G.tolist()
    tool_point = (rows[0][3], rows[1][3], rows[2][3])
    if not P.tool_eye:
        rows = ((M if P.base_eye else G) @ P.tool_inv).tolist()
    return M, rows, tool_point


@functools.cache
def _limits_reason(ok: tuple[bool, ...]) -> str:
    """The reason of a solution whose joints marked False have no in-limit equivalent."""
    bad = [str(j + 1) for j, good in enumerate(ok) if not good]
    many = len(bad) > 1
    return (
        f"outside joint limits: joint{'s' if many else ''} {', '.join(bad)} "
        f"ha{'ve' if many else 's'} no 2 pi-equivalent within the limits"
    )


def puma_ik_report(
    robot: Robot, T: ArrayLike, q_current: ArrayLike | None = None
) -> tuple[list[IKSolution], str]:
    """Every distinct closed-form solution of tool pose ``T`` and a reason when there is none.

    ``T`` (4x4, rigid) is the tool pose in the robot's base-reference frame, as returned by
    ``robot.fk``; ``q_current`` (6,) rad, optional, picks the 2 pi-representative of each
    joint (``Robot.wrap_to_limits(q, near=q_current)``), q4 at an aligned wrist, and the
    order. Returns ``(solutions, reason)``: up to 8 :class:`IKSolution` (see the module
    docstring for the config letters), and ``""``, or why the list is empty ("out of
    reach: ...") or why no solution is usable ("no solution within the joint limits").

    Each solution: ``q`` the in-limit representative (nearest to ``q_current``, else to the
    (-pi, pi] value); when a joint has no equivalent inside its limits, ``q`` is left
    wrapped to (-pi, pi] with ``within_limits=False``, ``success=False`` and a reason naming
    the joints. ``position_error`` (m) and ``orientation_error`` (rad) are measured by FK
    of the returned q against T; ``success`` needs both below 1e-9. Order: within limits
    first; then by max_i |q_i - q_current_i| (rad) when ``q_current`` is given, else in
    ``CONFIGS`` order (lun, luf, ldn, ldf, run, ruf, rdn, rdf).

    Raises KinematicsError for a robot outside the Puma family (saying which DH entries
    differ) and GeometryError for a target that is not a finite rigid 4x4 transform.
    """
    P = _params(robot)
    ref = _reference(robot, q_current)
    M, T6, tool_point = _pose(robot, P, T)
    ref_l = None if ref is None else ref.tolist()
    branches, maybe_dup, reason = _solve_one(P, T6, ref_l)
    if not branches:
        return [], reason
    near: tuple[float | None, ...] = (None,) * 6
    if ref_l is not None:
        near = tuple(v * _INV_TWO_PI for v in ref_l)  # turns, as wrap_batch computes them
    slots, singular, Qs, rows, flags = _joint_rows(P, branches, near, maybe_dup)
    m = len(rows)
    if maybe_dup:
        keep = _distinct(np.array(Qs)).tolist()
        pick = [i for i in range(m) if keep[i]]
        slots, singular = [slots[i] for i in pick], [singular[i] for i in pick]
        rows, flags = [rows[i] for i in pick], [flags[i] for i in pick]
        m = len(rows)
    Qw = np.array(rows)
    # FK of each returned q against T; when base or tool is rigid only to within 1e-9,
    # through the robot's own chain (which applies them as they are)
    errors = _fk_errors(P, rows, T6, tool_point) if P.frame0 else _fk_errors_batch(robot, Qw, M)
    if ref is None:  # the rows come in slot order
        order, outside = [], []
        for i, f in enumerate(flags):
            (order if f is None else outside).append(i)
        order += outside
    else:
        dist = np.abs(Qw - ref)
        far, total = dist.max(axis=1).tolist(), dist.sum(axis=1).tolist()
        order = sorted(range(m), key=lambda i: (flags[i] is not None, far[i], total[i], slots[i]))
    qs = list(Qw)
    sols = []
    for i in order:
        dp, dr = errors[i]
        bad = flags[i]
        if bad is not None:
            why = _limits_reason(bad)
        elif dp > EXACT_TOL or dr > EXACT_TOL:
            why = f"pose not reached exactly: errors {dp:.1e} m, {dr:.1e} rad"
        else:
            why = ""
        # positional (the fastest): q, success, config, within_limits, singular,
        # position_error, orientation_error, iterations, reason, method
        c = CONFIGS[slots[i]]
        sols.append(IKSolution(qs[i], not why, c, bad is None, singular[i], dp, dr, 0, why, _CF))
    if all(f is not None for f in flags):
        reason = f"no solution within the joint limits ({m} found outside them)"
    return sols, reason


def puma_ik(robot: Robot, T: ArrayLike, q_current: ArrayLike | None = None) -> list[IKSolution]:
    """Every distinct closed-form solution of tool pose ``T`` (Puma family), up to 8.

    An empty list when the pose is out of reach (:func:`puma_ik_report` says why). See
    :func:`puma_ik_report` for the fields, limits handling and order.
    """
    return puma_ik_report(robot, T, q_current)[0]


def puma_config(robot: Robot, q: ArrayLike) -> str:
    """Configuration letters (arm l|r, elbow u|d, wrist n|f) of joint vector q (rad).

    The letters of the module docstring, computed from the DH angles theta = q + offset:
    in the arm plane the elbow is e = a2 (c2, s2) and the wrist centre
    w = e + a3 (c23, s23) + d4 (-s23, c23); ``r`` when w_x >= 0; ``u`` when the elbow is
    on the upper side of the shoulder-wrist line (w_x e_y - w_y e_x >= 0 for a right arm,
    <= 0 for a left one); ``f`` when sin(theta5) > 0. On a boundary (w_x = 0, the elbow on
    the line, sin(theta5) = 0) both letters describe q; :func:`puma_ik` reports the first
    in ``CONFIGS`` order.
    """
    P = _params(robot)
    v = np.asarray(q, dtype=np.float64)
    if v.shape != (6,) or not np.all(np.isfinite(v)):
        raise KinematicsError(
            f"robot '{robot.name}': q must be 6 finite joint values (rad), got {q!r}"
        )
    t = (v + P.offset).tolist()
    t2, t23 = t[1], t[1] + t[2]
    ex, ey = P.a2 * math.cos(t2), P.a2 * math.sin(t2)
    wx = ex + P.a3 * math.cos(t23) - P.d4 * math.sin(t23)
    wy = ey + P.a3 * math.sin(t23) + P.d4 * math.cos(t23)
    right = wx >= 0.0
    cross = wx * ey - wy * ex
    up = cross >= 0.0 if right else cross <= 0.0
    return ("r" if right else "l") + ("u" if up else "d") + ("f" if math.sin(t[4]) > 0 else "n")


# ---------------------------------------------------------------- the batched solver
def puma_ik_batch(
    robot: Robot, Ts: ArrayLike, q_current: ArrayLike | None = None
) -> tuple[Array, NDArray[np.bool_]]:
    """All closed-form solutions of N tool poses at once, vectorised over the poses.

    ``Ts`` (N, 4, 4) rigid tool poses in the base-reference frame (a single 4x4 counts as
    N = 1); ``q_current`` (6,) or (N, 6) rad, optional, as in :func:`puma_ik_report`.
    Returns ``Q`` (N, 8, 6) rad and ``valid`` (N, 8) bool; slot k holds configuration
    ``CONFIGS[k]`` (lun, luf, ldn, ldf, run, ruf, rdn, rdf). ``Q[n, k]`` is NaN when slot k
    is not a distinct solution of pose n (pose out of reach; the flip twin at an aligned
    wrist; a branch that coincides with an earlier slot); otherwise the in-limit
    representative (nearest to ``q_current``, else to the (-pi, pi] value), or the
    (-pi, pi] value when some joint has no equivalent within its limits.
    ``valid[n, k]`` is True for the in-limit solutions. The non-NaN slots are exactly the
    solutions of :func:`puma_ik` (same q, same config); there is no FK check and no
    singular flag here. Raises GeometryError for poses that are not rigid transforms.
    """
    P = _params(robot)
    T = spatial.as_transforms(Ts, rigid=True, what=f"robot '{robot.name}' target poses")
    if T.ndim == 2:
        T = T[None]
    N = T.shape[0]
    ref = None
    if q_current is not None:
        ref = np.asarray(q_current, dtype=np.float64)
        if ref.shape not in ((6,), (N, 6)) or not np.all(np.isfinite(ref)):
            raise KinematicsError(
                f"robot '{robot.name}': q_current must be (6,) or ({N}, 6) finite rad, "
                f"got shape {ref.shape}"
            )
        ref = np.broadcast_to(ref, (N, 6))
    T6 = P.base_inv @ T @ P.tool_inv
    R = T6[:, :3, :3]
    px, py = T6[:, 0, 3], T6[:, 1, 3]
    z = T6[:, 2, 3] - P.d1
    a2, L, d3 = P.a2, P.L, P.d3

    r2 = px * px + py * py
    r = np.sqrt(r2)
    hr2 = r2 - d3 * d3
    hr = np.sqrt(np.maximum(hr2, 0.0))
    rho2 = np.maximum(hr2, 0.0) + z * z
    rho = np.sqrt(rho2)
    reach = (r >= abs(d3) - REACH_TOL) & (rho <= a2 + L + REACH_TOL)
    reach &= rho >= abs(a2 - L) - REACH_TOL
    shoulder_free = r < REACH_TOL
    ref1 = P.offset[0] + (0.0 if ref is None else ref[:, 0])
    phi = np.where(shoulder_free, ref1, np.arctan2(py, px))
    delta = np.arctan2(d3, hr)
    with np.errstate(divide="ignore", invalid="ignore"):
        cpsi = np.where(rho > 0.0, (a2 * a2 + rho2 - L * L) / (2.0 * a2 * rho), 0.0)
    psi = np.arccos(np.clip(cpsi, -1.0, 1.0))

    # (arm, elbow) pairs in CONFIGS order: lu, ld, ru, rd -> arrays (N, 4)
    right = np.array([False, False, True, True])
    up = np.array([True, False, True, False])
    t1 = np.where(right, phi[:, None] + delta[:, None], (phi + _PI - delta)[:, None])
    h = np.where(right, hr[:, None], -hr[:, None])
    beta = np.arctan2(z[:, None], h)
    t2 = beta + np.where(up == right, 1.0, -1.0) * psi[:, None]
    zz = z[:, None]
    t23 = np.arctan2(zz - a2 * np.sin(t2), h - a2 * np.cos(t2)) - P.gamma
    c1, s1, c23, s23 = np.cos(t1), np.sin(t1), np.cos(t23), np.sin(t23)

    def cols(v: Array) -> tuple[Array, Array, Array]:
        """Components of the column v (N, 3) of R06 in frame 3 (x3, y3, z3), each (N, 4)."""
        vx, vy, vz = v[:, 0, None], v[:, 1, None], v[:, 2, None]
        u1 = c1 * vx + s1 * vy
        return c23 * u1 + s23 * vz, c1 * vy - s1 * vx, c23 * vz - s23 * u1

    m02, m12, m22 = cols(R[:, :, 2])
    m00, m10, m20 = cols(R[:, :, 0])
    s5abs = np.hypot(m02, m12)
    aligned = s5abs < ALIGNED_TOL
    ref4 = P.offset[3] + (0.0 if ref is None else ref[:, 3, None])
    t4 = np.where(aligned, ref4, np.arctan2(m12, m02))
    t5 = np.where(aligned, np.where(m22 > 0.0, 0.0, _PI), np.arctan2(-s5abs, m22))
    c4, s4, c5, s5 = np.cos(t4), np.sin(t4), np.cos(t5), np.sin(t5)
    t6 = np.arctan2(-s4 * m00 + c4 * m10, c5 * (c4 * m00 + s4 * m10) + s5 * m20)

    th = np.empty((N, 4, 2, 6))
    th[..., 0] = t1[..., None]
    th[..., 1] = t2[..., None]
    th[..., 2] = (t23 - t2)[..., None]
    th[..., 0, 3], th[..., 0, 4], th[..., 0, 5] = t4, t5, t6
    th[..., 1, 3], th[..., 1, 4], th[..., 1, 5] = t4 + _PI, -t5, t6 + _PI
    Q = _wrap_pi(th.reshape(N, 8, 6) - P.offset)

    exists = np.repeat(reach[:, None], 8, axis=1)
    exists[:, 1::2] &= ~aligned
    degenerate = reach & (
        (hr < _DEGENERATE * np.maximum(r, 1e-300))
        | (np.minimum(psi, _PI - psi) < _DEGENERATE)
        | shoulder_free
    )
    for n in np.flatnonzero(degenerate):
        idx = np.flatnonzero(exists[n])
        exists[n, idx[~_distinct(Q[n, idx])]] = False

    W, ok = robot.wrap_batch(Q, None if ref is None else ref[:, None, :])
    Qw = np.where(ok.all(axis=-1, keepdims=True), W, Q)
    Qw[~exists] = np.nan
    return Qw, exists & ok.all(axis=-1)
