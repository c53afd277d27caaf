"""Timing a Cartesian path: the tool at its programmed speed, the joints within their limits.

:func:`timed_frames` (through :func:`time_path`) turns a
:class:`~workcell.sim.paths.CartesianPath` and its IK samples into a
:class:`~workcell.sim.pathlaw.PathMotion` and its frames:

1. joint samples (:func:`sample_params`, :func:`workcell.sim.cartesian.path_joints`): the
   path cut at most ``step`` (m, less on curved pieces) and 2 deg of turn apart, each
   sample solved by IK warm-started at the previous one (an unreachable sample or a joint
   jump raises UnreachableError saying where);
2. the exact joint path through them (:func:`~workcell.sim.pathlaw.joint_path`), with
   one more coordinate, the tool-point arc length l(s), so that the tool speed
   ``l' s_dot`` and tool acceleration are constraints like the joints' own (programmed
   values that may change along the path: across a blend);
3. toppra's time-optimal parameterization under the joints' speed and acceleration
   limits (:data:`JOINT_MARGIN` below them) and the tool's, with the constant-acceleration
   parametrizer (toppra's default spline output overshoots acceleration limits by
   ~10 %): the tool runs at the programmed speed wherever the joints allow and slows down
   where they do not (near a singularity) instead of breaking a limit;
4. checks: the joints' limits again between the knots (middles, and the quarters and
   next to the knots of intervals whose joint rates change fast); where one would be passed the
   points become knots and the path is timed again; then the frames themselves (finite
   differences) must keep the limits, else the path is timed again with the bounds
   tightened by the excess;
5. frames: at each frame's time the path parameter s(t) of the law, the exact pose on the
   path at s(t), and its IK to 1e-9 m and rad, so every frame lies on the path.

``import toppra`` costs ~1 s (it pulls in matplotlib): it happens at the first call.
"""

from __future__ import annotations

import functools
import logging
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell import limits as work_limits
from workcell.robots.robot import Robot
from workcell.sim.jerk import Limits
from workcell.sim.pathlaw import IK_TOL, JointPath, PathMotion, PathProfile, joint_path, refine_ik
from workcell.sim.paths import CartesianPath

__all__ = ["FRAME_CHECK_MAX", "JOINT_MARGIN", "sample_params", "time_path", "timed_frames"]

Array = NDArray[np.float64]
JOINT_MARGIN = 0.985  # toppra gets the joint limits times this (room between its knots)
_UNLIMITED = 1e6  # stands for "no limit" (inf) in toppra's constraints
_ANGLE_STEP = math.radians(2.0)
_MIN_GRID = 24


def sample_params(path: CartesianPath, step: float) -> Array:
    """Path parameters of the IK samples: each piece cut into equal parts at most
    ``step`` (m; a curved piece's own ``max_step`` if shorter) and 2 deg of turn long
    (the start included), and at least 24 of them in all (toppra's grid)."""
    kinds = {type(p).__name__ for p in path.pieces}
    what = {"Line": "line", "Arc": "arc"}.get(kinds.pop(), "path") if len(kinds) == 1 else "path"
    work_limits.check(
        "max_frames_per_command",
        path.span / step,
        f"a {path.span:.4g} m {what} sampled every {step:g} m",
    )
    step = min(step, path.span / (_MIN_GRID - 1)) if path.span > 0 else step
    counts = [
        max(
            1,
            math.ceil(p.span / min(step, p.max_step) - 1e-9),
            math.ceil(p.angle / _ANGLE_STEP - 1e-9),
        )
        for p in path.pieces
    ]
    work_limits.check(
        "max_path_samples",
        sum(counts),
        f"a {path.span:.4g} m {what} sampled every {step:g} m: IK solutions",
    )
    out = [np.zeros(1)]
    for k, (p, n) in enumerate(zip(path.pieces, counts, strict=True)):
        out.append(path.starts[k] + p.span * np.arange(1, n + 1) / n)
    return np.concatenate(out)


