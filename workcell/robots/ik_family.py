"""A robot's closed-form IK family (:mod:`workcell.robots.ik_closed`, whose module doc
says how families are found and trusted): the family's solver, detected from the robot's
geometry, verified (a rounded chain's refined solutions must contain the generating q at
random joint vectors) and cached per robot; :func:`_batch` solves many poses with it.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell.errors import KinematicsError
from workcell.robots.ik_wrap import DEDUPE_TOL, wrap_pi
from workcell.robots.robot import Robot
from workcell.spatial import invert

__all__ = ["family_model", "family_of", "wrist_sine"]

Array = NDArray[np.float64]
_ORTHO_TOL = 1e-13  # |R^T R - I| of base and tool below which errors are measured in floats
_FOUND_TOL = 1e-5  # rad: a refined solution is the generating q (modulo 2 pi)
_CONDITIONED = 1e-3  # smallest singular value of the Jacobian of a well-conditioned q
_SINGULAR_TOL = 1e-6  # |sin theta5| of a singular wrist (both families flag it so)


@dataclass(frozen=True, eq=False)
class _Solver:
    """A robot's verified family model and what the solvers need, read once per robot."""

    family: str
    model: Any  # OPWModel or URModel
    solve_one: Any  # (model, rows, ref theta (6,) | None) -> (solutions, maybe_dup, reason)
    solve_batch: Any  # (model, M (N,4,4), ref theta (N,6) | None) -> (theta, exists, degenerate)
    letters: Any  # (model, theta) -> str
    errors: Any  # (model, joint rows q, target rows, t_end) -> [(dp, dr)]
    signs: tuple[float, ...]
    offs: tuple[float, ...]
    pre: Array | None  # (base @ W)^-1, None when the identity
    post: Array | None  # end^-1, None when the identity
    t_end: tuple[float, float, float]  # the tool point in the model's end frame (m)
    floats: bool  # base and tool rotations orthonormal to rounding: errors in floats
    joints: tuple[tuple[float, float, float, float], ...]  # lo, hi, lo_t, hi_t per joint
    ref0: tuple[float, ...]  # the family angles of q = 0 (rad): the free angles by default
    refine: bool = False  # a rounded chain: solutions are Newton-refined on the robot's own


_CACHE: weakref.WeakKeyDictionary[Robot, _Solver | str] = weakref.WeakKeyDictionary()
_LAST: tuple[weakref.ref[Robot] | None, _Solver | None] = (None, None)


def _detect(robot: Robot) -> _Solver | str:
    """The robot's family solver, or the reasons it has none."""
    from workcell.robots import opw, opw_solve, ur, ur_solve

    reasons = []
    families = (
        ("opw", opw.opw_model, opw_solve),
        ("ur", ur.ur_model, ur_solve),
    )
    for name, build, mod in families:
        try:
            model = build(robot)
        except KinematicsError as exc:
            reasons.append(f"{name}: {exc}")
            continue
        W = robot.base @ model.base
        pre = None if np.array_equal(W, np.eye(4)) else invert(W)
        post = None if np.array_equal(model.end, np.eye(4)) else invert(model.end)
        Rs = np.stack([robot.base[:3, :3], robot.tool[:3, :3]])
        deviation = float(np.abs(Rs.transpose(0, 2, 1) @ Rs - np.eye(3)).max())
        S = _Solver(
            family=name,
            model=model,
            solve_one=mod.solve_one,
            solve_batch=mod.solve_batch,
            letters=mod.letters,
            errors=mod.pose_errors,
            signs=tuple(float(s) for s in model.signs),
            offs=tuple(float(o) for o in model.offsets),
            pre=pre,
            post=post,
            t_end=tuple(float(v) for v in model.end[:3, 3]),
            floats=deviation <= _ORTHO_TOL and model.exact,
            ref0=tuple(
                float(s) * 0.0 - float(o) for s, o in zip(model.signs, model.offsets, strict=True)
            ),
            joints=tuple(
                zip(
                    robot._lo.tolist(),
                    robot._hi.tolist(),
                    robot._lo_turns.tolist(),
                    robot._hi_turns.tolist(),
                    strict=True,
                )
            ),
            refine=not model.exact,
        )
        if S.refine:
            why = _verify_refined(robot, S)
            if why:
                reasons.append(f"{name}: robot '{robot.name}' {why}")
                continue
        return S
    return "; ".join(reasons)


