"""The thesis's Newton-Gauss IK for :mod:`workcell.robots.ik_numeric` (see its docstring)."""

from __future__ import annotations

import math
import weakref
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from workcell.errors import KinematicsError
from workcell.robots.ik_closed import config_of, family_of
from workcell.robots.ik_common import (
    STALL_IMPROVEMENT,
    STALL_WINDOW,
    STEP_EPS,
    UNREACHABLE_RESTARTS,
    Array,
    _Attempt,
    _length_scale,
    _pose_errors,
    _random_q,
    _reach_gap,
    best_of_attempts,
)
from workcell.robots.robot import IKSolution, Robot

__all__ = ["NewtonGaussContext", "newton_gauss_context", "ng_residual_jacobian"]


# ------------------------------------------------------------------------- Newton-Gauss
@dataclass(eq=False)
class NewtonGaussContext:
    """Per-robot data of the Newton-Gauss solver, built once: the candidate start
    configurations sorted by the condition number of their weighted Jacobian (smallest
    first) and their configuration letters (closed-form families) or None."""

    starts: list[tuple[Array, float, str | None]]  # (q, condition number, config)
    length: float


_NG_CACHE: weakref.WeakKeyDictionary[Robot, NewtonGaussContext] = weakref.WeakKeyDictionary()
NG_CANDIDATES = 256  # sampled configurations searched for well-conditioned starts
NG_STARTS_PER_CONFIG = 2
NG_GENERIC_STARTS = 12
NG_MIN_SEPARATION = 1.0  # rad (max-norm) between kept generic starts
NG_STEP_POSITION = 0.2  # m of target motion per continuation step
NG_STEP_ANGLE = 0.5  # rad of target rotation per continuation step
NG_STEP_ITERATIONS = 2  # per continuation step
NG_LM = 1e-3  # adaptive LM damping: lambda = NG_LM * |f|^2 + 1e-12
NG_MAX_STEP = 0.5  # rad: the largest joint change in one iteration


def _vect(M: Array) -> Array:
    """Vector invariant 1/2 (m32 - m23, m13 - m31, m21 - m12) of a 3x3 matrix."""
    return 0.5 * np.array([M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1]])


def _ng_equations(
    chain: Robot, q: Array, T_target: Array, length: float
) -> tuple[Array, Array, Array]:
    T, J = chain.pose_jacobian(q)
    E = T_target[:3, :3] @ T[:3, :3].T
    v = _vect(E)
    tr = E[0, 0] + E[1, 1] + E[2, 2]
    f = np.empty(7)
    f[:3] = (T[:3, 3] - T_target[:3, 3]) / length
    f[3:6] = v
    f[6] = 0.5 * (tr - 3.0)
    Jf = np.empty((7, chain.dof))
    Jf[:3] = J[:3] / length
    Jf[3:6] = -0.5 * (tr * np.eye(3) - E.T) @ J[3:]
    Jf[6] = v @ J[3:]
    return f, Jf, T


def ng_residual_jacobian(
    robot: Robot, q: ArrayLike, T_target: ArrayLike, length: float = 1.0
) -> tuple[Array, Array, Array]:
    """The thesis's 7 equations at q, their analytic 7xn Jacobian, and the tool pose.

    ``f = [(p - p_t) / length, vect(E), (trace(E) - 3) / 2]`` with ``E = R_t R^T``
    (dimensionless; ``length`` in m weighs position against rotation; ``vect(E) =
    sin(theta) k`` and ``(trace(E) - 3) / 2 = cos(theta) - 1`` for a rotation error of
    theta about k, so all seven vanish exactly at the target, and the trace equation
    tells theta = pi from theta = 0 where the vector invariant cannot). With the
    geometric Jacobian's angular columns w_i (``dR/dq_i = [w_i]x R``):
    ``d vect(E)/dq_i = -1/2 (trace(E) I - E^T) w_i`` and
    ``d ((trace(E) - 3)/2)/dq_i = vect(E) . w_i``.
    """
    q = np.asarray(q, dtype=np.float64)
    if q.shape != (robot.dof,) or not np.all(np.isfinite(q)):
        raise KinematicsError(f"robot '{robot.name}': q must be {robot.dof} finite numbers")
    return _ng_equations(robot, q, np.asarray(T_target, dtype=np.float64), length)