def _least_time(
    Q: Array,
    vj: Array,
    aj: Array,
    path: CartesianPath,
    speed: tuple[Array, Array] | None,
    acceleration: tuple[Array, Array] | None,
    from_rest: bool,
) -> float:
    """A lower bound (s) of any time law of the path: each joint's travel through the
    samples Q over its speed bound ``vj``, the path's length over the highest tool speed,
    and from rest to rest 2 sqrt(distance / acceleration) for the tool and each joint
    (inf when a bound underflowed to 0: an override of 1e-320)."""
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        travel = np.abs(np.diff(Q, axis=0)).sum(axis=0) if len(Q) > 1 else np.zeros(len(vj))
        bounds = [np.where(travel > 0, travel / vj, 0.0)]
        L = np.float64(path.span)
        if speed is not None and L > 0:
            bounds.append(L / np.max(speed[1]))
        if from_rest:
            net = np.abs(Q[-1] - Q[0]) if len(Q) > 1 else np.zeros(len(aj))
            bounds.append(np.where(net > 0, 2.0 * np.sqrt(net / aj), 0.0))
            if acceleration is not None and L > 0:
                bounds.append(2.0 * np.sqrt(L / np.max(acceleration[1])))
        t = max(float(np.max(b, initial=0.0)) for b in bounds)
    return t if t == t else math.inf


def _toppra() -> Any:
    import toppra

    logging.getLogger("toppra").setLevel(logging.ERROR)
    return toppra


@functools.cache
def _joint_constraints(v: tuple[float, ...], a: tuple[float, ...]) -> tuple[Any, Any]:
    """toppra's joint speed and acceleration constraints for bounds v, a (cached: making
    them prints the bounds into a description, ~1 ms)."""
    from toppra import constraint

    va, aa = np.array(v), np.array(a)
    return (
        constraint.JointVelocityConstraint(np.stack([-va, va], axis=1)),
        constraint.JointAccelerationConstraint(
            np.stack([-aa, aa], axis=1),
            discretization_scheme=constraint.DiscretizationType.Interpolation,
        ),
    )


def _tool_constraint(speed: Array, acceleration: Array) -> Any:
    """A toppra constraint on the path's last coordinate, the tool-point arc length l(s):
    ``|l' s_dot| <= speed`` and ``|l' s_ddot + l'' s_dot^2| <= acceleration``, both given
    per gridpoint (the programmed values, which change across a blend)."""
    c = _tool_constraint_class()()
    c.speed, c.acceleration = speed, acceleration
    return c


@functools.cache
def _tool_constraint_class() -> type:
    from toppra.constraint import DiscretizationType, LinearConstraint
    from toppra.constraint.linear_constraint import canlinear_colloc_to_interpolate

    class ToolConstraint(LinearConstraint):
        speed: Array
        acceleration: Array

        def __init__(self) -> None:
            super().__init__()
            self.set_discretization_type(DiscretizationType.Interpolation)

        def compute_constraint_params(self, path: Any, grid: Array, *args: Any, **kw: Any) -> Any:
            d1 = path(grid, 1)[:, -1:]
            d2 = path(grid, 2)[:, -1:]
            n = len(grid)
            F = np.repeat(np.array([[[1.0], [-1.0]]]), n, axis=0)
            speed, acceleration = self.speed, self.acceleration
            g = np.stack([acceleration, acceleration], axis=1)
            xb = np.zeros((n, 2))
            with np.errstate(divide="ignore"):
                xb[:, 1] = np.where(np.abs(d1[:, 0]) > 1e-12, (speed / np.abs(d1[:, 0])) ** 2, 1e12)
            a, b, c, F, g, _, _ = canlinear_colloc_to_interpolate(
                d1, d2, np.zeros_like(d1), F, g, None, None, grid, identical=False
            )
            return a, b, c, F, g, None, xb  # (..., ubound, xbound)

    return ToolConstraint


