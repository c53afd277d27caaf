"""Closed-form solutions of the OPW model (:mod:`workcell.robots.opw`): one pose in floats, many in numpy.

The target is the model's end pose: the wrist-centre frame in W (``M = W^-1 T end^-1``,
with T the robot's tool pose in frame 0), so its position is the wrist centre C.

- theta1: C = Rz(t1) (x, b, z) with x = +-sqrt(Cx^2 + Cy^2 - b^2) (+: the wrist centre
  ahead of axis 1, shoulder ``r``; -: behind, ``l``), t1 = atan2(Cy, Cx) - atan2(b, x).
  Inside the cylinder of radius |b| about axis 1 there is none; on axis 1 (b = 0)
  theta1 is free and taken from the current q.
- theta2, theta3: in the arm plane, relative to the shoulder, (u, v) = (x - a1, z - c1)
  = c2 e(t2) + L e(t2 + d) with e(a) = (sin a, cos a), L = sqrt(c3^2 + a2^2); the law
  of cosines gives d = +-acos((u^2 + v^2 - c2^2 - L^2) / (2 c2 L)) and t2 = atan2(u, v)
  - atan2(L sin d, c2 + L cos d); t23 = t2 + d - atan2(a2, c3). The elbow lies left of
  the shoulder-to-wrist direction for d > 0: above it (``u``) when u >= 0.
- theta4..6: M' = Ry(-t23) Rz(-t1) R = Rz(t4) Ry(t5) Rz(t6): t5 = atan2(+-|(m02, m12)|,
  m22), t4 = atan2(m12, m02), t6 = atan2(m21, -m20), and the twin (t4 + pi, -t5, t6 +
  pi); ``n`` when sign5 sin t5 < 0. At an aligned wrist (|sin t5| < ALIGNED_TOL) only
  t4 + t6 is fixed: t4 is the current one and the pose stays exact.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from workcell.robots.opw import OPWModel

__all__ = [
    "ALIGNED_TOL",
    "REACH_TOL",
    "SINGULAR_TOL",
    "arm_plane",
    "beside_axis1",
    "letters",
    "pose_errors",
    "solve_batch",
    "solve_one",
]

Array = NDArray[np.float64]
SINGULAR_TOL = 1e-6  # |sin theta5| below which a solution is flagged singular
ALIGNED_TOL = 1e-12  # |sin theta5| below which the wrist axes 4 and 6 count as aligned
REACH_TOL = 1e-12  # m: slack on the reach tests (points on the boundary are reachable)
DEGENERATE = 1e-6  # branch separation below which duplicates are looked for
_PI = math.pi

Solution = tuple[int, tuple[float, float, float, float, float, float], bool]
"""(slot in CONFIGS: 4 r + 2 d + f, OPW angles theta1..6 (rad), singular)."""


def _unreachable(m: OPWModel, rho: float, far: bool) -> str:
    L = m.forearm[0]
    if far:
        return (
            f"out of reach: the wrist centre is {rho:.4g} m from the shoulder, beyond the "
            f"arm's reach of {m.c2 + L:.4g} m"
        )
    return (
        f"out of reach: the wrist centre is {rho:.4g} m from the shoulder, closer than the "
        f"arm's minimum reach of {abs(m.c2 - L):.4g} m"
    )


def beside_axis1(
    px: float, py: float, offset: float, point: str, name: str, slack: float = 0.0
) -> tuple[float, float, str]:
    """A wrist point (px, py, m) against the cylinder of radius |offset| (m) about axis 1
    that the arm cannot enter: (squared distance from axis 1, the point's distance along
    a tangent of the cylinder, sqrt(r2 - offset^2) (0 on it), "" or why it is out of reach).
    ``point`` and ``name`` word the reason (the point's and the offset's names); a point
    within ``REACH_TOL + slack`` (m) inside counts as on the cylinder."""
    r2 = px * px + py * py
    h2 = r2 - offset * offset
    if h2 < -2.0 * abs(offset) * (REACH_TOL + slack):
        return (
            r2,
            0.0,
            (
                f"out of reach: the {point} is {math.sqrt(r2):.4g} m from axis 1, inside the "
                f"cylinder of radius |{name}| = {abs(offset):.4g} m the arm cannot enter"
            ),
        )
    return r2, (math.sqrt(h2) if h2 > 0.0 else 0.0), ""


def solve_one(
    m: OPWModel, M: list[list[float]], ref: tuple[float, ...] | None
) -> tuple[list[Solution], bool, str]:
    """Every solution of one end pose M (3 rows of 4 floats, module doc), in slot order.

    ``ref`` the OPW angles (6,) of the current q (rad), used where they are free. Returns
    (solutions, maybe_duplicates, reason when there is none).
    """
    (r00, _r01, r02, px), (r10, _r11, r12, py), (r20, _r21, r22, pz) = M
    a1, b, c1, c2 = m.a1, m.b, m.c1, m.c2
    (L, gamma), s5 = m.forearm, m.signs[4]
    cos, sin, atan2, sqrt = math.cos, math.sin, math.atan2, math.sqrt
    tol = REACH_TOL + m.slack
    r2, xs, why = beside_axis1(px, py, b, "wrist centre", "b", m.slack)
    if why:
        return [], False, why
    shoulder_free = r2 < REACH_TOL * REACH_TOL
    t1_ref, t4_ref = (ref[0], ref[3]) if ref is not None else (0.0, 0.0)
    phi = t1_ref if shoulder_free else atan2(py, px)
    v = pz - c1
    cc = c2 * c2 + L * L
    twice = 2.0 * c2 * L
    acos, hypot = math.acos, math.hypot
    out: list[Solution] = []
    reasons: list[str] = []
    shoulder = shoulder_free or xs < SINGULAR_TOL * max(sqrt(r2), 1e-300)
    maybe_dup = shoulder_free or xs < DEGENERATE * max(sqrt(r2), 1e-300)
    for right in (False, True):
        x = xs if right else -xs
        t1 = phi - atan2(b, x)
        u = x - a1
        rho2 = u * u + v * v
        ck = (rho2 - cc) / twice
        if ck > 1.0 or ck < -1.0:
            rho = sqrt(rho2)
            if rho > c2 + L + tol or rho < abs(c2 - L) - tol:
                reasons.append(_unreachable(m, rho, rho > c2 + L))
                continue
            ck = 1.0 if ck > 1.0 else -1.0  # on the boundary, up to rounding
        kappa = acos(ck)
        bend = _PI - kappa if kappa > _PI - kappa else kappa  # min(kappa, pi - kappa)
        elbow = bend < SINGULAR_TOL  # stretched or folded
        if bend < DEGENERATE:
            maybe_dup = True
        phv = atan2(u, v)
        c1_, s1_ = cos(t1), sin(t1)
        # the target's columns 0 and 2 turned into the arm plane (Rz(-t1))
        a0, b0 = c1_ * r00 + s1_ * r10, c1_ * r10 - s1_ * r00
        a2_, b2 = c1_ * r02 + s1_ * r12, c1_ * r12 - s1_ * r02
        for up in (True, False):
            d = kappa if up == (u >= 0.0) else -kappa
            t2 = phv - atan2(L * sin(d), c2 + L * cos(d))
            t23 = t2 + d - gamma
            c23, s23 = cos(t23), sin(t23)
            m02, m12, m22 = c23 * a2_ - s23 * r22, b2, s23 * a2_ + c23 * r22
            m00, m10, m20 = c23 * a0 - s23 * r20, b0, s23 * a0 + c23 * r20
            s5abs = hypot(m02, m12)
            if s5abs < ALIGNED_TOL:
                t4, t5 = t4_ref, (0.0 if m22 > 0.0 else _PI)
            else:
                t4, t5 = atan2(m12, m02), atan2(s5abs, m22)
            c4, s4, c5, sn5 = cos(t4), sin(t4), cos(t5), sin(t5)
            t6 = atan2(-s4 * m00 + c4 * m10, c5 * (c4 * m00 + s4 * m10) - sn5 * m20)
            singular = s5abs < SINGULAR_TOL or shoulder or elbow
            slot = 4 * right + 2 * (not up)
            t3 = t23 - t2
            first = (t1, t2, t3, t4, t5, t6)
            if s5abs < ALIGNED_TOL:
                out.append((slot, first, singular))
                continue
            twin = (t1, t2, t3, t4 + _PI, -t5, t6 + _PI)
            # the first has sin t5 > 0: letter n when sign5 < 0
            n_first, f_first = (first, twin) if s5 < 0 else (twin, first)
            out.append((slot, n_first, singular))
            out.append((slot + 1, f_first, singular))
    if not out:
        return [], False, reasons[-1] if reasons else "out of reach"
    return out, maybe_dup, ""


def arm_plane(m: OPWModel, theta: Array) -> tuple[float, float]:
    """(u, cross): the wrist centre's distance ahead of the shoulder in the arm's plane
    (m), and (wrist x elbow) there (m^2): the elbow lies on the arm's upper side (the
    side it has in front of the robot with the elbow up) when cross >= 0."""
    t2, t3 = float(theta[1]), float(theta[2])
    L, gamma = m.forearm
    t23 = t2 + t3
    ex, ez = m.c2 * math.sin(t2), m.c2 * math.cos(t2)  # elbow from the shoulder
    u = ex + L * math.sin(t23 + gamma)
    v = ez + L * math.cos(t23 + gamma)
    return u, u * ez - v * ex


def letters(m: OPWModel, theta: Array) -> str:
    """Configuration letters of the OPW angles theta (6,) rad (module doc of opw)."""
    u, cross = arm_plane(m, theta)
    right = u + m.a1 >= 0.0
    up = cross >= 0.0 if u >= 0.0 else cross <= 0.0
    flip = m.signs[4] * math.sin(float(theta[4])) > 0.0
    return ("r" if right else "l") + ("u" if up else "d") + ("f" if flip else "n")


def pose_errors(
    m: OPWModel,
    qs: list[list[float]],
    M: list[list[float]],
    t_end: tuple[float, float, float],
) -> list[tuple[float, float]]:
    """Position (m) and orientation (rad) errors of the model's FK at each joint vector of
    ``qs`` (rad) against the end pose M (3 rows of 4), in floats.

    The tool point (``t_end`` in the end frame) against the target's, and
    2 asin(|R - R_M|_F / sqrt(8)); both measured in the forearm frame Rz(t1) Ry(t23)
    (a rotation: the same numbers). Rows with the same q1..3 as the row before share the
    arm terms; a tool point on axis 6 (tx = ty = 0) skips their terms, and one at the
    wrist centre (t_end = 0) makes the position error an arm term: the same numbers up
    to the sign of a zero, which is squared.
    """
    (b00, b01, b02, px), (b10, b11, b12, py), (b20, b21, b22, pz) = M
    tx, ty, tz = t_end
    on_axis = tx == 0.0 and ty == 0.0
    at_centre = on_axis and tz == 0.0
    if on_axis:
        gx, gy, gz = px + b02 * tz, py + b12 * tz, pz + b22 * tz  # the target's tool point
    else:
        gx = px + b00 * tx + b01 * ty + b02 * tz
        gy = py + b10 * tx + b11 * ty + b12 * tz
        gz = pz + b20 * tx + b21 * ty + b22 * tz
    a1, b, c1, c2 = m.a1, m.b, m.c1, m.c2
    L, gamma = m.forearm
    cos, sin, sqrt, asin = math.cos, math.sin, math.sqrt, math.asin
    (k1, k2, k3, k4, k5, k6), (o1, o2, o3, o4, o5, o6) = m.signs, m.offsets
    out: list[tuple[float, float]] = []
    p1 = p2 = p3 = math.nan  # q1..3 of the previous row (NaN: none yet)
    n00 = n01 = n02 = n10 = n11 = n12 = n20 = n21 = n22 = e0 = e1 = e2 = dp = 0.0
    for q1, q2, q3, q4, q5, q6 in qs:
        if q1 != p1 or q2 != p2 or q3 != p3:
            p1, p2, p3 = q1, q2, q3
            t1, t2 = k1 * q1 - o1, k2 * q2 - o2
            t23 = t2 + k3 * q3 - o3
            cs1, sn1, c23, s23 = cos(t1), sin(t1), cos(t23), sin(t23)
            x = a1 + c2 * sin(t2) + L * sin(t23 + gamma)
            z = c1 + c2 * cos(t2) + L * cos(t23 + gamma)
            # N = Ry(-t23) Rz(-t1) R_M, column by column
            a, n10 = cs1 * b00 + sn1 * b10, cs1 * b10 - sn1 * b00
            n00, n20 = c23 * a - s23 * b20, s23 * a + c23 * b20
            a, n11 = cs1 * b01 + sn1 * b11, cs1 * b11 - sn1 * b01
            n01, n21 = c23 * a - s23 * b21, s23 * a + c23 * b21
            a, n12 = cs1 * b02 + sn1 * b12, cs1 * b12 - sn1 * b02
            n02, n22 = c23 * a - s23 * b22, s23 * a + c23 * b22
            # e = Ry(-t23) ((x, b, z) - Rz(-t1) g): wrist centre minus target tool point
            dx, dy, dz = x - (cs1 * gx + sn1 * gy), b - (cs1 * gy - sn1 * gx), z - gz
            e0, e1, e2 = c23 * dx - s23 * dz, dy, s23 * dx + c23 * dz
            if at_centre:
                dp = sqrt(e0 * e0 + e1 * e1 + e2 * e2)
        t4, t5, t6 = k4 * q4 - o4, k5 * q5 - o5, k6 * q6 - o6
        ca, sa, cb, sb, cc, sc = cos(t4), sin(t4), cos(t5), sin(t5), cos(t6), sin(t6)
        cacb, sacb = ca * cb, sa * cb
        v00, v01, v02 = cacb * cc - sa * sc, -cacb * sc - sa * cc, ca * sb
        v10, v11, v12 = sacb * cc + ca * sc, -sacb * sc + ca * cc, sa * sb
        v20, v21 = -sb * cc, sb * sc
        if at_centre:
            pass
        elif on_axis:
            dx, dy, dz = e0 + v02 * tz, e1 + v12 * tz, e2 + cb * tz
            dp = sqrt(dx * dx + dy * dy + dz * dz)
        else:
            dx = e0 + v00 * tx + v01 * ty + v02 * tz
            dy = e1 + v10 * tx + v11 * ty + v12 * tz
            dz = e2 + v20 * tx + v21 * ty + cb * tz
            dp = sqrt(dx * dx + dy * dy + dz * dz)
        f0, f1, f2 = v00 - n00, v01 - n01, v02 - n02
        f = f0 * f0 + f1 * f1 + f2 * f2
        f0, f1, f2 = v10 - n10, v11 - n11, v12 - n12
        f += f0 * f0 + f1 * f1 + f2 * f2
        f0, f1, f2 = v20 - n20, v21 - n21, cb - n22
        f += f0 * f0 + f1 * f1 + f2 * f2
        f = sqrt(f / 8.0)
        out.append((dp, 2.0 * asin(f if f < 1.0 else 1.0)))
    return out


def solve_batch(
    m: OPWModel, M: Array, ref: Array | None
) -> tuple[Array, NDArray[np.bool_], NDArray[np.bool_]]:
    """All solutions of N end poses M (N, 4, 4) at once: OPW angles (N, 8, 6) by slot,
    whether each slot exists (N, 8) and whether the pose is degenerate (N,) (duplicates
    possible). ``ref`` (N, 6) the current OPW angles, or None."""
    N = len(M)
    (L, gamma), s5 = m.forearm, m.signs[4]
    a1, b, c1, c2 = m.a1, m.b, m.c1, m.c2
    R = M[:, :3, :3]
    px, py, pz = M[:, 0, 3], M[:, 1, 3], M[:, 2, 3]
    r2 = px * px + py * py
    xs2 = r2 - b * b
    tol = REACH_TOL + m.slack
    inside = xs2 < -2.0 * abs(b) * tol
    xs = np.sqrt(np.maximum(xs2, 0.0))
    free = r2 < REACH_TOL * REACH_TOL
    t1r = np.zeros(N) if ref is None else ref[:, 0]
    t4r = np.zeros((N, 1)) if ref is None else ref[:, 3:4]
    phi = np.where(free, t1r, np.arctan2(py, px))
    right = np.array([False, False, True, True])  # (arm, elbow) pairs: lu, ld, ru, rd
    up = np.array([True, False, True, False])
    x = np.where(right, xs[:, None], -xs[:, None])
    t1 = phi[:, None] - np.arctan2(b, x)
    u = x - a1
    v = (pz - c1)[:, None]
    rho = np.hypot(u, v)
    ck = (u * u + v * v - (c2 * c2 + L * L)) / (2.0 * c2 * L)  # as the single-pose path
    ok = (rho <= c2 + L + tol) & (rho >= abs(c2 - L) - tol) & ~inside[:, None]
    kappa = np.arccos(np.clip(ck, -1.0, 1.0))
    d = np.where(up == (u >= 0.0), kappa, -kappa)
    t2 = np.arctan2(u, v) - np.arctan2(L * np.sin(d), c2 + L * np.cos(d))
    t23 = t2 + d - gamma
    c1_, s1_, c23, s23 = np.cos(t1), np.sin(t1), np.cos(t23), np.sin(t23)

    def col(k: int) -> tuple[Array, Array, Array]:
        cx, cy, cz = R[:, 0, k, None], R[:, 1, k, None], R[:, 2, k, None]
        a = c1_ * cx + s1_ * cy
        return c23 * a - s23 * cz, c1_ * cy - s1_ * cx, s23 * a + c23 * cz

    m02, m12, m22 = col(2)
    m00, m10, m20 = col(0)
    s5abs = np.hypot(m02, m12)
    aligned = s5abs < ALIGNED_TOL
    t4 = np.where(aligned, t4r, np.arctan2(m12, m02))
    t5 = np.where(aligned, np.where(m22 > 0.0, 0.0, _PI), np.arctan2(s5abs, m22))
    c4, s4, c5, sn5 = np.cos(t4), np.sin(t4), np.cos(t5), np.sin(t5)
    t6 = np.arctan2(-s4 * m00 + c4 * m10, c5 * (c4 * m00 + s4 * m10) - sn5 * m20)
    n_first = (s5 < 0) | aligned  # the first (sin t5 >= 0) has letter n when sign5 < 0
    th = np.empty((N, 4, 2, 6))
    th[..., 0] = t1[..., None]
    th[..., 1] = t2[..., None]
    th[..., 2] = (t23 - t2)[..., None]
    first = np.stack([t4, t5, t6], axis=-1)
    twin = np.stack([t4 + _PI, -t5, t6 + _PI], axis=-1)
    th[:, :, 0, 3:] = np.where(n_first[..., None], first, twin)
    th[:, :, 1, 3:] = np.where(n_first[..., None], twin, first)
    exists = np.stack([ok, ok & ~aligned], axis=-1)  # an aligned wrist: one solution, n
    degenerate = free | (xs < DEGENERATE * np.maximum(np.sqrt(r2), 1e-300))
    degenerate |= ((np.minimum(kappa, _PI - kappa) < DEGENERATE) & ok).any(axis=1)
    return th.reshape(N, 8, 6), exists.reshape(N, 8), degenerate
