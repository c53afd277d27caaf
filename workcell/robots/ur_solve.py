"""Closed-form solutions of the UR model (:mod:`workcell.robots.ur`): one pose in floats, many in numpy.

The target is the model's end pose ``M = W^-1 T end^-1`` (T the robot's tool pose in
frame 0): its position is p5, where axes 5 and 6 meet, its z axis is axis 6. With DH
frame 1 at (0, 0, d1), x1 = (c1, s1, 0), z1 = (s1, -c1, 0) (axis 2):

- theta1: p5 . z1 = d4 (the parallel axes shift the arm sideways by d4 only), so p5 =
  Rz(t1) (h, -d4) with h = +-sqrt(|p5_xy|^2 - d4^2) (ahead of axis 1: ``r``; behind: ``l``).
  Inside the cylinder of radius |d4| about axis 1 there is none.
- theta5, theta6: z1 seen from frame 6 is (s5 c6, -s5 s6, c5): t5 = atan2(+-|(w_x,
  w_y)|, w_z) with w = R^T z1, t6 = atan2(-w_y / s5, w_x / s5). At an aligned wrist
  (|sin t5| < ALIGNED_TOL) t6 is the current one.
- theta2, theta3, theta4: axis 4 passes p4 = p5 - d5 z4 with z4 = -s6 x6 - c6 y6; in the
  arm plane (u, v) = (p4 . x1, p4_z - d1) = a2 e(t2) + a3 e(t2 + t3), e(a) = (cos a, sin
  a): t3 = +-acos((u^2 + v^2 - a2^2 - a3^2) / (2 a2 a3)), t2 = atan2(v, u) - atan2(a3
  s3, a2 + a3 c3); t4 = atan2(x4_z, x4 . x1) - t2 - t3 with x4 = R (c5 c6, -c5 s6, -s5).

Letters as in :mod:`workcell.robots.ik_closed`: ``r`` when p5 lies ahead of axis 1 in the
direction the arm faces at q = 0 (``forward`` x1), ``u`` when the elbow (axis 3) lies
above the line from axis 2 to axis 4, ``n`` when sin(q5 - straight) < 0.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from workcell.robots.opw_solve import (
    ALIGNED_TOL,
    DEGENERATE,
    REACH_TOL,
    SINGULAR_TOL,
    beside_axis1,
)
from workcell.robots.ur import URModel

__all__ = ["letters", "pose_errors", "solve_batch", "solve_one"]

Array = NDArray[np.float64]
Solution = tuple[int, tuple[float, float, float, float, float, float], bool]
_PI = math.pi


def _elbow_up(f: int, wx: float, wz: float, ex: float, ez: float) -> bool:
    """Elbow e above the line from the shoulder to the wrist point w (arm plane, x1 and z
    coordinates, the arm facing f x1)."""
    cross = f * (wx * ez - wz * ex)
    return cross >= 0.0 if f * wx >= 0.0 else cross <= 0.0


def solve_one(
    m: URModel, M: list[list[float]], ref: tuple[float, ...] | None
) -> tuple[list[Solution], bool, str]:
    """Every solution of one end pose M (3 rows of 4 floats, module doc), in slot order.

    ``ref`` the current DH angles (6,) (rad), used where they are free. Returns
    (solutions, maybe_duplicates, reason when there is none).
    """
    (r00, r01, r02, px), (r10, r11, r12, py), (r20, r21, r22, pz) = M
    d1, a2, a3, d4, d5, f, st = m.d1, m.a2, m.a3, m.d4, m.d5, m.forward, m.straight
    cos, sin, atan2, sqrt = math.cos, math.sin, math.atan2, math.sqrt
    tol = REACH_TOL + m.slack
    r2, hs, why = beside_axis1(px, py, d4, "wrist", "d4", m.slack)
    if why:
        return [], False, why
    free = r2 < REACH_TOL * REACH_TOL
    psi = ref[0] if free and ref is not None else (0.0 if free else atan2(py, px))
    shoulder = free or hs < SINGULAR_TOL * max(sqrt(r2), 1e-300)
    maybe_dup = free or hs < DEGENERATE * max(sqrt(r2), 1e-300)
    found: dict[int, tuple[tuple[float, ...], bool]] = {}
    reason = ""
    lim = abs(a2) + abs(a3)
    for right in (False, True):
        h = (f if right else -f) * hs
        t1 = psi - atan2(-d4, h)
        c1, s1 = cos(t1), sin(t1)
        wx, wy, wz = r00 * s1 - r10 * c1, r01 * s1 - r11 * c1, r02 * s1 - r12 * c1
        s5abs = math.hypot(wx, wy)
        aligned = s5abs < ALIGNED_TOL
        for sg in (1.0,) if aligned else (1.0, -1.0):
            if aligned:
                t5 = 0.0 if wz > 0.0 else _PI
                t6 = ref[5] if ref is not None else 0.0
            else:
                t5, t6 = atan2(sg * s5abs, wz), atan2(-wy * sg, wx * sg)
            c5, sn5, c6, s6 = cos(t5), sin(t5), cos(t6), sin(t6)
            z4x, z4y, z4z = -s6 * r00 - c6 * r01, -s6 * r10 - c6 * r11, -s6 * r20 - c6 * r21
            qx, qy, qz = px - d5 * z4x, py - d5 * z4y, pz - d5 * z4z
            u, v = qx * c1 + qy * s1, qz - d1
            D = (u * u + v * v - a2 * a2 - a3 * a3) / (2.0 * a2 * a3)
            if D > 1.0 or D < -1.0:
                rho = math.hypot(u, v)
                if rho > lim + tol or rho < abs(abs(a2) - abs(a3)) - tol:
                    reason = (
                        f"out of reach: axis 4 would pass {rho:.4g} m from the shoulder, "
                        f"outside the arm's {abs(abs(a2) - abs(a3)):.4g} .. {lim:.4g} m"
                    )
                    continue
                D = 1.0 if D > 1.0 else -1.0
            k = math.acos(D)
            elbow = min(k, _PI - k) < SINGULAR_TOL  # stretched or folded
            if min(k, _PI - k) < DEGENERATE:
                maybe_dup = True
            x4x = c5 * c6 * r00 - c5 * s6 * r01 - sn5 * r02
            x4y = c5 * c6 * r10 - c5 * s6 * r11 - sn5 * r12
            x4z = c5 * c6 * r20 - c5 * s6 * r21 - sn5 * r22
            t234 = atan2(x4z, x4x * c1 + x4y * s1)
            flip = not aligned and st * sn5 > 0.0
            singular = s5abs < SINGULAR_TOL or shoulder or elbow
            for t3 in (k, -k):
                t2 = atan2(v, u) - atan2(a3 * sin(t3), a2 + a3 * cos(t3))
                up = _elbow_up(f, u, v, a2 * cos(t2), a2 * sin(t2))
                slot = 4 * right + 2 * (not up) + flip
                if slot not in found:
                    found[slot] = ((t1, t2, t3, t234 - t2 - t3, t5, t6), singular)
    out = [(s, th, sing) for s, (th, sing) in sorted(found.items())]
    return out, maybe_dup, ("" if out else reason or "out of reach")  # type: ignore[return-value]


def letters(m: URModel, theta: Array) -> str:
    """Configuration letters of the DH angles theta (6,) rad (module doc)."""
    _t1, t2, t3, t4, t5, _ = (float(t) for t in theta)
    t23 = t2 + t3
    ex, ez = m.a2 * math.cos(t2), m.a2 * math.sin(t2)
    wx, wz = ex + m.a3 * math.cos(t23), ez + m.a3 * math.sin(t23)
    h = wx + m.d5 * math.sin(t23 + t4)  # p5 along x1
    right = m.forward * h >= 0.0
    up = _elbow_up(m.forward, wx, wz, ex, ez)
    flip = m.straight * math.sin(t5) > 0.0
    return ("r" if right else "l") + ("u" if up else "d") + ("f" if flip else "n")


def pose_errors(
    m: URModel,
    qs: list[list[float]],
    M: list[list[float]],
    t_end: tuple[float, float, float],
) -> list[tuple[float, float]]:
    """Position (m) and orientation (rad) errors of the model's FK at each joint vector of
    ``qs`` (rad) against the end pose M (3 rows of 4): the tool points (``t_end`` in the
    end frame) and 2 asin(|R - R_M|_F / sqrt(8)), in floats (the DH chain written out:
    x4 = c234 x1 + s234 z0, y4 = z1, z4 = s234 x1 - c234 z0; x5 = c5 x4 + s5 y4,
    y5 = -z4, z5 = -s5 x4 + c5 y4; x6 = c6 x5 + s6 y5, y6 = -s6 x5 + c6 y5)."""
    (b00, b01, b02, px), (b10, b11, b12, py), (b20, b21, b22, pz) = M
    tx, ty, tz = t_end
    (k1, k2, k3, k4, k5, k6), (o1, o2, o3, o4, o5, o6) = m.signs, m.offsets
    a2, a3, d1, d4, d5 = m.a2, m.a3, m.d1, m.d4, m.d5
    cos, sin, sqrt, asin = math.cos, math.sin, math.sqrt, math.asin
    out = []
    for q1, q2, q3, q4, q5, q6 in qs:
        t1, t2 = k1 * q1 - o1, k2 * q2 - o2
        t23 = t2 + k3 * q3 - o3
        t234, t5, t6 = t23 + k4 * q4 - o4, k5 * q5 - o5, k6 * q6 - o6
        c1, s1 = cos(t1), sin(t1)
        c234, s234, c5, s5, c6, s6 = cos(t234), sin(t234), cos(t5), sin(t5), cos(t6), sin(t6)
        ax = a2 * cos(t2) + a3 * cos(t23) + d5 * s234  # p5 along x1, and its height
        az = d1 + a2 * sin(t2) + a3 * sin(t23) - d5 * c234
        x4x, x4y, x4z = c234 * c1, c234 * s1, s234
        z4x, z4y, z4z = s234 * c1, s234 * s1, -c234
        x5x, x5y, x5z = c5 * x4x + s5 * s1, c5 * x4y - s5 * c1, c5 * x4z
        z5x, z5y, z5z = -s5 * x4x + c5 * s1, -s5 * x4y - c5 * c1, -s5 * x4z
        x6x, x6y, x6z = c6 * x5x - s6 * z4x, c6 * x5y - s6 * z4y, c6 * x5z - s6 * z4z
        y6x, y6y, y6z = -s6 * x5x - c6 * z4x, -s6 * x5y - c6 * z4y, -s6 * x5z - c6 * z4z
        e00, e01, e02 = x6x - b00, y6x - b01, z5x - b02
        e10, e11, e12 = x6y - b10, y6y - b11, z5y - b12
        e20, e21, e22 = x6z - b20, y6z - b21, z5z - b22
        f = e00 * e00 + e01 * e01 + e02 * e02 + e10 * e10 + e11 * e11 + e12 * e12
        f = sqrt((f + e20 * e20 + e21 * e21 + e22 * e22) / 8.0)
        dx = ax * c1 + d4 * s1 - px + e00 * tx + e01 * ty + e02 * tz
        dy = ax * s1 - d4 * c1 - py + e10 * tx + e11 * ty + e12 * tz
        dz = az - pz + e20 * tx + e21 * ty + e22 * tz
        out.append((sqrt(dx * dx + dy * dy + dz * dz), 2.0 * asin(f if f < 1.0 else 1.0)))
    return out


def solve_batch(
    m: URModel, M: Array, ref: Array | None
) -> tuple[Array, NDArray[np.bool_], NDArray[np.bool_]]:
    """All solutions of N end poses M (N, 4, 4): DH angles (N, 8, 6) by slot, whether each
    slot exists (N, 8) and whether the pose is degenerate (N,). ``ref`` (N, 6) the
    current DH angles, or None."""
    N = len(M)
    d1, a2, a3, d4, d5, f, st = m.d1, m.a2, m.a3, m.d4, m.d5, m.forward, m.straight
    R, p = M[:, :3, :3], M[:, :3, 3]
    r2 = p[:, 0] ** 2 + p[:, 1] ** 2
    h2 = r2 - d4 * d4
    tol = REACH_TOL + m.slack
    inside = h2 < -2.0 * abs(d4) * tol
    hs = np.sqrt(np.maximum(h2, 0.0))
    free = r2 < REACH_TOL * REACH_TOL
    ref1 = np.zeros(N) if ref is None else ref[:, 0]
    ref6 = np.zeros(N) if ref is None else ref[:, 5]
    psi = np.where(free, ref1, np.arctan2(p[:, 1], p[:, 0]))
    # candidates (N, 2 shoulder, 2 wrist, 2 elbow)
    right = np.array([False, True])[None, :, None, None]
    h = np.where(right, f, -f) * hs[:, None, None, None]
    t1 = psi[:, None, None, None] - np.arctan2(-d4, h)
    c1, s1 = np.cos(t1), np.sin(t1)

    def col(k: int) -> tuple[Array, Array, Array]:
        return (
            R[:, 0, k, None, None, None],
            R[:, 1, k, None, None, None],
            R[:, 2, k, None, None, None],
        )

    (r00, r10, r20), (r01, r11, r21), (r02, r12, r22) = col(0), col(1), col(2)
    wx, wy, wz = r00 * s1 - r10 * c1, r01 * s1 - r11 * c1, r02 * s1 - r12 * c1
    s5abs = np.hypot(wx, wy)
    aligned = s5abs < ALIGNED_TOL
    sg = np.array([1.0, -1.0])[None, None, :, None]
    t5 = np.where(aligned, np.where(wz > 0.0, 0.0, _PI), np.arctan2(sg * s5abs, wz))
    t6 = np.where(aligned, ref6[:, None, None, None], np.arctan2(-wy * sg, wx * sg))
    c5, sn5, c6, s6 = np.cos(t5), np.sin(t5), np.cos(t6), np.sin(t6)
    qx = p[:, 0, None, None, None] - d5 * (-s6 * r00 - c6 * r01)
    qy = p[:, 1, None, None, None] - d5 * (-s6 * r10 - c6 * r11)
    qz = p[:, 2, None, None, None] - d5 * (-s6 * r20 - c6 * r21)
    u, v = qx * c1 + qy * s1, qz - d1
    rho = np.hypot(u, v)
    ok = (rho <= abs(a2) + abs(a3) + tol) & (rho >= abs(abs(a2) - abs(a3)) - tol)
    ok &= ~inside[:, None, None, None]
    D = np.clip((u * u + v * v - a2 * a2 - a3 * a3) / (2.0 * a2 * a3), -1.0, 1.0)
    k = np.arccos(D)
    t3 = k * np.array([1.0, -1.0])
    t2 = np.arctan2(v, u) - np.arctan2(a3 * np.sin(t3), a2 + a3 * np.cos(t3))
    x4x = c5 * c6 * r00 - c5 * s6 * r01 - sn5 * r02
    x4y = c5 * c6 * r10 - c5 * s6 * r11 - sn5 * r12
    x4z = c5 * c6 * r20 - c5 * s6 * r21 - sn5 * r22
    t4 = np.arctan2(x4z, x4x * c1 + x4y * s1) - t2 - t3
    ex, ez = a2 * np.cos(t2), a2 * np.sin(t2)
    cross = f * (u * ez - v * ex)
    up = np.where(f * u >= 0.0, cross >= 0.0, cross <= 0.0)
    flip = ~aligned & (st * sn5 > 0.0)
    exists = np.broadcast_to(ok & ~(aligned & (sg < 0)), up.shape)
    slot = 4 * np.broadcast_to(right, up.shape) + 2 * ~up + np.broadcast_to(flip, up.shape)
    cand = np.stack(np.broadcast_arrays(t1, t2, t3, t4, t5, t6), axis=-1).reshape(N, 8, 6)
    slot, exists = slot.reshape(N, 8), exists.reshape(N, 8)
    theta = np.full((N, 8, 6), np.nan)
    have = np.zeros((N, 8), dtype=bool)
    rows = np.arange(N)
    for c in range(8):  # the first candidate of a slot wins (a duplicate otherwise)
        s, e = slot[:, c], exists[:, c] & ~have[rows, slot[:, c]]
        theta[rows[e], s[e]] = cand[rows[e], c]
        have[rows[e], s[e]] = True
    degenerate = free | (hs < DEGENERATE * np.maximum(np.sqrt(r2), 1e-300))
    degenerate |= ((np.minimum(k, _PI - k) < DEGENERATE) & ok).reshape(N, -1).any(axis=1)
    return theta, have, degenerate
