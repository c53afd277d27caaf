"""Closed-form inverse kinematics by family, detected from the geometry (thesis §4.3, generalised).

:func:`family_of` reads a robot's joint axes and returns ``"opw"`` (ortho-parallel base,
spherical wrist: :mod:`workcell.robots.opw`; the Pumas, KUKA KR, ABB IRB, Fanuc), ``"ur"``
(three parallel axes and an offset wrist: :mod:`workcell.robots.ur`) or None. A family's
parameters are verified against the robot's FK at random q before they are trusted, and
kept per robot (robots are immutable; :mod:`workcell.robots.ik_family`). Every other arm
uses the numerical IK.

Configuration letters (``IKSolution.config``), the Puma's as P. Corke's Robotics Toolbox
defines them (``ikine6s``, after Paul and Zhang 1986), stated geometrically so that they
mean the same for every family:

- shoulder ``r`` (right) when the wrist point (OPW: the wrist centre; UR: where axes 5
  and 6 meet) lies ahead of axis 1 in the arm's plane, on the side the arm faces at
  q = 0 (the Puma: +x1, h >= 0); ``l`` (left) behind it (the arm reaching back over);
- elbow ``u`` (up) when the elbow lies above the straight line from the shoulder to the
  wrist in the arm plane, above being the side of +z of the base; ``d`` below;
- wrist ``n`` (no flip) when joint 5 lies below the value at which the wrist is straight
  (axes 4 and 6 aligned, the value nearest the middle of its limits): sin(q5 - q5_straight)
  < 0 (the Puma: sin(theta5) < 0); ``f`` (flip) above it. A branch whose wrist is aligned
  gives one solution, marked ``n``.

Examples: the Puma 560's zero pose qz is ``rdn``; its nominal pose qn = (0, 45, -180,
0, 45, 0) deg is ``ruf``.

Each solution's q is the in-limit 2 pi-representative of every joint (nearest to
``q_current``, else to the (-pi, pi] value; :meth:`Robot.wrap_batch`'s arithmetic written
out per joint, the same bits); a joint without one leaves q wrapped to (-pi, pi] with
``within_limits=False``. Every returned q is checked by the family's own FK in floats
(the robot's numpy chain when base or tool is rigid only to within 1e-9): ``success``
needs position and orientation errors below 1e-9. Singular solutions are flagged: the
wrist (|sin theta5| < 1e-6), the shoulder (the wrist point within 1e-6 (relative) of
the boundary between the l and r branches; on axis 1 itself q1 is taken from
``q_current``) and the elbow (the arm stretched or folded to within 1e-6 rad). At an aligned wrist (|sin theta5| < 1e-12) q4 is the current q4 (or 0)
and q6 is solved so the pose stays exact.

Robot files round their numbers (the ROS Puma 560 URDF's axes are 1.8e-9 rad off
perpendicular). A chain within 1e-6 rad and 1e-7 m of a family (:mod:`workcell.robots.axes`)
is solved on the nearest exact geometry; every solution is then refined on the robot's
own chain to 1e-10 m and rad (:mod:`workcell.robots.ik_refine`: its ``position_error``
and ``orientation_error`` are the residuals, its ``method`` ``"closed-form, refined"``),
and one that does not refine is left out, never returned wrong. Such a family is
trusted only when, at random joint vectors away from singularities, the refined
solutions contain the generating q.
"""

from __future__ import annotations

import math
from itertools import chain
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell import spatial
from workcell.errors import GeometryError, KinematicsError
from workcell.robots.ik_family import _batch, _Solver, _solver, family_model, family_of, wrist_sine
from workcell.robots.ik_wrap import distinct, limits_reason, rows_of
from workcell.robots.robot import IKSolution, Robot

__all__ = [
    "CONFIGS",
    "EXACT_TOL",
    "config_of",
    "family_model",
    "family_of",
    "ik_all",
    "ik_batch",
    "ik_report",
    "wrist_sine",
]

Array = NDArray[np.float64]
CONFIGS: tuple[str, ...] = ("lun", "luf", "ldn", "ldf", "run", "ruf", "rdn", "rdf")
"""Slot order of :func:`ik_batch` and the default order of :func:`ik_all`."""
EXACT_TOL = 1e-9  # m and rad: a solution is exact when FK(q) is this close to T
_CF = "closed-form"
_CF_REFINED = "closed-form, refined"  # the method of a rounded chain's solutions
_INV_TWO_PI = 1.0 / (2.0 * math.pi)
_NO_NEAR: tuple[float | None, ...] = (None,) * 6
_chain = chain.from_iterable
_new_solution = tuple.__new__  # IKSolution from a full tuple: skips the named tuple's __new__


