"""mink differential IK for :mod:`workcell.robots.ik_numeric` (see its docstring)."""

from __future__ import annotations

import threading
import weakref
from collections.abc import Iterator
from dataclasses import dataclass, field

import mink
import mujoco
import numpy as np

from workcell.errors import KinematicsError
from workcell.robots.ik_closed import config_of
from workcell.robots.ik_common import (
    STALL_IMPROVEMENT,
    STALL_WINDOW,
    STEP_EPS,
    UNREACHABLE_RESTARTS,
    Array,
    _Attempt,
    _closed_form_seeds,
    _length_scale,
    _random_q,
    _reach_gap,
    best_of_attempts,
)
from workcell.robots.ik_newton import newton_gauss_context
from workcell.robots.mjcf import TOOL_SITE, kinematic_model
from workcell.robots.robot import IKSolution, Robot
from workcell.spatial import angle_between

__all__ = ["MinkContext", "mink_context"]

# mink settings (notes/mink.md §3, §7): lm_damping scales with the squared error, so it
# vanishes at convergence but keeps unreachable and near-singular targets from thrashing.
MINK_SOLVER = "daqp"
MINK_LM_DAMPING = 0.1
MINK_DAMPING = 1e-12
# Redundant arms (more than 6 joints): a posture task pulls the self-motion towards the
# attempt's start q; it is dropped once the pose is within POSTURE_HANDOFF (m and rad),
# so the last iterations reach the exact pose without trading it against the posture.
POSTURE_COST = 1e-2
POSTURE_HANDOFF = 1e-3


# ---------------------------------------------------------------------------------- mink
@dataclass(eq=False)
class MinkContext:
    """Everything mink needs for one robot, built once and reused by every solve.

    ``model`` the kinematic MjModel (joint i = ``robot.joints[i]``, site ``"tool"``);
    ``configuration`` its mink Configuration (holds its own MjData); ``task`` the
    FrameTask on the tool site; ``posture`` a PostureTask for redundant arms (None
    otherwise); ``limits`` the prebuilt ``[ConfigurationLimit]``; ``lock`` serialises
    solves (the Configuration is shared).
    """

    model: mujoco.MjModel
    configuration: mink.Configuration
    task: mink.FrameTask
    limits: list[mink.ConfigurationLimit]
    site_id: int
    length: float
    posture: mink.PostureTask | None = None
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
        posture=mink.PostureTask(model, cost=POSTURE_COST) if robot.dof > 6 else None,
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
    its step vanishes. A redundant arm's posture task (target: the solve's q0, set by
    the caller) acts until the pose is within ``POSTURE_HANDOFF``, or until the attempt
    stalls or its step vanishes with it: the posture then holds the pose away from the
    target (its pull balances the frame task's, often at ~1e-3 m near joint limits), so
    the attempt continues without it instead of ending (this lifted the success of a
    Panda on random reachable targets from 76 % to 100 %: see scripts/bench_kinematics.py).
    """
    task, length = ctx.task, ctx.length
    cfg, data, sid = ctx.configuration, ctx.configuration.data, ctx.site_id
    p_t, R_t = T_target[:3, 3], T_target[:3, :3]
    task.set_target(mink.SE3.from_matrix(T_target))
    cfg.update(np.clip(q_start, robot.lower, robot.upper))
    posture = ctx.posture  # its target was set by the solve (its q0)

    def errors() -> tuple[float, float]:
        p = data.site_xpos[sid]
        R = data.site_xmat[sid].reshape(3, 3)
        return float(np.linalg.norm(p - p_t)), angle_between(R, R_t)

    ep, eo = errors()
    best = _Attempt(cfg.q, ep, eo, 0, "iteration limit", seed)
    best_merit = ep + length * eo
    last_improvement = 0
    for it in range(1, max_iterations + 1):
        if ep <= tol_p and eo <= tol_o:
            return _Attempt(cfg.q, ep, eo, it - 1, "converged", seed)
        far = ep > POSTURE_HANDOFF or eo > POSTURE_HANDOFF
        tasks = [task, posture] if posture is not None and far else [task]
        try:
            dq = mink.solve_ik(
                cfg, tasks, 1.0, MINK_SOLVER, damping=MINK_DAMPING, limits=ctx.limits
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
        stalled = it - last_improvement >= STALL_WINDOW
        vanished = float(np.max(np.abs(dq))) < STEP_EPS and not (ep <= tol_p and eo <= tol_o)
        if posture is not None and (stalled or vanished):
            # the posture holds the pose off the target: converge without it from here
            posture, last_improvement = None, it
            continue
        if vanished:
            best.status = "step vanished"
            return best
        if stalled:
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
        if config_of(robot, q) == config:
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
    seeds = _mink_seeds(robot, q_start, closed, config, budget, rng)
    with ctx.lock:  # the attempts share the cached Configuration
        if ctx.posture is not None:  # a redundant arm prefers the self-motion nearest q0
            ctx.posture.set_target(np.clip(q_start, robot.lower, robot.upper))
        return best_of_attempts(
            robot,
            T_target,
            (
                (
                    _mink_attempt(ctx, robot, q, T_target, tol_p, tol_o, max_iterations, kind),
                    kind == "random",
                )
                for q, kind in seeds
            ),
            config=config,
            tol_p=tol_p,
            tol_o=tol_o,
            method="mink",
            length=ctx.length,
            closest=out_of_reach,
            closed=closed,
            gap=gap,
        )
