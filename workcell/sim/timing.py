"""Timing a Cartesian path: the tool at its programmed speed, the joints within their limits.

:func:`time_path` turns a :class:`~workcell.sim.paths.CartesianPath` into a motion:

1. joint samples: the path is sampled at most ``step`` (m) and 2 deg of turn apart and
   each sample solved by IK warm-started at the previous one
   (:func:`workcell.sim.cartesian.path_joints`: an unreachable sample or a joint jump
   raises UnreachableError saying where);
2. a cubic spline q(s) through them, with one more coordinate, the tool-point arc length
   l(s), so that the tool speed ``l' s_dot`` and tool acceleration ``l' s_ddot`` are
   constraints like the joints' own;
3. toppra's time-optimal parameterization under the joints' speed and acceleration
   limits (a :data:`JOINT_MARGIN` below them, room for the spline's approximation) and
   the tool's speed and acceleration, with the constant-acceleration parametrizer
   (toppra's default spline output overshoots acceleration limits by ~10 %): the tool
   runs at the programmed speed wherever the joints allow and slows down where they
   do not (near a singularity) instead of breaking a limit;
4. frames: at each frame's time the path parameter s(t) of that law, the exact pose on
   the path at s(t), and its IK by Gauss-Newton from the spline's q(s(t)) (errors below
   1e-9 m and rad), so every frame lies on the path to IK precision.

``import toppra`` costs ~1 s (it pulls in matplotlib): it happens at the first call.
"""

from __future__ import annotations

import functools
import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell import limits as work_limits
from workcell.errors import UnreachableError
from workcell.robots.robot import Robot
from workcell.sim.jerk import Limits
from workcell.sim.paths import CartesianPath

__all__ = [
    "FRAME_CHECK_MAX",
    "JOINT_MARGIN",
    "JointPath",
    "PathMotion",
    "PathProfile",
    "jacobians",
    "joint_path",
    "refine_ik",
    "sample_params",
    "time_path",
    "timed_frames",
]

Array = NDArray[np.float64]
JOINT_MARGIN = 0.985  # toppra gets the joint limits times this (room between its knots)
_UNLIMITED = 1e6  # stands for "no limit" (inf) in toppra's constraints
_ANGLE_STEP = math.radians(2.0)
_MIN_GRID = 24
_ACTIVE = 0.99  # a constraint counts as active at >= this fraction of its bound
_IK_TOL = 1e-9


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
    out = [np.zeros(1)]
    step = min(step, path.span / (_MIN_GRID - 1)) if path.span > 0 else step
    for k, p in enumerate(path.pieces):
        h = min(step, p.max_step)
        n = max(1, math.ceil(p.span / h - 1e-9), math.ceil(p.angle / _ANGLE_STEP - 1e-9))
        out.append(path.starts[k] + p.span * np.arange(1, n + 1) / n)
    return np.concatenate(out)


@dataclass(frozen=True)
class PathProfile:
    """A time law s(t) with constant path acceleration between gridpoints ``s`` (N,):
    path speeds ``sd`` (N,) there, reached at times ``t`` (N,) (s, from 0)."""

    s: Array
    sd: Array
    t: Array

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    @property
    def sdd(self) -> Array:
        """Path acceleration in each interval (N-1,)."""
        ds = np.diff(self.s)
        return np.where(ds > 0, (self.sd[1:] ** 2 - self.sd[:-1] ** 2) / (2.0 * ds), 0.0)

    @classmethod
    def of(cls, s: Array, sd: Array) -> PathProfile:
        sd = np.maximum(sd, 0.0)
        v = sd[:-1] + sd[1:]
        dt = np.where(v > 0, 2.0 * np.diff(s) / np.maximum(v, 1e-300), 0.0)
        return cls(s, sd, np.concatenate([[0.0], np.cumsum(dt)]))

    def at(self, t: Array) -> tuple[Array, Array, Array]:
        """(s, s_dot, s_ddot) at times t (s), clipped to [0, duration]."""
        t = np.clip(np.asarray(t, dtype=np.float64), 0.0, self.duration)
        i = np.clip(np.searchsorted(self.t, t, side="right") - 1, 0, len(self.s) - 2)
        tau = t - self.t[i]
        acc = self.sdd[i]
        s = np.minimum(self.s[i] + self.sd[i] * tau + 0.5 * acc * tau * tau, self.s[i + 1])
        return s, self.sd[i] + acc * tau, acc

    def time_at(self, s: float) -> float:
        """The time (s) the law reaches path parameter ``s``."""
        s = min(max(float(s), float(self.s[0])), float(self.s[-1]))
        i = int(np.clip(np.searchsorted(self.s, s, side="right") - 1, 0, len(self.s) - 2))
        acc, v0, d = float(self.sdd[i]), float(self.sd[i]), s - float(self.s[i])
        if abs(acc) < 1e-15:
            return float(self.t[i]) + (d / v0 if v0 > 0 else 0.0)
        v = math.sqrt(max(v0 * v0 + 2.0 * acc * d, 0.0))
        return float(self.t[i]) + (v - v0) / acc