def time_path(
    robot: Robot,
    base_inv: Array,
    path: CartesianPath,
    Q: Array,
    s_knots: Array,
    *,
    limits: Limits,
    speed: tuple[Array, Array] | None,
    acceleration: tuple[Array, Array] | None,
    sd_start: float = 0.0,
    refinements: int = 3,
    scale: float = 1.0,
) -> PathMotion | None:
    """Time ``path`` (module doc) through joint samples Q (k, dof) at ``s_knots`` (k,),
    from path speed ``sd_start`` to rest. ``speed`` (m/s) and ``acceleration`` (m/s^2)
    bound the tool point, each as breakpoints (s, value) interpolated along the path
    (None: only the joints). Returns None when no time law exists (a start speed that
    cannot be brought to rest). ``scale`` (<= 1) tightens the joints' bounds further.

    The joints' limits are checked again between knots (at the middle of each interval,
    at the quarters and near the ends of intervals where a joint's rate changes fast: exact
    IK there, the time law's speed and acceleration): where the path bends so fast that a
    joint would pass its limit between knots (a tight corner, a singularity near), those
    points become knots and the path is timed again (up to ``refinements`` times)."""
    _toppra()
    m = JOINT_MARGIN * scale
    vj = np.where(np.isfinite(limits.speed), limits.speed * m, _UNLIMITED)
    aj = np.where(np.isfinite(limits.acceleration), limits.acceleration * m, _UNLIMITED)
    least = _least_time(Q, vj, aj, path, speed, acceleration, from_rest=sd_start == 0.0)
    work_limits.check(
        "max_sim_time",
        least,
        "a path timed within its limits, at least (its speed, override or acceleration is "
        "too small)",
    )  # before toppra, whose numbers fail on limits of 1e-100 (a law of 0 s)
    law = None
    for attempt in range(refinements + 1):
        law = _time_once(robot, base_inv, path, Q, s_knots, vj, aj, speed, acceleration, sd_start)
        if law is not None and law.duration < 0.5 * least:
            return None  # far faster than the limits allow: the numbers failed, no law
        if law is None or attempt == refinements:
            return law
        # check points: every interval's middle, more where the joint rates change fast
        idx, frac = _check_points(law.spline)
        pts = s_knots[idx] + frac * (s_knots[idx + 1] - s_knots[idx])
        Qm, err = refine_ik(robot, law.spline(pts)[:, :-1], base_inv @ path.poses(pts))
        if err.max(initial=0.0) > IK_TOL:
            return law  # a check point's IK cannot settle: keep the knots' law
        over = _over_limits(law, joint_path(robot, base_inv, path, Qm, pts), limits, idx, frac)
        if not over.any():
            return law
        order = np.argsort(np.concatenate([s_knots, pts[over]]), kind="stable")
        s_knots = np.concatenate([s_knots, pts[over]])[order]
        Q = np.concatenate([Q, Qm[over]])[order]
    return law


FRAME_CHECK_MAX = 200_000  # frames: longer motions are not checked frame by frame


def timed_frames(
    robot: Robot,
    base_inv: Array,
    path: CartesianPath,
    Q: Array,
    s_knots: Array,
    dt: float,
    what: str,
    *,
    limits: Limits,
    speed: tuple[Array, Array] | None,
    acceleration: tuple[Array, Array] | None,
    sd_start: float = 0.0,
    q_before: Array | None = None,
) -> tuple[PathMotion, Array, Array] | None:
    """:func:`time_path`, then its frames every ``dt`` (s): (law, local times, rows).

    The frames are the final check: their finite-difference joint speeds and
    accelerations (from rest at ``q_before``, when given) must keep the limits; where a
    joint's rate changes too fast even for the checks between knots (a line ending right
    next to a singularity), the path is timed again with the joints' bounds tightened by
    the excess (twice at most). Motions of more than :data:`FRAME_CHECK_MAX` frames are
    not checked this way. None when no time law exists."""
    from workcell.sim.planning import frames_of

    scale = 1.0
    for attempt in range(3):
        law = time_path(
            robot, base_inv, path, Q, s_knots, limits=limits, speed=speed,
            acceleration=acceleration, sd_start=sd_start, scale=scale,
        )  # fmt: skip
        if law is None:
            return None
        t = frames_of(law.duration, dt, what)
        if len(t) > FRAME_CHECK_MAX:
            return law, t, None  # type: ignore[return-value]
        rows = law.positions(t) if len(t) else np.empty((0, Q.shape[1]))
        if len(t):
            rows[-1] = Q[-1]
        ratio = _frame_ratio(t, rows, q_before, limits)
        if ratio <= 1.0 or attempt == 2:
            return law, t, rows
        scale /= ratio * 1.002
    return None


