"""Numerical inverse kinematics (thesis §4.3): mink differential IK and the thesis's Newton-Gauss.

:func:`solve` is what :meth:`Robot.ik <workcell.robots.robot.Robot.ik>` calls. It never
returns a silently wrong q: a result has ``success=True`` only when ``robot.fk(q)`` (the
DH forward kinematics, not the solver's own model) is within ``tol_position`` (m) and
``tol_orientation`` (rad) of the target, q lies within the joint limits and, when
``config`` is given, q has that Puma configuration. Otherwise ``success=False`` with the
closest pose reached (q of the best attempt, always finite and within the limits), its
errors and a ``reason``.

Two methods:

- ``"mink"``: mink 1.3 differential IK on :func:`~workcell.robots.mjcf.kinematic_model`,
  one ``FrameTask`` on the ``"tool"`` site (position and orientation cost 1,
  ``lm_damping``), the daqp QP backend, a prebuilt ``ConfigurationLimit`` (exact limits),
  tiny global damping and no posture task (see ``/work/shared/notes/mink.md``, P1-P5).
  Attempts, in order: ``q0``; for the Puma family the closed-form solutions nearest to
  ``q0`` (``workcell.robots.ik_closed.puma_ik``, when that module exists), filtered by
  ``config``; then seeded random in-limit configurations. An attempt ends when converged,
  when the error stops improving over a window of iterations, or when the step vanishes.
- ``"newton-gauss"``: the thesis's solver. Seven equations in n unknowns: position (3), the
  vector invariant of the rotation error ``E = R_target R^T`` (3,
  ``vect(E) = 1/2 (e32 - e23, e13 - e31, e21 - e12) = sin(theta) k``) and its trace (1,
  ``(trace(E) - 3) / 2 = cos(theta) - 1``), solved in the least-squares sense with the
  analytic 7xn Jacobian, Levenberg-Marquardt damped. Robustness as in the thesis: start
  from the configuration whose Jacobian condition number is smallest (one per Puma
  configuration, or a spread of well-conditioned samples for other robots), follow a
  continuation path from that start's pose to the target (linear position, SLERP
  orientation) solving each step from the previous one, then polish. Joint limits: each
  step is clipped to the limits, and joints at a limit that the step pushes outward are
  held while the others are re-solved (one active-set pass). Failed paths restart from
  the next candidate start (starts of the requested configuration, or of q0's, first).

Unreachable targets (farther than :func:`max_reach`, or with no closed-form solution) get
a reduced restart budget; the attempts are then polished to the closest tool position
(exact-Hessian projected Newton on ``1/2 |p(q) - p_target|^2``), so ``position_error``
is the distance from the target to the reachable workspace (a local minimum in
principle; the global one on every case tested). Stalled attempts (limits, branches)
that are not provably unreachable keep the attempt of least ``position + length *
orientation`` error (``length`` = half the reach bound, m/rad).

Errors: position error in m (Euclidean distance of the tool points), orientation error
in rad (angle of ``R_current^T R_target``). The caches (mink model, configuration, tasks,
limits; Newton-Gauss start candidates) are built once per robot object and reused.
"""

from __future__ import annotations

import math
import threading
import weakref
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Literal

import mink
import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from workcell.errors import GeometryError, KinematicsError
from workcell.robots.ik_closed import puma_config, puma_ik
from workcell.robots.mjcf import TOOL_SITE, kinematic_model
from workcell.robots.robot import IKSolution, Robot
from workcell.spatial import as_transform

__all__ = [
    "MinkContext",
    "NewtonGaussContext",
    "max_reach",
    "mink_context",
    "newton_gauss_context",
    "ng_residual_jacobian",
    "orientation_error",
    "position_gradient_hessian",
    "puma_config",
    "solve",
]

Array = NDArray[np.float64]
Method = Literal["mink", "newton-gauss"]