def _verify_refined(robot: Robot, S: _Solver) -> str:
    """ "" when the refined closed form of a rounded chain (``S.refine``) finds, at q = 0
    and at :func:`~workcell.robots.axes.verify_fk`'s random joint vectors, the generating
    q among its solutions (every solution it returns is exact by construction); else why
    not. Joint vectors near a singularity (the Jacobian's smallest singular value below
    ``_CONDITIONED``) are left out: there the rounding itself moves the solutions (a
    fold's two branches split by ~sqrt of the rounding) and the check would test it."""
    from workcell.robots.axes import VERIFY_SAMPLES
    from workcell.robots.ik_refine import pose_jacobians

    rng = np.random.default_rng(7)
    Q = np.vstack([np.zeros(6), rng.uniform(robot._lo, robot._hi, (VERIFY_SAMPLES, 6))])
    T, J = pose_jacobians(robot, Q)
    keep = np.linalg.svd(J, compute_uv=False)[:, -1] > _CONDITIONED
    Q = Q[keep]
    S_all, _ = _batch(robot, S, T[keep], Q)
    found = np.abs(wrap_pi(S_all - Q[:, None, :])).max(axis=-1)
    missed = ~(np.nan_to_num(found, nan=np.inf).min(axis=1) < _FOUND_TOL)
    if missed.any() or len(Q) < VERIFY_SAMPLES // 2:
        return (
            f"is within the rounding of the {S.family} family but its refined closed form "
            f"misses the generating joint values at {int(missed.sum())} of {len(Q)} test "
            "poses"
        )
    return ""


def _solver(robot: Robot) -> _Solver:
    """The robot's family solver (cached); KinematicsError saying why there is none."""
    global _LAST
    last, S = _LAST
    if last is not None and last() is robot and S is not None:
        return S
    if not isinstance(robot, Robot):
        raise KinematicsError(f"closed-form IK needs a Robot, got {type(robot).__name__}")
    found = _CACHE.get(robot)
    if found is None:
        found = _CACHE[robot] = _detect(robot)
    if isinstance(found, str):
        raise KinematicsError(
            f"robot '{robot.name}' has no closed-form IK (family None: {found}); use Robot.ik"
        )
    _LAST = (weakref.ref(robot), found)
    return found


def family_of(robot: Robot) -> str | None:
    """``"opw"``, ``"ur"`` or None, detected from the robot's geometry (cached per robot)."""
    try:
        return _solver(robot).family
    except KinematicsError:
        return None


def wrist_sine(robot: Robot, q: Array) -> float | None:
    """|sin theta5| of joint vector q (0 at the wrist singularity), None without a family."""
    try:
        S = _solver(robot)
    except KinematicsError:
        return None
    return abs(math.sin(S.signs[4] * float(q[4]) - S.offs[4]))


def family_model(robot: Robot) -> Any:
    """The verified family model (``OPWModel`` or ``URModel``); KinematicsError when none."""
    return _solver(robot).model


def _batch(
    robot: Robot, S: _Solver, T: Array, ref: Array | None
) -> tuple[Array, NDArray[np.bool_]]:
    """:func:`~workcell.robots.ik_closed.ik_batch` of poses ``T`` (N, 4, 4) with solver
    ``S`` and the optional reference joints ``ref`` (N, 6) rad, in one step."""
    M = T if S.pre is None else S.pre @ T
    M = M if S.post is None else M @ S.post
    signs, offs = np.array(S.signs), np.array(S.offs)
    ref_t = (np.zeros((len(T), 6)) if ref is None else ref) * signs - offs
    theta, exists, degenerate = S.solve_batch(S.model, M, ref_t)
    if S.refine:  # a rounded chain: Newton on the robot's own chain, failures dropped
        from workcell.robots.ik_refine import refine

        n_i, k_i = np.nonzero(exists)
        th = theta[n_i, k_i]
        singular = np.abs(np.sin(th[:, 4])) < _SINGULAR_TOL
        Qr, _, _, ok = refine(robot, signs * (th + offs), T[n_i], singular)
        theta[n_i, k_i] = signs * Qr - offs
        exists[n_i[~ok], k_i[~ok]] = False
        degenerate = np.ones_like(degenerate)
    Q = wrap_pi(signs * (theta + offs))
    rows = np.flatnonzero(degenerate & exists.any(axis=1))
    if len(rows):  # a slot equal (modulo 2 pi) to an earlier existing slot is dropped
        Qd, ed = Q[rows], exists[rows]
        D = np.abs(wrap_pi(Qd[:, :, None, :] - Qd[:, None, :, :])).max(axis=-1)
        same = (D < DEDUPE_TOL) & ed[:, None, :] & np.tril(np.ones((8, 8), dtype=bool), k=-1)
        exists[rows] = ed & ~same.any(axis=2)
    W, ok = robot.wrap_batch(Q, None if ref is None else ref[:, None, :])
    Qw = np.where(ok.all(axis=-1, keepdims=True), W, Q)
    Qw[~exists] = np.nan
    return Qw, exists & ok.all(axis=-1)