def _reference(robot: Robot, q_current: ArrayLike | None, shape: tuple[int, ...]) -> Array | None:
    if q_current is None:
        return None
    q = np.asarray(q_current, dtype=np.float64)
    if q.shape not in shape or not np.all(np.isfinite(q)):
        want = " or ".join(str(s) for s in shape)
        raise KinematicsError(
            f"robot '{robot.name}': q_current must be finite joint values (rad) of shape "
            f"{want}, got {q_current!r}"
        )
    return q


def _pose(robot: Robot, S: _Solver, T: ArrayLike) -> tuple[Array, list[list[float]]]:
    """Validate T (4x4 rigid tool pose in the base frame); return it and the model's end
    pose ``pre @ T @ post`` as rows (floats)."""
    M = None
    if type(T) is np.ndarray and T.shape == (4, 4) and T.dtype == np.float64:
        rows = T.tolist()
        if rows[3] == [0.0, 0.0, 0.0, 1.0] and spatial._valid_single(rows, True):
            M = T
    if M is None:
        M = spatial.as_transforms(T, rigid=True, what=f"robot '{robot.name}': the target pose")
        if M.shape != (4, 4):
            raise GeometryError(f"robot '{robot.name}': the target pose must be one 4x4 matrix")
        rows = M.tolist()
    if S.pre is not None or S.post is not None:
        G = M if S.pre is None else S.pre @ M
        rows = (G if S.post is None else G @ S.post).tolist()
    return M, rows[:3]


# ---------------------------------------------------------------- one pose
def ik_report(
    robot: Robot, T: ArrayLike, q_current: ArrayLike | None = None
) -> tuple[list[IKSolution], str]:
    """Every distinct closed-form solution of tool pose ``T`` and a reason when there is none.

    ``T`` (4x4, rigid) is the tool pose in the robot's base-reference frame (as
    ``robot.fk`` gives it); ``q_current`` (dof,) rad picks each joint's 2 pi
    representative, the free q1 / q4 at singular poses and the order. Returns up to 8
    :class:`IKSolution` (module doc) and ``""``, or why the list is empty ("out of
    reach: ...") or why no solution is usable. Order: within limits first; then by
    max_i |q_i - q_current_i| when ``q_current`` is given, else in ``CONFIGS`` order.
    KinematicsError for a robot without a family, GeometryError for a bad T.
    """
    S = _solver(robot)
    if q_current is None:  # the free angles at singular poses come from q = 0
        ref, ref_t, near = None, S.ref0, _NO_NEAR
    else:
        ref = _reference(robot, q_current, ((6,),))
        ref_l = ref.tolist()
        signs, offs = S.signs, S.offs
        ref_t = tuple(signs[j] * ref_l[j] - offs[j] for j in range(6))
        near = tuple(v * _INV_TWO_PI for v in ref_l)
    M, rows = _pose(robot, S, T)
    sols, maybe_dup, reason = S.solve_one(S.model, rows, ref_t)
    if not sols:
        return [], reason
    if S.refine:  # a rounded chain: Newton on the robot's own chain, failures dropped
        found = len(sols)
        sols = _refined(robot, S, sols, M)
        maybe_dup = True
        if not sols:
            return [], (
                f"none of the {found} closed-form solutions of the nearest exact geometry "
                f"refines onto robot '{robot.name}' (its rounding matters at this pose)"
            )
    Qs, qs, flags = rows_of(S.signs, S.offs, S.joints, sols, near)
    if maybe_dup:
        keep = distinct(np.array(Qs)).tolist()
        if not all(keep):
            sols = [s for s, k in zip(sols, keep, strict=True) if k]
            qs = [q for q, k in zip(qs, keep, strict=True) if k]
            flags = [f for f, k in zip(flags, keep, strict=True) if k]
    m = len(qs)
    Qw = np.fromiter(_chain(qs), np.float64, 6 * m).reshape(m, 6)  # np.array(qs), faster
    if S.floats:
        errors = S.errors(S.model, qs, rows, S.t_end)
    else:  # through the robot's own chain, which applies base and tool as they are
        D = robot._fk_unchecked(Qw)[:, :3, :] - M[:3, :]
        errors = [
            (math.sqrt(ep), 2.0 * math.asin(min(1.0, math.sqrt((ex + ey + ez) / 8.0))))
            for ex, ey, ez, ep in (D * D).sum(axis=1).tolist()
        ]
    rows_q = list(Qw)
    parts: Any = zip(sols, errors, flags, rows_q, strict=True)
    if ref is not None:
        dist = np.abs(Qw - ref)
        far, total = dist.max(axis=1).tolist(), dist.sum(axis=1).tolist()
        order = sorted(range(m), key=lambda i: (flags[i] is not None, far[i], total[i], sols[i][0]))
        parts = [(sols[i], errors[i], flags[i], rows_q[i]) for i in order]
    out = []  # within limits first, each group in slot order (or nearest first)
    outside = []
    new = _new_solution
    cf = _CF_REFINED if S.refine else _CF
    for (slot, _, singular), (dp, dr), bad, q in parts:
        if bad is not None:
            why = limits_reason(bad)
            sol = (q, False, CONFIGS[slot], False, singular, dp, dr, 0, why, cf)
            outside.append(new(IKSolution, sol))
            continue
        why = ""
        if dp > EXACT_TOL or dr > EXACT_TOL:
            why = f"pose not reached exactly: errors {dp:.1e} m, {dr:.1e} rad"
        out.append(new(IKSolution, (q, not why, CONFIGS[slot], True, singular, dp, dr, 0, why, cf)))
    in_limits = len(out)
    out += outside
    if not in_limits:
        reason = f"no solution within the joint limits ({m} found outside them)"
    return out, reason