# mink settings (notes/mink.md §3, §7): lm_damping scales with the squared error, so it
# vanishes at convergence but keeps unreachable and near-singular targets from thrashing.
MINK_SOLVER = "daqp"
MINK_LM_DAMPING = 0.1
MINK_DAMPING = 1e-12

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
def orientation_error(R: ArrayLike, R_target: ArrayLike) -> float:
    """Angle (rad, in [0, pi]) of ``R^T R_target``, accurate to ~1e-16 for small angles."""
    M = np.asarray(R).T @ np.asarray(R_target)
    s = 0.5 * math.sqrt(
        (M[2, 1] - M[1, 2]) ** 2 + (M[0, 2] - M[2, 0]) ** 2 + (M[1, 0] - M[0, 1]) ** 2
    )
    c = 0.5 * (M[0, 0] + M[1, 1] + M[2, 2] - 1.0)
    return math.atan2(s, c)


def _pose_errors(T: Array, T_target: Array) -> tuple[float, float]:
    return (
        float(np.linalg.norm(T[:3, 3] - T_target[:3, 3])),
        orientation_error(T[:3, :3], T_target[:3, :3]),
    )


def max_reach(robot: Robot) -> float:
    """Upper bound (m) on the distance from the origin of frame 0 (``robot.base``) to the tool point.

    Sum over the DH rows of the largest translation each row can make (``sqrt(a^2 + d^2)``,
    with d over its limits for a prismatic joint) plus the tool offset. Any target farther
    than this is out of reach whatever the joint limits.
    """
    r = 0.0
    for j in robot.joints:
        if j.kind == "prismatic":
            d = max(abs(j.limits[0] + j.offset), abs(j.limits[1] + j.offset))
        else:
            d = abs(j.d)
        r += math.hypot(j.a, d)
    return r + float(np.linalg.norm(robot.tool[:3, 3]))


def _reach_gap(robot: Robot, T_target: Array) -> float:
    """Lower bound (m) on the position error of any q: distance beyond :func:`max_reach`."""
    p = np.linalg.solve(robot.base, T_target[:, 3])[:3]
    return float(np.linalg.norm(p)) - max_reach(robot)


def _check_config(robot: Robot, config: str | None) -> str | None:
    if config is None:
        return None
    if robot.family != "puma":
        raise KinematicsError(
            f"robot '{robot.name}': config {config!r} applies to the Puma family only "
            f"(family is {robot.family!r})"
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
    """Closed-form solutions of a Puma as (q within limits, config), nearest to q_near first.

    Returns ``(seeds, any_solution)`` where ``any_solution`` says whether the closed form
    found the pose geometrically reachable (limits aside), or None when no closed-form
    solver is available for this robot.
    """
    if robot.family != "puma":
        return None
    try:
        sols = list(puma_ik(robot, T_target, q_near))
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


# ---------------------------------------------------------------------------------- mink
@dataclass(eq=False)
class MinkContext:
    """Everything mink needs for one robot, built once and reused by every solve.

    ``model`` the kinematic MjModel (joint i = ``robot.joints[i]``, site ``"tool"``);
    ``configuration`` its mink Configuration (holds its own MjData); ``task`` the
    FrameTask on the tool site; ``limits`` the prebuilt
    ``[ConfigurationLimit]``; ``lock`` serialises solves (the Configuration is shared).
    """

    model: mujoco.MjModel
    configuration: mink.Configuration
    task: mink.FrameTask
    limits: list[mink.ConfigurationLimit]
    site_id: int
    length: float
    lock: threading.Lock = field(default_factory=threading.Lock)


_MINK_CACHE: weakref.WeakKeyDictionary[Robot, MinkContext] = weakref.WeakKeyDictionary()


def mink_context(robot: Robot) -> MinkContext:
    """The cached :class:`MinkContext` of ``robot`` (rebuilt only if its kinematics changed)."""
    ctx = _MINK_CACHE.get(robot)
    if ctx is not None:
        return ctx
    model = kinematic_model(robot)
    if model.nq != robot.dof or model.nv != robot.dof:
        raise KinematicsError(
            f"robot '{robot.name}': kinematic model has nq={model.nq}, expected {robot.dof}"
        )
    cfg = mink.Configuration(model)
    task = mink.FrameTask(
        TOOL_SITE, "site", position_cost=1.0, orientation_cost=1.0, lm_damping=MINK_LM_DAMPING
    )
    site_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, TOOL_SITE)
    ctx = MinkContext(
        model=model,
        configuration=cfg,
        task=task,
        limits=[mink.ConfigurationLimit(model)],
        site_id=site_id,
        length=_length_scale(robot),
    )
    _MINK_CACHE[robot] = ctx
    return ctx