class PathMotion:
    """A timed Cartesian path (module doc): joint rows at local times, states, and which
    limit was active when."""

    def __init__(
        self,
        robot: Robot,
        base_inv: Array,
        path: CartesianPath,
        spline: Any,
        profile: PathProfile,
        bounds: dict[str, Array],
    ) -> None:
        self.robot, self.base_inv, self.path = robot, base_inv, path
        self.spline, self.profile, self._bounds = spline, profile, bounds
        self.duration = profile.duration
        self.q_end = spline(path.span)[:-1]

    def positions(self, t: Array) -> Array:
        """Joint rows (k, dof) at local times t: exact IK of the path's pose at s(t)."""
        s, _, _ = self.profile.at(t)
        Q0 = self.spline(s)[:, :-1]
        T = self.base_inv @ self.path.poses(s)
        Q, err = refine_ik(self.robot, Q0, T)
        if len(err) and err.max() > _IK_TOL:
            k = int(np.argmax(err))
            raise UnreachableError(
                f"the path cannot be followed to 1e-9 at t = {float(t[k]):.4g} s "
                f"(tool at {', '.join(f'{v:.4g}' for v in self.path.points(s[k : k + 1])[0])} m): "
                f"IK error {err[k]:.2g}"
            )
        return Q

    def state(self, t: float) -> tuple[Array, Array, Array]:
        """(q, q_dot, q_ddot) at local time t, from the spline and the time law."""
        s, sd, sdd = (float(x[0]) for x in self.profile.at(np.array([t])))
        d1, d2 = self.spline(s, 1)[:-1], self.spline(s, 2)[:-1]
        q = self.positions(np.array([t]))[0]
        return q, d1 * sd, d1 * sdd + d2 * sd * sd

    def tool_length(self, t: Array) -> Array:
        """Tool-point arc length (m) covered by local times t."""
        return self.path.tool_length(self.profile.at(t)[0])

    def activity(self, s_from: float = 0.0, s_to: float = math.inf) -> dict[str, float]:
        """Seconds each limit was active between path parameters ``s_from`` and ``s_to``:
        ``"tool speed"``, ``"tool acceleration"``, ``"j<i> speed"``, ``"j<i> acceleration"``
        (in each interval of the time law, the constraint nearest its bound, if within
        1 % of it)."""
        p = self.profile
        s, sd, sdd = p.s, p.sd, p.sdd
        d1, d2 = self.spline(s, 1), self.spline(s, 2)
        names = [f"j{i + 1}" for i in range(d1.shape[1] - 1)] + ["tool"]
        b = self._bounds
        vmax = np.concatenate(
            [np.broadcast_to(b["speed"][:-1], (len(s), d1.shape[1] - 1)), b["tool_speed"][:, None]],
            axis=1,
        )
        amax = np.concatenate(
            [
                np.broadcast_to(b["acceleration"][:-1], (len(s), d1.shape[1] - 1)),
                b["tool_acceleration"][:, None],
            ],
            axis=1,
        )
        speed = np.abs(d1) * sd[:, None] / vmax  # (N, dof+1)
        speed = np.maximum(speed[:-1], speed[1:])
        acc = np.maximum(  # the time law's constant s_ddot at both ends of each interval
            np.abs(d1[:-1] * sdd[:, None] + d2[:-1] * (sd[:-1, None] ** 2)) / amax[:-1],
            np.abs(d1[1:] * sdd[:, None] + d2[1:] * (sd[1:, None] ** 2)) / amax[1:],
        )
        ratios = np.concatenate([speed, acc], axis=1)
        labels = [f"{n} speed" for n in names] + [f"{n} acceleration" for n in names]
        best = np.argmax(ratios, axis=1)
        active = ratios[np.arange(len(best)), best] >= _ACTIVE
        mid = 0.5 * (s[:-1] + s[1:])
        keep = active & (mid >= s_from) & (mid <= s_to)
        out: dict[str, float] = {}
        for k in np.flatnonzero(keep):
            key = labels[best[k]]
            out[key] = out.get(key, 0.0) + float(p.t[k + 1] - p.t[k])
        return out