def _frame_ratio(t: Array, rows: Array, q_before: Array | None, limits: Limits) -> float:
    """The largest finite-difference joint speed or acceleration of frames (over the
    limits); from rest at ``q_before`` (local time 0) when given."""
    if q_before is not None:
        t, rows = np.concatenate([[0.0], t]), np.vstack([q_before, rows])
    if len(t) < 3:
        return 0.0
    dt = np.diff(t)
    ok = dt > 1e-12
    v = np.diff(rows, axis=0)[ok] / dt[ok][:, None]
    tm = (0.5 * (t[1:] + t[:-1]))[ok]
    a = np.diff(v, axis=0) / np.diff(tm)[:, None]
    if q_before is not None:  # the rest before the first frame
        a = np.vstack([v[:1] / tm[:1, None], a])
    with np.errstate(invalid="ignore", divide="ignore"):
        rv = np.nan_to_num(np.abs(v) / limits.speed).max(initial=0.0)
        ra = np.nan_to_num(np.abs(a) / limits.acceleration).max(initial=0.0)
    return float(max(rv, ra))


def _check_points(jp: JointPath) -> tuple[NDArray[np.intp], Array]:
    """Interval index and fraction of the points where :func:`time_path` checks the limits
    again: each interval's middle, and its quarters and near both ends for the intervals
    over which a joint's rate along the path changes by a third or more (towards a
    singularity the joints' speeds grow fastest right next to a knot; elsewhere the
    rates vary smoothly and the frames are checked once more in :func:`timed_frames`)."""
    n = len(jp.s) - 1
    d1 = np.abs(jp.dW[:, :-1])
    change = np.abs(np.diff(jp.dW[:, :-1], axis=0)) / np.maximum(np.maximum(d1[:-1], d1[1:]), 1e-9)
    steep = np.flatnonzero(change.max(axis=1) > 1.0 / 3.0)
    idx = np.concatenate([np.arange(n), np.repeat(steep, 6)])
    frac = np.concatenate(
        [np.full(n, 0.5), np.tile([0.02, 0.1, 0.25, 0.75, 0.9, 0.98], len(steep))]
    )
    order = np.argsort(idx + frac, kind="stable")
    return idx[order], frac[order]


def _over_limits(
    law: PathMotion, at: JointPath, limits: Limits, idx: NDArray[np.intp], frac: Array
) -> NDArray[np.bool_]:
    """Which check points (interval ``idx``, fraction ``frac``; ``at``: the exact path there)
    take a joint over its speed or acceleration limit under ``law`` (the path speed squared
    is linear in s within an interval, the path acceleration constant)."""
    p = law.profile
    x = p.sd[idx] ** 2 + frac * (p.sd[idx + 1] ** 2 - p.sd[idx] ** 2)
    d1, d2 = at.dW[:, :-1], at.ddW[:, :-1]
    speed = np.abs(d1) * np.sqrt(np.maximum(x, 0.0))[:, None] / limits.speed
    acc = np.abs(d1 * p.sdd[idx][:, None] + d2 * x[:, None]) / limits.acceleration
    return (np.nan_to_num(speed) > 1.0).any(axis=1) | (np.nan_to_num(acc) > 1.0).any(axis=1)


def _time_once(
    robot: Robot,
    base_inv: Array,
    path: CartesianPath,
    Q: Array,
    grid: Array,
    vj: Array,
    aj: Array,
    speed: tuple[Array, Array] | None,
    acceleration: tuple[Array, Array] | None,
    sd_start: float,
) -> PathMotion | None:
    """toppra's time law over knots ``grid`` (joint bounds vj, aj already with margin)."""
    from toppra import algorithm

    spline = joint_path(robot, base_inv, path, Q, grid)
    v, a = np.append(vj, _UNLIMITED), np.append(aj, _UNLIMITED)
    tool_v = np.full(len(grid), _UNLIMITED) if speed is None else np.interp(grid, *speed)
    tool_a = (
        np.full(len(grid), _UNLIMITED) if acceleration is None else np.interp(grid, *acceleration)
    )
    cons = [*_joint_constraints(tuple(v), tuple(a)), _tool_constraint(tool_v, tool_a)]
    inst = algorithm.TOPPRA(cons, spline, gridpoints=grid, parametrizer="ParametrizeConstAccel")
    sd = inst.compute_parameterization(float(sd_start), 0.0)[1]
    if sd is None or np.isnan(sd).any():
        return None
    bounds = {
        "speed": np.append(vj, 0.0),
        "acceleration": np.append(aj, 0.0),
        "tool_speed": tool_v,
        "tool_acceleration": tool_a,
    }
    return PathMotion(robot, base_inv, path, spline, PathProfile.of(grid, sd), bounds)