def _mink_attempt(
    ctx: MinkContext,
    robot: Robot,
    q_start: Array,
    T_target: Array,
    tol_p: float,
    tol_o: float,
    max_iterations: int,
    seed: str,
) -> _Attempt:
    """Iterate solve_ik from q_start until converged, stalled or out of iterations.

    An attempt stalls when its best error ``position + length * orientation`` has not
    improved by ``STALL_IMPROVEMENT`` (relative) for ``STALL_WINDOW`` iterations, or when
    its step vanishes.
    """
    task, length = ctx.task, ctx.length
    cfg, data, sid = ctx.configuration, ctx.configuration.data, ctx.site_id
    p_t, R_t = T_target[:3, 3], T_target[:3, :3]
    task.set_target(mink.SE3.from_matrix(T_target))
    cfg.update(np.clip(q_start, robot.lower, robot.upper))

    def errors() -> tuple[float, float]:
        p = data.site_xpos[sid]
        R = data.site_xmat[sid].reshape(3, 3)
        return float(np.linalg.norm(p - p_t)), orientation_error(R, R_t)

    ep, eo = errors()
    best = _Attempt(cfg.q, ep, eo, 0, "iteration limit", seed)
    best_merit = ep + length * eo
    last_improvement = 0
    for it in range(1, max_iterations + 1):
        if ep <= tol_p and eo <= tol_o:
            return _Attempt(cfg.q, ep, eo, it - 1, "converged", seed)
        try:
            dq = mink.solve_ik(
                cfg, [task], 1.0, MINK_SOLVER, damping=MINK_DAMPING, limits=ctx.limits
            )
        except mink.NoSolutionFound:
            best.status, best.iterations = "qp failed", it
            return best
        cfg.integrate_inplace(dq, 1.0)
        ep, eo = errors()
        merit = ep + length * eo
        if merit < best_merit:
            if merit < (1.0 - STALL_IMPROVEMENT) * best_merit:
                last_improvement = it
            best_merit = merit
            best = _Attempt(cfg.q, ep, eo, it, "iteration limit", seed)
        best.iterations = it
        if float(np.max(np.abs(dq))) < STEP_EPS and not (ep <= tol_p and eo <= tol_o):
            best.status = "step vanished"
            return best
        if it - last_improvement >= STALL_WINDOW:
            best.status = "stalled"
            return best
    if ep <= tol_p and eo <= tol_o:
        return _Attempt(cfg.q, ep, eo, max_iterations, "converged", seed)
    return best


def _random_q_in_config(
    robot: Robot, rng: np.random.Generator, config: str | None, tries: int = 64
) -> Array:
    """A random in-limit q, of configuration ``config`` when one is found in ``tries`` draws."""
    q = _random_q(robot, rng)
    if config is None:
        return q
    for _ in range(tries):
        if puma_config(robot, q) == config:
            return q
        q = _random_q(robot, rng)
    return q