def jacobians(robot: Robot, Q: Array, F: Array | None = None) -> Array:
    """Jacobians (k, 6, n) of the tool pose at joint rows Q (k, n) (base frame: linear then
    angular velocity per unit joint speed): forward differences of ``fk_batch`` (``F``:
    the poses at Q, when known), vectorised over the rows."""
    k, n = Q.shape
    h = 1e-7
    F = robot.fk_batch(Q) if F is None else F
    Fp = robot.fk_batch((Q[:, None, :] + np.eye(n) * h).reshape(-1, n)).reshape(k, n, 4, 4)
    J = np.empty((k, 6, n))
    J[:, :3] = np.transpose(Fp[:, :, :3, 3] - F[:, None, :3, 3], (0, 2, 1)) / h
    Rrel = Fp[:, :, :3, :3] @ np.transpose(F[:, None, :3, :3], (0, 1, 3, 2))
    J[:, 3:] = np.transpose(_vee(Rrel), (0, 2, 1)) / h
    return J


def refine_ik(
    robot: Robot, Q: Array, T: Array, iterations: int = 4, J: Array | None = None
) -> tuple[Array, Array]:
    """Gauss-Newton from joint rows Q (k, n) to tool poses T (k, 4, 4, base frame).

    Returns the rows and each one's error (max of position m and orientation rad). The
    Jacobians are :func:`jacobians` at each iterate, or the given ``J`` (k, 6, n) kept
    throughout (rows that start very near their solution converge as well)."""
    Q = np.array(Q, dtype=np.float64)
    k, n = Q.shape
    err = np.zeros(k)
    if k == 0:
        return Q, err
    for it in range(iterations + 1):
        F = robot.fk_batch(Q)
        e = _pose_residual(F, T)
        err = np.abs(e).max(axis=1)
        bad = err > 1e-13
        if it == iterations or not bad.any():
            break
        Jb = jacobians(robot, Q[bad], F[bad]) if J is None else J[bad]
        Jt = np.transpose(Jb, (0, 2, 1))
        A = Jt @ Jb + 1e-12 * np.eye(n)
        Q[bad] += np.linalg.solve(A, (Jt @ e[bad][:, :, None]))[:, :, 0]
    return Q, err


def _vee(R: Array) -> Array:
    """The rotation vector of rotations near the identity (..., 3, 3) -> (..., 3)."""
    return 0.5 * np.stack(
        [R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]],
        axis=-1,
    )


def _pose_residual(F: Array, T: Array) -> Array:
    """(k, 6): target position - position, and the rotation taking F's orientation to T's."""
    e = np.empty((len(F), 6))
    e[:, :3] = T[:, :3, 3] - F[:, :3, 3]
    e[:, 3:] = _vee(T[:, :3, :3] @ np.transpose(F[:, :3, :3], (0, 2, 1)))
    return e


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


class JointPath:
    """q(s) and the tool length l(s) (last column) through exact IK samples at knots
    ``s``: exact values ``W``, first and second derivatives ``dW``, ``ddW`` there (central
    differences of exact IK, :func:`joint_path`), a cubic Hermite spline between knots
    (second derivatives interpolated linearly). toppra evaluates it at the knots only,
    so its constraints are those of the exact path."""

    def __init__(self, s: Array, W: Array, dW: Array, ddW: Array) -> None:
        from scipy.interpolate import CubicHermiteSpline

        self.s, self.W, self.dW, self.ddW = s, W, dW, ddW
        self._herm = CubicHermiteSpline(s, W, dW)
        self.dof = W.shape[1]
        self.path_interval = np.array([s[0], s[-1]])

    def __call__(self, ss: Any, order: int = 0) -> Array:
        ss = np.asarray(ss, dtype=np.float64)
        if ss.shape == self.s.shape and np.array_equal(ss, self.s):
            return (self.W, self.dW, self.ddW)[order].copy()
        if order == 2:
            flat = np.atleast_1d(ss)
            out = np.stack([np.interp(flat, self.s, c) for c in self.ddW.T], axis=-1)
            return out if ss.ndim else out[0]
        return self._herm(ss, order)