def _refined(robot: Robot, S: _Solver, sols: list[Any], M: Array) -> list[Any]:
    """The solutions (slot, family angles, singular) refined onto pose M on the robot's
    chain (:func:`workcell.robots.ik_refine.refine`); those that do not refine are left out."""
    from workcell.robots.ik_refine import refine

    signs, offs = np.array(S.signs), np.array(S.offs)
    theta = np.array([t for _, t, _ in sols])
    singular = np.array([sing for _, _, sing in sols], dtype=bool)
    Q, _, _, ok = refine(robot, signs * (theta + offs), M, singular)
    theta = signs * Q - offs
    return [
        (slot, tuple(theta[i].tolist()), singular)
        for i, (slot, _, singular) in enumerate(sols)
        if ok[i]
    ]


def ik_all(robot: Robot, T: ArrayLike, q_current: ArrayLike | None = None) -> list[IKSolution]:
    """Every distinct closed-form solution of tool pose ``T``, up to 8 (see :func:`ik_report`)."""
    return ik_report(robot, T, q_current)[0]


def config_of(robot: Robot, q: ArrayLike) -> str:
    """Configuration letters (shoulder l|r, elbow u|d, wrist n|f) of joint vector q (rad).

    On a boundary (the wrist point on axis 1's plane, the elbow on the line, a straight
    wrist) both letters describe q; :func:`ik_all` reports the first in CONFIGS order.
    KinematicsError for a robot without a family or a bad q.
    """
    S = _solver(robot)
    v = np.asarray(q, dtype=np.float64)
    if v.shape != (6,) or not np.all(np.isfinite(v)):
        raise KinematicsError(
            f"robot '{robot.name}': q must be 6 finite joint values (rad), got {q!r}"
        )
    return S.letters(S.model, v * np.array(S.signs) - np.array(S.offs))


# ---------------------------------------------------------------- many poses
def ik_batch(
    robot: Robot, Ts: ArrayLike, q_current: ArrayLike | None = None
) -> tuple[Array, NDArray[np.bool_]]:
    """All closed-form solutions of N tool poses at once, vectorised over the poses.

    ``Ts`` (N, 4, 4) rigid tool poses in the base-reference frame (one 4x4 counts as N = 1);
    ``q_current`` (6,) or (N, 6) rad, optional, as in :func:`ik_report`. Returns ``Q``
    (N, 8, 6) rad and ``valid`` (N, 8): slot k holds configuration ``CONFIGS[k]``; NaN
    where slot k is not a distinct solution of pose n; otherwise the in-limit
    representative (nearest to ``q_current``, else to the (-pi, pi] value), or the
    (-pi, pi] value when some joint has none. ``valid`` marks the in-limit solutions. The
    non-NaN slots are the solutions of :func:`ik_all` (same q, same config); there is no
    FK check and no singular flag here (a rounded chain's slots are refined, and NaN
    where that fails). GeometryError for poses that are not rigid.
    """
    S = _solver(robot)
    T = spatial.as_transforms(Ts, rigid=True, what=f"robot '{robot.name}' target poses")
    if T.ndim == 2:
        T = T[None]
    N = T.shape[0]
    ref = _reference(robot, q_current, ((6,), (N, 6)))
    if ref is not None:
        ref = np.broadcast_to(ref, (N, 6))
    Q = np.empty((N, 8, 6))
    valid = np.empty((N, 8), dtype=bool)
    for i in range(0, N, _CHUNK):  # chunks keep the temporaries in cache
        j = min(N, i + _CHUNK)
        Q[i:j], valid[i:j] = _batch(robot, S, T[i:j], None if ref is None else ref[i:j])
    return Q, valid


_CHUNK = 4096  # poses per step of ik_batch