def _condition(chain: Robot, q: Array, length: float) -> float:
    _, J = chain.pose_jacobian(q)
    J[:3] /= length
    s = np.linalg.svd(J, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else math.inf


def newton_gauss_context(robot: Robot) -> NewtonGaussContext:
    """The cached :class:`NewtonGaussContext` of ``robot``.

    Candidate starts: the named poses and ``NG_CANDIDATES`` seeded random in-limit
    configurations, ranked by the condition number of the weighted 6xn Jacobian
    ``[J_v / length; J_w]`` (equal to that of the 7xn Jacobian at a zero rotation error,
    whose trace row vanishes there). Closed-form robots keep the best ``NG_STARTS_PER_CONFIG``
    per configuration (so every branch has a start); other robots keep
    ``NG_GENERIC_STARTS`` mutually distant ones.
    """
    ctx = _NG_CACHE.get(robot)
    if ctx is not None:
        return ctx
    chain, length = robot, _length_scale(robot)
    rng = np.random.default_rng(20240601)
    cands = [p for p in robot.poses.values() if robot.within_limits(p)]
    cands += [_random_q(robot, rng) for _ in range(NG_CANDIDATES)]
    scored = sorted(((q, _condition(chain, q, length)) for q in cands), key=lambda t: t[1])
    starts: list[tuple[Array, float, str | None]] = []
    if family_of(robot) is not None:
        per: dict[str, int] = {}
        for q, c in scored:
            k = config_of(robot, q)
            if per.get(k, 0) < NG_STARTS_PER_CONFIG and math.isfinite(c):
                per[k] = per.get(k, 0) + 1
                starts.append((q, c, k))
    else:
        for q, c in scored:
            if len(starts) >= NG_GENERIC_STARTS or not math.isfinite(c):
                break
            if all(np.max(np.abs(q - s[0])) > NG_MIN_SEPARATION for s in starts):
                starts.append((q, c, None))
    starts.sort(key=lambda t: t[1])
    ctx = NewtonGaussContext(starts=starts, length=length)
    _NG_CACHE[robot] = ctx
    return ctx


@dataclass
class _NGProblem:
    chain: Robot
    lo: Array
    hi: Array
    length: float
    tol_p: float
    tol_o: float
    max_iterations: int

    def iterate(
        self, q: Array, T_target: Array, tol_p: float, tol_o: float, max_iterations: int
    ) -> tuple[Array, float, float, int]:
        """Damped Newton-Gauss on the 7 equations; returns (best q, ep m, eo rad, iterations).

        Step: ``(Jf^T Jf + lambda I) dq = -Jf^T f`` with ``lambda = NG_LM |f|^2`` (vanishes
        at convergence), scaled to at most ``NG_MAX_STEP`` per joint, then clipped to the
        limits. Stops when converged, when the step vanishes or after ``STALL_WINDOW``
        iterations without a ``STALL_IMPROVEMENT`` relative improvement.
        """
        length, eye = self.length, np.eye(self.chain.dof)
        f, Jf, T = _ng_equations(self.chain, q, T_target, length)
        ep, eo = _pose_errors(T, T_target)
        best = (q, ep, eo)
        best_merit = ep + length * eo
        last_improvement = 0
        it = 0
        for it in range(1, max_iterations + 1):
            if ep <= tol_p and eo <= tol_o:
                return q, ep, eo, it - 1
            lam = NG_LM * float(f @ f) + 1e-12
            H, g = Jf.T @ Jf + lam * eye, -(Jf.T @ f)
            dq = np.linalg.solve(H, g)
            # joints at a limit that the step pushes outward are held (one active-set pass)
            held = ((q <= self.lo) & (dq < 0)) | ((q >= self.hi) & (dq > 0))
            if held.any():
                free = ~held
                dq = np.zeros_like(dq)
                if free.any():
                    dq[free] = np.linalg.solve(H[np.ix_(free, free)], g[free])
            m = float(np.max(np.abs(dq)))
            if m > NG_MAX_STEP:
                dq *= NG_MAX_STEP / m
            q = np.clip(q + dq, self.lo, self.hi)
            f, Jf, T = _ng_equations(self.chain, q, T_target, length)
            ep, eo = _pose_errors(T, T_target)
            merit = ep + length * eo
            if merit < best_merit:
                if merit < (1.0 - STALL_IMPROVEMENT) * best_merit:
                    last_improvement = it
                best_merit, best = merit, (q, ep, eo)
            if m < STEP_EPS or it - last_improvement >= STALL_WINDOW:
                break
        if ep <= tol_p and eo <= tol_o:
            return q, ep, eo, it
        return best[0], best[1], best[2], it

    def path(self, q_start: Array, T_target: Array, seed: str) -> _Attempt:
        """Continuation from q_start's pose to T_target in k steps, then polish.

        k makes each step move the target at most ``NG_STEP_POSITION`` m and
        ``NG_STEP_ANGLE`` rad; each intermediate pose gets ``NG_STEP_ITERATIONS``
        iterations warm-started from the previous solution. A step that ends far from its
        pose means the path was lost (a limit or singularity); the polish then starts
        from there and usually fails, and the caller moves on to the next start.
        """
        T0, _ = self.chain.pose_jacobian(q_start)
        dp, da = _pose_errors(T0, T_target)
        k = max(1, math.ceil(max(dp / NG_STEP_POSITION, da / NG_STEP_ANGLE)))
        q, total = q_start.copy(), 0
        step_tol_p, step_tol_o = 1e-3 * NG_STEP_POSITION, 1e-3 * NG_STEP_ANGLE
        for T_k in _interpolate_poses(T0, T_target, k)[:-1]:
            q, ep, eo, its = self.iterate(q, T_k, step_tol_p, step_tol_o, NG_STEP_ITERATIONS)
            total += its
            if ep > NG_STEP_POSITION or eo > NG_STEP_ANGLE:
                break
        q, ep, eo, its = self.iterate(q, T_target, self.tol_p, self.tol_o, self.max_iterations)
        total += its
        status = "converged" if (ep <= self.tol_p and eo <= self.tol_o) else "stalled"
        return _Attempt(q, ep, eo, total, status, seed)


def _interpolate_poses(T0: Array, T1: Array, k: int) -> Array:
    """k poses (k, 4, 4) from T0 (excluded) to T1 (included): linear position, SLERP rotation."""
    s = np.arange(1, k + 1) / k
    rv = Rotation.from_matrix(T0[:3, :3].T @ T1[:3, :3]).as_rotvec()
    out = np.zeros((k, 4, 4))
    out[:, :3, :3] = T0[:3, :3] @ Rotation.from_rotvec(s[:, None] * rv).as_matrix()
    out[:, :3, 3] = T0[:3, 3] + s[:, None] * (T1[:3, 3] - T0[:3, 3])
    out[:, 3, 3] = 1.0
    out[-1] = T1
    return out


def _solve_newton_gauss(
    robot: Robot,
    T_target: Array,
    q0: Array | None,
    config: str | None,
    tol_p: float,
    tol_o: float,
    max_iterations: int,
    restarts: int,
    rng: np.random.Generator,
) -> IKSolution:
    ctx = newton_gauss_context(robot)
    problem = _NGProblem(robot, robot.lower, robot.upper, ctx.length, tol_p, tol_o, max_iterations)
    gap = _reach_gap(robot, T_target)
    budget = min(restarts, UNREACHABLE_RESTARTS) if gap > tol_p else restarts
    # Smallest condition number first; the requested configuration's starts (or else those
    # of q0's configuration, so the answer stays on the caller's branch) before the others.
    prefer = config or (
        config_of(robot, q0) if q0 is not None and family_of(robot) is not None else None
    )
    starts = sorted(ctx.starts, key=lambda s: (prefer is not None and s[2] != prefer, s[1]))
    if q0 is not None:  # the caller's q0 after the well-conditioned starts
        starts.append((q0, math.nan, None))

    def tries() -> Iterator[tuple[_Attempt, bool]]:
        for i in range(budget + 1):
            if i < len(starts):
                q_s, kind = starts[i][0], f"start {i} (condition number {starts[i][1]:.3g})"
            else:
                q_s, kind = _random_q(robot, rng), "random"
            yield problem.path(q_s, T_target, kind), i >= len(starts)

    return best_of_attempts(
        robot,
        T_target,
        tries(),
        config=config,
        tol_p=tol_p,
        tol_o=tol_o,
        method="newton-gauss",
        length=ctx.length,
        closest=gap > tol_p,
        closed=None,
        gap=gap,
    )