def joint_path(
    robot: Robot, base_inv: Array, path: CartesianPath, Q: Array, s: Array, h: float = 1e-4
) -> JointPath:
    """The :class:`JointPath` of ``path`` through IK samples Q (k, dof) at knots s (k,):
    q' and q'' from exact IK at s +- h (one-sided at the ends; m of path parameter)."""
    k = len(Q)
    h = min(h, 0.25 * float(np.min(np.diff(s)))) if k > 1 else h
    # at a junction of pieces the path's third derivative jumps: a shorter stencil there
    # keeps the central difference of q'' from mixing the two sides
    hk = np.where(np.isin(s, path.starts[1:-1]), 0.1 * h, h)
    lo = np.where(s - hk < 0.0, 0, -1)  # offsets (in hk) of the three stencil points
    lo = np.where(s + hk > path.span, -2, lo)
    offs = lo[:, None] + np.arange(3)[None, :]  # (k, 3)
    R = np.repeat(Q[:, None, :], 3, axis=1)  # the knot itself is known: solve the others
    other = offs != 0
    ss = (s[:, None] + hk[:, None] * offs)[other]
    slope = np.gradient(Q, s, axis=0) if k > 2 else np.zeros_like(Q)
    guess = (Q[:, None, :] + (hk[:, None] * offs)[:, :, None] * slope[:, None, :])[other]
    J = np.repeat(jacobians(robot, Q)[:, None], 3, axis=1)[other]  # the knot's, for all three
    R[other], _ = refine_ik(robot, guess, base_inv @ path.poses(ss), J=J)
    # derivatives at the stencil point with offset 0 (its index -lo in the stencil)
    c = -lo
    h2 = (2 * hk)[:, None]
    d1 = np.where(
        (c == 1)[:, None],
        (R[:, 2] - R[:, 0]) / h2,
        np.where((c == 0)[:, None], (-3 * R[:, 0] + 4 * R[:, 1] - R[:, 2]) / h2,
                 (3 * R[:, 2] - 4 * R[:, 1] + R[:, 0]) / h2),
    )  # fmt: skip
    d2 = (R[:, 0] - 2 * R[:, 1] + R[:, 2]) / (hk * hk)[:, None]
    ell = path.tool_length(s)
    ratio = np.gradient(ell, s) if k > 1 else np.ones(k)
    W = np.hstack([Q, ell[:, None]])
    dW = np.hstack([d1, ratio[:, None]])
    ddW = np.hstack([d2, np.zeros((k, 1))])
    return JointPath(s, W, dW, ddW)


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

    The joints' limits are checked again between knots (at the quarters and the middle of
    each interval, near the ends of intervals where a joint's rate changes fast: exact IK
    there, the time law's speed and acceleration): where the path bends so fast that a
    joint would pass its limit between knots (a tight corner, a singularity near), those
    points become knots and the path is timed again (up to ``refinements`` times)."""
    _toppra()
    m = JOINT_MARGIN * scale
    vj = np.where(np.isfinite(limits.speed), limits.speed * m, _UNLIMITED)
    aj = np.where(np.isfinite(limits.acceleration), limits.acceleration * m, _UNLIMITED)
    law = None
    for attempt in range(refinements + 1):
        law = _time_once(robot, base_inv, path, Q, s_knots, vj, aj, speed, acceleration, sd_start)
        if law is None or attempt == refinements:
            return law
        # check points: the quarters and the middle of every interval
        idx, frac = _check_points(law.spline)
        pts = s_knots[idx] + frac * (s_knots[idx + 1] - s_knots[idx])
        Qm, err = refine_ik(robot, law.spline(pts)[:, :-1], base_inv @ path.poses(pts))
        if err.max(initial=0.0) > _IK_TOL:
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
    again: each interval's quarters and middle, and near both ends of the intervals over
    which a joint's rate along the path changes by a third or more (towards a
    singularity the joints' speeds grow fastest right next to a knot)."""
    n = len(jp.s) - 1
    d1 = np.abs(jp.dW[:, :-1])
    change = np.abs(np.diff(jp.dW[:, :-1], axis=0)) / np.maximum(np.maximum(d1[:-1], d1[1:]), 1e-9)
    steep = np.flatnonzero(change.max(axis=1) > 1.0 / 3.0)
    idx = np.concatenate([np.repeat(np.arange(n), 3), np.repeat(steep, 4)])
    frac = np.concatenate(
        [np.tile([0.25, 0.5, 0.75], n), np.tile([0.02, 0.1, 0.9, 0.98], len(steep))]
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
