"""Shared parts of the numerical IK solvers: errors, reach, seeds, attempts, results."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.errors import KinematicsError
from workcell.robots.axes import max_reach
from workcell.robots.ik_closed import config_of, family_of, ik_all, wrist_sine
from workcell.robots.robot import IKSolution, Robot
from workcell.spatial import angle_between

__all__ = ["max_reach", "position_gradient_hessian"]

Array = NDArray[np.float64]
Method = Literal["mink", "newton-gauss"]

# mink settings (notes/mink.md §3, §7): lm_damping scales with the squared error, so it
# vanishes at convergence but keeps unreachable and near-singular targets from thrashing.
DEFAULT_MAX_ITERATIONS = {"mink": 60, "newton-gauss": 60}
DEFAULT_RESTARTS = {"mink": 20, "newton-gauss": 20}
# Restarts when the target is certainly out of reach (no closed-form solution, or farther
# than the reach bound): enough to find the closest pose, not a full search.
UNREACHABLE_RESTARTS = 2
STALL_WINDOW = 6  # iterations without a 5 % improvement of the best error
STALL_IMPROVEMENT = 0.05
POLISH_ITERATIONS = 100  # Newton iterations of the closest-position polish
STEP_EPS = 1e-12  # rad or m: a vanished step
LIMIT_TOL = 1e-6  # rad or m: "at a joint limit"

_CONFIG_LETTERS = ("lr", "ud", "nf")


# ------------------------------------------------------------------------------- helpers
def _pose_errors(T: Array, T_target: Array) -> tuple[float, float]:
    return (
        float(np.linalg.norm(T[:3, 3] - T_target[:3, 3])),
        angle_between(T[:3, :3], T_target[:3, :3]),
    )


def _reach_gap(robot: Robot, T_target: Array) -> float:
    """Lower bound (m) on the position error of any q: distance beyond :func:`max_reach`."""
    p = np.linalg.solve(robot.base, T_target[:, 3])[:3]
    return float(np.linalg.norm(p)) - max_reach(robot)


def _check_config(robot: Robot, config: str | None) -> str | None:
    if config is None:
        return None
    if family_of(robot) is None:
        raise KinematicsError(
            f"robot '{robot.name}': config {config!r} applies to robots with a closed-form "
            "family (OPW or UR) only; this one has none"
        )
    c = str(config).lower()
    if len(c) != 3 or any(
        ch not in allowed for ch, allowed in zip(c, _CONFIG_LETTERS, strict=True)
    ):
        raise KinematicsError(
            f"config must be three letters: arm l|r, elbow u|d, wrist n|f (e.g. 'lun'), got {config!r}"
        )
    return c


def _closed_form_seeds(
    robot: Robot, T_target: Array, q_near: Array
) -> tuple[list[tuple[Array, str | None]], bool] | None:
    """Closed-form solutions (OPW, UR) as (q within limits, config), nearest to q_near first.

    Returns ``(seeds, any_solution)`` where ``any_solution`` says whether the closed form
    found the pose geometrically reachable (limits aside), or None when no closed-form
    solver is available for this robot.
    """
    if family_of(robot) is None:
        return None
    try:
        sols = list(ik_all(robot, T_target, q_near))
    except KinematicsError:
        return None
    seeds: list[tuple[Array, str | None]] = []
    for s in sols:
        q = np.asarray(s.q, dtype=np.float64)
        if not np.all(np.isfinite(q)):
            continue
        qw = q if robot.within_limits(q) else robot.wrap_to_limits(q, near=q_near)
        if qw is None:
            continue
        seeds.append((qw, s.config))
    seeds.sort(key=lambda qc: float(np.sum((qc[0] - q_near) ** 2)))
    return seeds, bool(sols)


def _default_q0(robot: Robot) -> Array:
    if "home" in robot.poses:
        return robot.pose("home")
    return 0.5 * (robot.lower + robot.upper)


def _start(robot: Robot, q0: ArrayLike | None) -> Array:
    if q0 is None:
        return _default_q0(robot)
    q = np.asarray(q0, dtype=np.float64)
    if q.shape != (robot.dof,) or not np.all(np.isfinite(q)):
        raise KinematicsError(
            f"robot '{robot.name}': q0 must be {robot.dof} finite numbers, got {q0!r}"
        )
    if robot.within_limits(q):
        return q.copy()
    w = robot.wrap_to_limits(q)
    return w if w is not None else np.clip(q, robot.lower, robot.upper)


def _random_q(robot: Robot, rng: np.random.Generator) -> Array:
    return rng.uniform(robot.lower, robot.upper)


def _at_limits(robot: Robot, q: Array) -> list[str]:
    span = robot.upper - robot.lower
    near = (q - robot.lower <= LIMIT_TOL * np.maximum(span, 1)) | (
        robot.upper - q <= LIMIT_TOL * np.maximum(span, 1)
    )
    return [robot.joints[i].name for i in np.flatnonzero(near)]


def _length_scale(robot: Robot) -> float:
    """Characteristic length (m) to weigh orientation against position: half the reach bound."""
    return max(0.5 * max_reach(robot), 1e-3)


@dataclass
class _Attempt:
    q: Array
    position_error: float
    orientation_error: float
    iterations: int
    status: str  # "converged", "stalled", "step vanished", "iteration limit", "qp failed"
    seed: str  # "q0", "closed form", "random", "start ..."

    def merit(self, length: float) -> float:
        return self.position_error + length * self.orientation_error


def position_gradient_hessian(
    robot: Robot, q: ArrayLike, p_target: ArrayLike
) -> tuple[float, Array, Array]:
    """``g(q) = 1/2 |p(q) - p_target|^2`` (m^2), its gradient and exact Hessian in q.

    Gradient ``J_v^T e`` with ``e = p - p_target``. Hessian ``J_v^T J_v + sum_k e_k
    d^2 p_k / dq^2``, where for joints a <= b ``d J_b / d q_a = z_a x J_b`` when joint a
    is revolute (it turns everything after it) and 0 when prismatic; J_b the linear
    Jacobian column, z_a joint a's axis.
    """
    q = np.asarray(q, dtype=np.float64)
    return _position_objective(robot, q, np.asarray(p_target, dtype=np.float64))


def _position_objective(chain: Robot, q: Array, p_t: Array) -> tuple[float, Array, Array]:
    T, J = chain.pose_jacobian(q)
    z = np.where(chain.revolute[:, None], J[3:].T, J[:3].T)  # joint axes (n, 3)
    Jv = J[:3]
    e = T[:3, 3] - p_t
    ez = np.cross(e, z)  # (n, 3): e x z_a, so (e x z_a) . J_b = e . (z_a x J_b)
    C = ez @ Jv  # C[a, b] = e . (z_a x J_b)
    C[~chain.revolute, :] = 0.0
    upper = np.triu(C)
    H = Jv.T @ Jv + upper + np.triu(upper, 1).T
    return 0.5 * float(e @ e), Jv.T @ e, H


def _closest_position(robot: Robot, attempts: Sequence[_Attempt], T_target: Array) -> _Attempt:
    """Polish an unreachable target's attempts to the closest tool position; the best one.

    From the end of every attempt, minimises ``1/2 |p(q) - p_target|^2`` over the joint
    box by projected Newton steps with the exact Hessian (Levenberg-Marquardt safeguarded:
    a step is kept only if it lowers the objective; joints at a limit that the step
    pushes outward are held). Returns the attempt with the smallest position error, and
    among those within 1 nm of it the smallest orientation error.
    Gauss-Newton steps (mink, Newton-Gauss) converge poorly here: at the optimum the
    residual is large and the arm stretched, so the neglected second-order term
    dominates. Several starts guard against a local minimum against a joint limit.
    """
    p_t = T_target[:3, 3]
    chain = robot
    lo, hi = robot.lower, robot.upper
    eye = np.eye(robot.dof)
    found = list(attempts)
    for a in attempts:
        q = np.clip(a.q, lo, hi)
        f, g, H = _position_objective(chain, q, p_t)
        mu = 1e-6
        for _ in range(POLISH_ITERATIONS):
            held = ((q <= lo) & (g > 0)) | ((q >= hi) & (g < 0))
            free = ~held
            if not free.any() or float(np.max(np.abs(g[free]))) < 1e-13:
                break
            Hf = H[np.ix_(free, free)]
            shift = max(0.0, -float(np.linalg.eigvalsh(Hf)[0])) + mu
            dq = np.zeros_like(q)
            dq[free] = np.linalg.solve(Hf + shift * eye[: free.sum(), : free.sum()], -g[free])
            q_new = np.clip(q + dq, lo, hi)
            f_new, g_new, H_new = _position_objective(chain, q_new, p_t)
            if f_new < f:
                converged = f - f_new <= 1e-15 * max(f, 1e-300)
                q, f, g, H, mu = q_new, f_new, g_new, H_new, max(mu / 4, 1e-12)
                if converged:
                    break
            else:
                mu *= 8
                if mu > 1e6:
                    break
        ep, eo = _pose_errors(chain.pose_jacobian(q)[0], T_target)
        found.append(_Attempt(q, ep, eo, a.iterations, "closest position", a.seed))
    # the closest position; among equally close ones (1 nm) the best orientation
    closest = min(a.position_error for a in found)
    return min(
        (a for a in found if a.position_error <= closest + 1e-9),
        key=lambda a: a.orientation_error,
    )


# ---------------------------------------------------------------------- common endings
def _finish(
    robot: Robot,
    T_target: Array,
    a: _Attempt,
    config: str | None,
    tol_p: float,
    tol_o: float,
    iterations: int,
    method: str,
    reason: str | None = None,
) -> IKSolution:
    """Verify attempt ``a`` with the DH forward kinematics and build the IKSolution."""
    q = np.clip(a.q, robot.lower, robot.upper)
    ep, eo = _pose_errors(robot.fk(q), T_target)
    cfg = config_of(robot, q) if family_of(robot) is not None else None
    sine = wrist_sine(robot, q)
    singular = sine is not None and sine < 1e-3
    ok = ep <= tol_p and eo <= tol_o and (config is None or cfg == config)
    if not ok and reason is None:
        if ep > tol_p or eo > tol_o:
            reason = f"not converged: position error {ep:.3g} m, orientation error {eo:.3g} rad"
        else:
            reason = f"reached the pose in configuration '{cfg}', not the requested '{config}'"
    return IKSolution(
        q=q,
        success=ok,
        config=cfg,
        within_limits=True,
        singular=singular,
        position_error=ep,
        orientation_error=eo,
        iterations=iterations,
        reason="" if ok else str(reason),
        method=method,
    )


def _failure_reason(
    robot: Robot,
    best: _Attempt,
    attempts: list[_Attempt],
    config: str | None,
    rejected_configs: list[str],
    n_random: int,
    closed: tuple[list[tuple[Array, str | None]], bool] | None,
    gap: float,
    tol_p: float,
) -> str:
    n = len(attempts)
    errs = f"best position error {best.position_error:.3g} m, orientation error {best.orientation_error:.3g} rad"
    tries = f"after {n} attempts ({n_random} random restarts)"
    if gap > tol_p:
        return f"unreachable: the target is at least {gap:.3g} m beyond the robot's reach; {errs} {tries}"
    if closed is not None and not closed[1]:
        return f"unreachable: the pose is outside the workspace (closed form has no solution); {errs} {tries}"
    if closed is not None and config is not None and all(c != config for _, c in closed[0]):
        have = ", ".join(sorted({str(c) for _, c in closed[0]})) or "none"
        return (
            f"no solution in configuration '{config}' within the joint limits (closed-form "
            f"solutions within the limits: {have}); {errs} {tries}"
        )
    if config is not None and rejected_configs:
        got = ", ".join(sorted(set(rejected_configs)))
        return f"no solution in configuration '{config}' (reached the pose only as {got}); {errs} {tries}"
    if closed is not None and not closed[0]:
        return f"unreachable within the joint limits (every closed-form solution is outside them); {errs} {tries}"
    why = f"no solution found (the pose may be unreachable): {errs} {tries}"
    pinned = _at_limits(robot, best.q)
    if pinned and all(a.status != "converged" for a in attempts):
        why += f"; stalled at joint limits ({', '.join(pinned)})"
    elif best.status in ("stalled", "step vanished"):
        why += f"; {best.status}"
    return why


def best_of_attempts(
    robot: Robot,
    T_target: Array,
    attempts_iter: Iterator[tuple[_Attempt, bool]],
    *,
    config: str | None,
    tol_p: float,
    tol_o: float,
    method: str,
    length: float,
    closest: bool,
    closed: object,
    gap: float,
) -> IKSolution:
    """Run attempts (each with whether it came from a random seed) until one succeeds.

    The first converged attempt that passes :func:`_finish` (pose, limits, configuration)
    is the answer. Otherwise the best attempt (least ``position + length * orientation``
    error, or the closest position when ``closest``) is returned with ``success=False``
    and the reason. Iterations are summed over all attempts.
    """
    attempts: list[_Attempt] = []
    rejected: list[str] = []
    total = n_random = 0
    for a, is_random in attempts_iter:
        n_random += is_random
        total += a.iterations
        attempts.append(a)
        if a.status == "converged":
            sol = _finish(robot, T_target, a, config, tol_p, tol_o, total, method)
            if sol.success:
                return sol
            if sol.config is not None and config is not None and sol.config != config:
                rejected.append(sol.config)
    best = min(attempts, key=lambda a: a.merit(length))
    if closest:
        best = _closest_position(robot, attempts, T_target)
    reason = _failure_reason(robot, best, attempts, config, rejected, n_random, closed, gap, tol_p)
    return _finish(robot, T_target, best, config, tol_p, tol_o, total, method, reason)
