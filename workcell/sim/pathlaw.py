"""A timed Cartesian path: the joint path, its time law, and the motion they make.

- :class:`JointPath`: q(s) and the tool-point arc length l(s) through exact IK samples
  of a :class:`~workcell.sim.paths.CartesianPath`, with exact first and second
  derivatives at the samples (central differences of exact IK at s +- h,
  :func:`joint_path`), a cubic Hermite spline between them;
- :class:`PathProfile`: a time law s(t) with constant path acceleration between
  gridpoints (toppra's constant-acceleration parametrization);
- :class:`PathMotion`: both together: joint rows at any times (the exact pose on the path
  at s(t) solved by Gauss-Newton from the spline's q, errors below 1e-9 m and rad), the
  state (q, q_dot, q_ddot) a blend starts from, and which limit was active when;
- :func:`refine_ik`, :func:`jacobians`: batched Gauss-Newton IK and forward-difference
  Jacobians over many rows at once.

:mod:`workcell.sim.timing` makes them (toppra's time-optimal parameterization).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell.errors import UnreachableError
from workcell.robots.robot import Robot
from workcell.sim.paths import CartesianPath

__all__ = [
    "JointPath",
    "PathMotion",
    "PathProfile",
    "jacobians",
    "joint_path",
    "refine_ik",
]

Array = NDArray[np.float64]
IK_TOL = 1e-9  # m and rad: what every frame of a timed path reaches
_ACTIVE = 0.99  # a constraint counts as active at >= this fraction of its bound


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
        if len(err) and err.max() > IK_TOL:
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
