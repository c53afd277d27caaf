"""Cartesian targets for the simulator: one pose to joints, and straight lines.

:func:`solve_pose` turns a world tool pose into joint values for ``move_end_effector``:
for robots with a closed-form family (OPW, UR) the in-limit solutions (of the requested
configuration, if any), nearest to the current joints; otherwise :meth:`Robot.ik` from
the current joints. It raises :class:`UnreachableError` with the reason (out of reach, outside the
limits, configuration not available: the available ones are listed).

:func:`line_waypoints` samples the straight line from the current tool pose to a target
(thesis §4.5 ``move_straight_line``): positions evenly spaced at most ``step`` apart,
orientation interpolated by slerp (held when start and target orientations agree), each
sample solved by IK warm-started at the previous sample's joints (the closed form's
nearest in-limit solution of the start's arm and elbow configuration, or numerical IK
from the previous q). A sample with no
solution, or a joint that would jump more than ``max_jump`` between samples (a
singularity on the way), makes the line impossible: :class:`UnreachableError` says at
which fraction of the line, where, which joint and why. :func:`line_deviation` then
measures how far the joint-interpolated frames stray from the line.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell import limits
from workcell.cell.workcell import RobotPlacement
from workcell.checks import is_finite_number
from workcell.errors import GeometryError, KinematicsError, ProgramError, UnreachableError
from workcell.robots.ik_closed import config_of, ik_report
from workcell.sim.planning import plan_waypoints
from workcell.spatial import angle_between, as_transform, invert

__all__ = [
    "CartesianCommands",
    "line_deviation",
    "line_waypoints",
    "solve_pose",
    "world_target",
]

Array = NDArray[np.float64]
_ANGLE_STEP = math.radians(2.0)  # rad: at most this much rotation between line samples


def world_target(T: ArrayLike, command: str, robot: str) -> Array:
    """A validated rigid 4x4 world pose (m); KinematicsError saying why otherwise."""
    try:
        return as_transform(T, rigid=True, name=f"{command} '{robot}' target")
    except GeometryError as exc:
        raise KinematicsError(str(exc)) from exc


def _closed_form(placement: RobotPlacement, Tb: Array, q: Array, config: str | None) -> Array:
    sols, reason = ik_report(placement.robot, Tb, q)
    ok = [s for s in sols if s.within_limits]
    if config is not None:
        have = sorted({s.config for s in ok if s.config})
        ok = [s for s in ok if s.config and all(c in s.config for c in config)]
        if not ok and have:
            outside = [s for s in sols if s.config and all(c in s.config for c in config)]
            why = f" ({outside[0].reason})" if outside and outside[0].reason else ""
            raise UnreachableError(
                f"configuration '{config}' cannot reach the pose within the limits{why}; "
                f"available: {', '.join(have)}"
            )
    if not ok:
        raise UnreachableError(reason or "no solution within the joint limits")
    return min(ok, key=lambda s: float(np.abs(s.q - q).max())).q


def solve_pose(
    placement: RobotPlacement, T_world: Array, q_current: Array, config: str | None = None
) -> Array:
    """Joint values (rad/m) putting the tool at ``T_world``, nearest to ``q_current``.

    Nearest in the largest joint change, so the one a joint move reaches soonest
    (eq. 4.27's duration is proportional to it).

    ``config``: configuration letters to require (any of l|r, u|d, n|f, e.g. "ru").
    Raises UnreachableError with the reason.
    """
    robot = placement.robot
    Tb = invert(placement.base) @ T_world
    if config is not None and (
        not isinstance(config, str) or not config or set(config) - set("lrudnf")
    ):
        raise KinematicsError(
            f"config must be letters of l|r, u|d, n|f (e.g. 'run'), got {config!r}"
        )
    if robot.ik_family is not None:
        return _closed_form(placement, Tb, q_current, config)
    sol = robot.ik(Tb, q_current, config=config)
    if not sol.success:
        raise UnreachableError(sol.reason or "numerical IK did not converge")
    return sol.q


def _slerp(R0: Array, R1: Array, s: Array) -> Array:
    """Rotations (k, 3, 3) from R0 to R1 at fractions s (k,), along the shortest arc."""
    Rrel = R0.T @ R1
    angle = angle_between(R0, R1)
    if angle < 1e-12:
        return np.repeat(R0[None], len(s), axis=0)
    w = np.array([Rrel[2, 1] - Rrel[1, 2], Rrel[0, 2] - Rrel[2, 0], Rrel[1, 0] - Rrel[0, 1]])
    if np.linalg.norm(w) < 1e-9:  # angle ~ pi: the axis from the symmetric part
        M = (Rrel + np.eye(3)) / 2.0
        axis = M[:, int(np.argmax(np.diag(M)))]
    else:
        axis = w
    axis = axis / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    th = angle * np.asarray(s)[:, None, None]
    R = np.eye(3) + np.sin(th) * K + (1.0 - np.cos(th)) * (K @ K)
    return R0 @ R


def line_waypoints(
    placement: RobotPlacement,
    q0: Array,
    T_start: Array,
    T_goal: Array,
    *,
    step: float,
    max_jump: float,
) -> tuple[Array, Array]:
    """Joint samples (k, dof) along the straight line (module doc) and their poses (k, 4, 4).

    The samples exclude the start (q0) and end at the goal. Raises UnreachableError
    naming the sample where the line fails.
    """
    p0, p1 = T_start[:3, 3], T_goal[:3, 3]
    length = float(np.linalg.norm(p1 - p0))
    angle = angle_between(T_start[:3, :3], T_goal[:3, :3])
    limits.check(
        "max_frames_per_command", length / step, f"a {length:.4g} m line sampled every {step:g} m"
    )
    n = max(1, math.ceil(length / step - 1e-9), math.ceil(angle / _ANGLE_STEP - 1e-9))
    s = np.arange(1, n + 1) / n
    poses = np.repeat(np.eye(4)[None], n, axis=0)
    poses[:, :3, :3] = _slerp(T_start[:3, :3], T_goal[:3, :3], s)
    poses[:, :3, 3] = p0 + np.outer(s, p1 - p0)
    Q = np.empty((n, len(q0)))
    prev = q0
    robot = placement.robot
    # a closed-form arm keeps its shoulder and elbow along a line (a switch is a jump)
    keep = config_of(robot, q0)[:2] if robot.ik_family is not None else None
    for k in range(n):
        where = f"at {s[k]:.0%} of the line, tool at ({', '.join(f'{v:.4g}' for v in poses[k, :3, 3])}) m"
        try:
            q = solve_pose(placement, poses[k], prev, keep)
        except UnreachableError as exc:
            raise UnreachableError(f"{where}: {exc}") from exc
        jump = np.abs(q - prev)
        j = int(np.argmax(jump))
        if jump[j] > max_jump:
            q5 = f"; joint 5 at {math.degrees(q[4]):.3g} deg" if len(q) >= 5 else ""
            raise UnreachableError(
                f"{where}: joint {j + 1} would jump {math.degrees(jump[j]):.3g} deg between "
                f"samples (max_jump {math.degrees(max_jump):.3g} deg): the line passes a "
                f"singularity{q5}"
            )
        Q[k] = prev = q
    return Q, poses


def line_deviation(placement: RobotPlacement, Q: Array, p0: Array, p1: Array) -> tuple[float, int]:
    """Largest distance (m) of the tool positions at joint values Q (k, dof) from the
    segment p0-p1 (world, m), and the row where it occurs."""
    P = (placement.base @ placement.robot.fk_batch(Q))[:, :3, 3]
    d = p1 - p0
    L2 = float(d @ d)
    s = np.clip(((P - p0) @ d) / L2, 0.0, 1.0) if L2 > 0 else np.zeros(len(P))
    dev = np.linalg.norm(P - (p0 + np.outer(s, d)), axis=1)
    i = int(np.argmax(dev))
    return float(dev[i]), i


class CartesianCommands:
    """``move_end_effector`` and ``move_straight_line`` (a mixin of Simulator)."""

    def move_end_effector(self, robot: str, T: ArrayLike, config: str | None = None) -> None:
        """Move the tool to the world pose ``T`` (4x4, m): IK, then linear in joints.

        ``config``: configuration letters to require (e.g. "ru"); default: the
        in-limit solution nearest the current joints. Raises UnreachableError saying why.
        """
        name = self._robot(robot)
        target = world_target(T, "move_end_effector", name)
        try:
            q = solve_pose(self.cell.robots[name], target, self.joints(name), config)
        except UnreachableError as exc:
            raise UnreachableError(f"move_end_effector '{name}': {exc}") from exc
        self._move(name, q, "move_end_effector")

    def move_straight_line(
        self, robot: str, T: ArrayLike, step: float = 0.005, *, max_jump: float = math.radians(10)
    ) -> None:
        """Move the tool along the straight line to the world pose ``T`` (4x4, m).

        Samples at most ``step`` (m) apart (orientation slerped, held when unchanged),
        IK at each warm-started at the previous, linear in joints between samples; a
        sample out of reach, a joint jump above ``max_jump`` (rad) or frames straying
        more than ``line_tolerance`` from the line raise UnreachableError saying where.
        """
        name = self._robot(robot)
        target = world_target(T, "move_straight_line", name)
        for what, v in (("step", step), ("max_jump", max_jump)):
            if not (is_finite_number(v) and v > 0):
                raise ProgramError(f"move_straight_line '{name}': {what} must be > 0, got {v!r}")
        placement = self.cell.robots[name]
        start = self.tool_pose(name)
        q0 = self.joints(name)
        try:
            Qw, _ = line_waypoints(
                placement, q0, start, target, step=float(step), max_jump=float(max_jump)
            )
        except UnreachableError as exc:
            raise UnreachableError(f"move_straight_line '{name}': {exc}") from exc
        times, Qr = plan_waypoints(
            q0, Qw, start=self._start_time(name), speed=self.speed(name), dt=self.dt
        )
        dev, i = line_deviation(placement, Qr, start[:3, 3], target[:3, 3])
        if dev > self.line_tolerance:
            raise UnreachableError(
                f"move_straight_line '{name}': the tool strays {dev * 1e3:.3g} mm from the "
                f"line at t = {times[i]:.4g} s (line_tolerance {self.line_tolerance * 1e3:.3g} "
                f"mm); use a smaller step"
            )
        length = float(np.linalg.norm(target[:3, 3] - start[:3, 3]))
        self._run(
            name, times, Qr, "move_straight_line", f"{length * 1e3:.4g} mm line, {len(Qw)} samples"
        )