def _mink_seeds(
    robot: Robot,
    q_start: Array,
    closed: tuple[list[tuple[Array, str | None]], bool] | None,
    config: str | None,
    budget: int,
    rng: np.random.Generator,
) -> Iterator[tuple[Array, str]]:
    """q0, then the closed-form solutions (of ``config`` when given), then random seeds.

    Without a closed form but with ``config``, the Newton-Gauss starts of that
    configuration (well-conditioned, cached) come before the random seeds, and the random
    seeds are drawn in that configuration.
    """
    yield q_start, "q0"
    if closed is not None:
        for q, c in closed[0]:
            if config is None or c is None or c == config:
                yield q, "closed form"
    elif config is not None:
        for q, _, c in newton_gauss_context(robot).starts:
            if c == config:
                yield q, "configuration start"
    for _ in range(budget):
        yield _random_q_in_config(robot, rng, config), "random"


def _solve_mink(
    robot: Robot,
    T_target: Array,
    q_start: Array,
    config: str | None,
    tol_p: float,
    tol_o: float,
    max_iterations: int,
    restarts: int,
    rng: np.random.Generator,
) -> IKSolution:
    ctx = mink_context(robot)
    closed = _closed_form_seeds(robot, T_target, q_start)
    gap = _reach_gap(robot, T_target)
    out_of_reach = gap > tol_p or (closed is not None and not closed[1])
    budget = restarts
    # the closed form is complete: no in-limit solution (of the configuration) is a proof
    if out_of_reach or (
        closed is not None and all(config is not None and c != config for _, c in closed[0])
    ):
        budget = min(budget, UNREACHABLE_RESTARTS)
    attempts: list[_Attempt] = []
    rejected_configs: list[str] = []
    total = n_random = 0
    with ctx.lock:
        for q_seed, kind in _mink_seeds(robot, q_start, closed, config, budget, rng):
            n_random += kind == "random"
            a = _mink_attempt(ctx, robot, q_seed, T_target, tol_p, tol_o, max_iterations, kind)
            total += a.iterations
            attempts.append(a)
            if a.status == "converged":
                sol = _finish(robot, T_target, a, config, tol_p, tol_o, total, "mink")
                if sol.success:
                    return sol
                if sol.config is not None and config is not None and sol.config != config:
                    rejected_configs.append(sol.config)
    best = min(attempts, key=lambda a: a.merit(ctx.length))
    if out_of_reach:
        best = _closest_position(robot, attempts, T_target)
    reason = _failure_reason(
        robot, best, attempts, config, rejected_configs, n_random, closed, gap, tol_p
    )
    return _finish(robot, T_target, best, config, tol_p, tol_o, total, "mink", reason)


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
    cfg = puma_config(robot, q) if robot.family == "puma" else None
    singular = robot.family == "puma" and abs(math.sin(q[4] + robot.joints[4].offset)) < 1e-3
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


# ------------------------------------------------------------------------- Newton-Gauss
@dataclass(eq=False)
class NewtonGaussContext:
    """Per-robot data of the Newton-Gauss solver, built once: the candidate start
    configurations sorted by the condition number of their weighted Jacobian (smallest
    first) and their configuration letters (Puma family) or None."""

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
    whose trace row vanishes there). Puma robots keep the best ``NG_STARTS_PER_CONFIG``
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
    if robot.family == "puma":
        per: dict[str, int] = {}
        for q, c in scored:
            k = puma_config(robot, q)
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
        puma_config(robot, q0) if q0 is not None and robot.family == "puma" else None
    )
    starts = sorted(ctx.starts, key=lambda s: (prefer is not None and s[2] != prefer, s[1]))
    if q0 is not None:  # the caller's q0 after the well-conditioned starts
        starts.append((q0, math.nan, None))
    attempts: list[_Attempt] = []
    rejected: list[str] = []
    total = 0
    n_random = 0
    for i in range(budget + 1):
        if i < len(starts):
            q_s, kind = starts[i][0], f"start {i} (condition number {starts[i][1]:.3g})"
        else:
            q_s, kind = _random_q(robot, rng), "random"
            n_random += 1
        a = problem.path(q_s, T_target, kind)
        total += a.iterations
        attempts.append(a)
        if a.status == "converged":
            sol = _finish(robot, T_target, a, config, tol_p, tol_o, total, "newton-gauss")
            if sol.success:
                return sol
            if sol.config is not None and config is not None and sol.config != config:
                rejected.append(sol.config)
    best = min(attempts, key=lambda a: a.merit(ctx.length))
    if gap > tol_p:
        best = _closest_position(robot, attempts, T_target)
    reason = _failure_reason(robot, best, attempts, config, rejected, n_random, None, gap, tol_p)
    return _finish(robot, T_target, best, config, tol_p, tol_o, total, "newton-gauss", reason)


