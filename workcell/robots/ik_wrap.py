"""Joint values of closed-form solutions: each joint's 2 pi-representative within its limits.

The same arithmetic as :meth:`Robot.wrap_batch <workcell.robots.robot.Robot.wrap_batch>`
(limits in turns with its 1e-12 slack, k rounded half to even like ``np.rint``), written
out in Python floats for the single-pose path of :mod:`workcell.robots.ik_closed`, where
per-call overhead is everything: the same bits as the numpy path. Angles in rad.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["DEDUPE_TOL", "distinct", "limits_reason", "rows_of", "wrap_pi"]

Array = NDArray[np.float64]
Limits = tuple[float, float, float, float]
"""A joint's (lo, hi) limits in rad and (lo, hi) in turns with the wrap slack."""
DEDUPE_TOL = 1e-9  # rad: solutions closer than this (modulo 2 pi) are the same
_PI = math.pi
_TWO_PI = 2.0 * math.pi
_INV_TWO_PI = 1.0 / _TWO_PI


def _shift(joint: Limits, q: float, near_t: float | None) -> float | None:
    """``Robot.wrap_batch`` for the value ``q`` (rad) of a joint with ``joint`` = (lo, hi,
    lo_t, hi_t), in floats: the 2 pi equivalent within the limits nearest to ``near_t``
    (turns; None: to q), or None."""
    lo, hi, lo_t, hi_t = joint
    t = q * _INV_TWO_PI
    k_lo = math.ceil(lo_t - t)
    k_hi = math.floor(hi_t - t)
    if k_lo > k_hi:
        return None
    k = 0 if near_t is None else round(near_t - t)
    k = k_lo if k < k_lo else k_hi if k > k_hi else k
    x = q + _TWO_PI * k
    return lo if x < lo else hi if x > hi else x


def rows_of(
    signs: tuple[float, ...],
    offs: tuple[float, ...],
    joints: tuple[Limits, ...],
    sols: list[tuple[int, tuple[float, ...], bool]],
    near: tuple[float | None, ...],
) -> tuple[list[list[float]], list[list[float]], list[tuple[bool, ...] | None]]:
    """For each solution's family angles theta: q = sign (theta + offset) wrapped to
    (-pi, pi] (``Q``), the returned q (the in-limit representative of every joint, nearest
    to ``near``, q_current in turns, else Q) and the flags (None, or per joint whether it
    has an in-limit value). A value within its limits and within half a turn of ``near``
    is its own representative (``wrap_batch``'s k = 0); :func:`_shift` does the others.
    Written out joint by joint: this runs for every pose. Joints 1 to 3 are wrapped once
    for a run of solutions that share theta1..3 (the wrist twins; the elbow pairs share
    theta1): the same value gives the same bits."""
    (s1, s2, s3, s4, s5, s6), (o1, o2, o3, o4, o5, o6) = signs, offs
    (l1, h1, _, _), (l2, h2, _, _), (l3, h3, _, _) = joints[:3]
    (l4, h4, _, _), (l5, h5, _, _), (l6, h6, _, _) = joints[3:]
    n1, n2, n3, n4, n5, n6 = near
    pi, two_pi, inv = _PI, _TWO_PI, _INV_TWO_PI
    Qs: list[list[float]] = []
    rows: list[list[float]] = []
    flags: list[tuple[bool, ...] | None] = []
    p1 = p2 = p3 = math.nan  # theta1..3 of the previous solution (NaN: none yet)
    q1 = q2 = q3 = w1 = w2 = w3 = 0.0
    for _, (t1, t2, t3, t4, t5, t6), _ in sols:
        if t1 != p1:
            p1, p2 = t1, math.nan
            q1 = pi - (pi - s1 * (t1 + o1)) % two_pi
            w1 = q1
            if not (l1 <= q1 <= h1 and (n1 is None or -0.5 <= n1 - q1 * inv <= 0.5)):
                w1 = _shift(joints[0], q1, n1)
        if t2 != p2 or t3 != p3:
            p2, p3 = t2, t3
            q2 = pi - (pi - s2 * (t2 + o2)) % two_pi
            q3 = pi - (pi - s3 * (t3 + o3)) % two_pi
            w2, w3 = q2, q3
            if not (l2 <= q2 <= h2 and (n2 is None or -0.5 <= n2 - q2 * inv <= 0.5)):
                w2 = _shift(joints[1], q2, n2)
            if not (l3 <= q3 <= h3 and (n3 is None or -0.5 <= n3 - q3 * inv <= 0.5)):
                w3 = _shift(joints[2], q3, n3)
        q4 = pi - (pi - s4 * (t4 + o4)) % two_pi
        q5 = pi - (pi - s5 * (t5 + o5)) % two_pi
        q6 = pi - (pi - s6 * (t6 + o6)) % two_pi
        w4, w5, w6 = q4, q5, q6
        if not (l4 <= q4 <= h4 and (n4 is None or -0.5 <= n4 - q4 * inv <= 0.5)):
            w4 = _shift(joints[3], q4, n4)
        if not (l5 <= q5 <= h5 and (n5 is None or -0.5 <= n5 - q5 * inv <= 0.5)):
            w5 = _shift(joints[4], q5, n5)
        if not (l6 <= q6 <= h6 and (n6 is None or -0.5 <= n6 - q6 * inv <= 0.5)):
            w6 = _shift(joints[5], q6, n6)
        Q = [q1, q2, q3, q4, q5, q6]
        Qs.append(Q)
        if w1 is None or w2 is None or w3 is None or w4 is None or w5 is None or w6 is None:
            rows.append(Q)
            flags.append(
                (w1 is not None, w2 is not None, w3 is not None,
                 w4 is not None, w5 is not None, w6 is not None)
            )  # fmt: skip
        else:
            rows.append([w1, w2, w3, w4, w5, w6])
            flags.append(None)
    return Qs, rows, flags


def wrap_pi(q: Array) -> Array:
    return _PI - np.mod(_PI - q, _TWO_PI)


def distinct(Q: Array) -> NDArray[np.bool_]:
    """Rows of Q (m, 6) that differ (modulo 2 pi, by DEDUPE_TOL) from every earlier row."""
    D = np.abs(wrap_pi(Q[:, None, :] - Q[None, :, :])).max(axis=-1)
    return ~np.tril(D < DEDUPE_TOL, k=-1).any(axis=1)


@functools.cache
def limits_reason(ok: tuple[bool, ...]) -> str:
    bad = [str(j + 1) for j, good in enumerate(ok) if not good]
    many = len(bad) > 1
    return (
        f"outside joint limits: joint{'s' if many else ''} {', '.join(bad)} "
        f"ha{'ve' if many else 's'} no 2 pi-equivalent within the limits"
    )