# --------------------------------------------------------------------------------- entry
_VALID_OPTIONS = ("tol_position", "tol_orientation", "max_iterations", "restarts", "seed")


def solve(
    robot: Robot,
    T: ArrayLike,
    q0: ArrayLike | None = None,
    *,
    config: str | None = None,
    method: Method = "mink",
    tol_position: float = 1e-6,
    tol_orientation: float = 1e-6,
    max_iterations: int | None = None,
    restarts: int | None = None,
    seed: int = 0,
    **unknown: object,
) -> IKSolution:
    """Numerical IK: joint values placing ``robot``'s tool at pose ``T`` (4x4, base frame, m).

    ``q0`` (rad/m): for mink the first start (default: the robot's ``"home"`` pose, else
    mid-range); for Newton-Gauss, which starts where the Jacobian is best conditioned, the
    starts in q0's Puma configuration go first and q0 itself follows the listed starts;
    ``config`` restricts a Puma solution to a configuration such as ``"lun"``; ``method``
    ``"mink"`` or ``"newton-gauss"``; tolerances in m (``tol_position``, tool-point
    distance) and rad (``tol_orientation``, angle of ``R^T R_target``);
    ``max_iterations`` per attempt (per final polish for Newton-Gauss); ``restarts`` the
    number of extra starts (random seeds for mink, after ``q0`` and the closed-form
    seeds; further candidate starts for Newton-Gauss); ``seed`` for the random starts.

    Returns an :class:`IKSolution` whose ``success`` is verified against ``robot.fk``;
    on failure ``q`` is the closest pose reached (within the limits) and ``reason`` says
    why. Raises KinematicsError for bad input (unknown option or method, bad config
    letters, a non-rigid T).
    """
    if unknown:
        raise KinematicsError(
            f"unknown IK option(s) {', '.join(sorted(unknown))}; valid: config, method, "
            + ", ".join(_VALID_OPTIONS)
        )
    if method not in ("mink", "newton-gauss"):
        raise KinematicsError(f"unknown IK method {method!r}; valid: 'mink', 'newton-gauss'")
    try:
        T_target = as_transform(T, rigid=True, name="IK target")
    except GeometryError as exc:
        raise KinematicsError(str(exc)) from exc
    if not (tol_position > 0 and tol_orientation > 0):
        raise KinematicsError(
            f"tolerances must be > 0, got tol_position={tol_position}, tol_orientation={tol_orientation}"
        )
    iters = DEFAULT_MAX_ITERATIONS[method] if max_iterations is None else int(max_iterations)
    nrest = DEFAULT_RESTARTS[method] if restarts is None else int(restarts)
    if iters < 1 or nrest < 0:
        raise KinematicsError(
            f"max_iterations must be >= 1 and restarts >= 0, got {max_iterations}, {restarts}"
        )
    cfg = _check_config(robot, config)
    rng = np.random.default_rng(seed)
    q_start = _start(robot, q0)
    if method == "mink":
        return _solve_mink(
            robot, T_target, q_start, cfg, tol_position, tol_orientation, iters, nrest, rng
        )
    return _solve_newton_gauss(
        robot,
        T_target,
        None if q0 is None else q_start,
        cfg,
        tol_position,
        tol_orientation,
        iters,
        nrest,
        rng,
    )
