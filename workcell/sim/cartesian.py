"""Cartesian targets for the simulator: one pose to joints, and straight lines.

:func:`solve_pose` turns a world tool pose into joint values for ``move_end_effector``:
for robots with a closed-form family (OPW, UR) the in-limit solutions (of the requested
configuration, if any), nearest to the current joints; otherwise :meth:`Robot.ik` from
the current joints. It raises :class:`UnreachableError` with the reason (out of reach, outside the
limits, configuration not available: the available ones are listed).

:func:`path_joints` solves the samples of any Cartesian path (:mod:`workcell.sim.paths`),
each by IK warm-started at the previous sample's joints (the closed form's nearest
in-limit solution of the start's arm and elbow configuration, all samples at once, or
numerical IK from the previous q). A sample with no solution, or a joint that would jump
more than ``max_jump`` between samples (a singularity on the way), makes the path
impossible: :class:`UnreachableError` says at which fraction of it, where, which joint
and why. :func:`line_waypoints` does this for the straight line from the current tool
pose to a target (thesis §4.5 ``move_straight_line``): positions evenly spaced at most
``step`` apart, orientation interpolated by slerp (held when start and target
orientations agree); :func:`line_deviation` then measures how far the joint-interpolated
frames stray from the line.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.cell.workcell import RobotPlacement
from workcell.checks import is_finite_number, quote_angle, quote_length
from workcell.errors import (
    GeometryError,
    KinematicsError,
    PlanningError,
    ProgramError,
    UnreachableError,
)
from workcell.robots.ik_closed import CONFIGS, config_of, ik_batch, ik_report
from workcell.robots.robot import Robot
from workcell.sim.cycle import command_record
from workcell.sim.jerk import require_finite
from workcell.sim.paths import CartesianPath, Line
from workcell.sim.planning import plan_waypoints
from workcell.sim.timing import sample_params
from workcell.spatial import as_transform, invert

__all__ = [
    "CartesianCommands",
    "line_deviation",
    "line_waypoints",
    "pose_solutions",
    "solve_pose",
    "world_target",
]

Array = NDArray[np.float64]


def world_target(T: ArrayLike, command: str, robot: str) -> Array:
    """A validated rigid 4x4 world pose (m); KinematicsError saying why otherwise."""
    try:
        return as_transform(T, rigid=True, name=f"{command} '{robot}' target")
    except GeometryError as exc:
        raise KinematicsError(str(exc)) from exc


def _closed_form(placement: RobotPlacement, Tb: Array, q: Array, config: str | None) -> list[Array]:
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
    return [s.q for s in sorted(ok, key=lambda s: float(np.abs(s.q - q).max()))]


def pose_solutions(
    placement: RobotPlacement, T_world: Array, q_current: Array, config: str | None = None
) -> list[Array]:
    """Every joint solution (rad/m) putting the tool at ``T_world`` within the limits,
    nearest to ``q_current`` first (in the largest joint change, so the one a joint move
    reaches soonest: eq. 4.27's duration is proportional to it).

    Closed-form families (``Robot.ik_family``) give all of them; other robots give the
    one :meth:`Robot.ik` finds from ``q_current``. ``config``: configuration letters to
    require (any of l|r, u|d, n|f, e.g. "ru"). Raises UnreachableError with the reason.
    """
    if config is not None and (
        not isinstance(config, str) or not config or set(config) - set("lrudnf")
    ):
        raise KinematicsError(
            f"config must be letters of l|r, u|d, n|f (e.g. 'run'), got {config!r}"
        )
    return _solutions_base(placement, invert(placement.base) @ T_world, q_current, config)


def _solutions_base(
    placement: RobotPlacement, Tb: Array, q: Array, config: str | None
) -> list[Array]:
    """:func:`pose_solutions` for a pose ``Tb`` in the robot's base frame."""
    robot = placement.robot
    if robot.ik_family is not None:
        return _closed_form(placement, Tb, q, config)
    sol = robot.ik(Tb, q, config=config)
    if not sol.success:
        raise UnreachableError(sol.reason or "numerical IK did not converge")
    return [sol.q]


def solve_pose(
    placement: RobotPlacement, T_world: Array, q_current: Array, config: str | None = None
) -> Array:
    """The joint values (rad/m) putting the tool at ``T_world`` nearest to ``q_current``:
    the first of :func:`pose_solutions`. Raises UnreachableError with the reason."""
    return pose_solutions(placement, T_world, q_current, config)[0]


def path_joints(
    placement: RobotPlacement,
    q0: Array,
    poses: Array,
    fractions: Array,
    *,
    max_jump: float,
    what: str = "line",
) -> Array:
    """Joint samples (k, dof) at world tool poses (k, 4, 4), each solved by IK warm-started
    at the previous one (a closed-form arm keeps its shoulder and elbow configuration: a
    switch is a jump). Raises UnreachableError saying at which ``fractions`` (k,) of the ``what``
    and where a sample is out of reach or a joint would jump more than ``max_jump``."""
    Tb = invert(placement.base) @ poses
    Q = np.empty((len(poses), len(q0)))
    prev = q0
    robot = placement.robot
    keep = config_of(robot, q0)[:2] if robot.ik_family is not None else None
    start = 0
    if keep is not None:  # the closed form for every sample at once, then one by one
        start, prev = _closed_form_samples(robot, Tb, q0, keep, Q, max_jump)
    for k in range(start, len(poses)):
        try:
            q = _solutions_base(placement, Tb[k], prev, keep)[0]
        except UnreachableError as exc:
            raise UnreachableError(f"{_where(fractions[k], poses[k], what)}: {exc}") from exc
        jump = np.abs(q - prev)
        j = int(np.argmax(jump))
        if jump[j] > max_jump:
            q5 = f"; joint 5 at {math.degrees(q[4]):.3g} deg" if len(q) >= 5 else ""
            raise UnreachableError(
                f"{_where(fractions[k], poses[k], what)}: joint {j + 1} would jump "
                f"{math.degrees(jump[j]):.3g} deg between samples (max_jump "
                f"{math.degrees(max_jump):.3g} deg): the {what} passes a singularity{q5}"
            )
        Q[k] = prev = q
    return Q


def _nearest_equivalents(robot: Robot, C: Array, near: Array) -> tuple[Array, Array]:
    """:meth:`Robot.wrap_batch` of candidates C (..., n) near ``near`` (..., n), written
    out for speed: the in-limit 2 pi-equivalent of each revolute joint nearest ``near``
    (prismatic joints as they are); and whether every joint has one."""
    two_pi = 2.0 * math.pi
    turns = C / two_pi
    k_lo = np.ceil(robot.lower / two_pi - 1e-12 - turns)
    k_hi = np.floor(robot.upper / two_pi + 1e-12 - turns)
    k = np.clip(np.rint((near - C) / two_pi), k_lo, k_hi)
    rev = robot.revolute
    W = np.where(rev, np.clip(C + two_pi * k, robot.lower, robot.upper), C)
    inside = (robot.lower - 1e-12 <= C) & (robot.upper + 1e-12 >= C)
    ok = np.where(rev, k_lo <= k_hi, inside).all(axis=-1)
    return W, ok


def _closed_form_samples(
    robot: Robot, Tb: Array, q0: Array, keep: str, Q: Array, max_jump: float
) -> tuple[int, Array]:
    """Fill Q with the closed form's solutions of shoulder and elbow configuration
    ``keep``, each the in-limit 2 pi-equivalent nearest the previous sample (as
    :func:`_solutions_base` orders them). Vectorised: one configuration followed along the
    whole path, kept when at every sample it is the nearest; else sample by sample.
    Stops at the first sample without a solution or with a joint jump over ``max_jump``.
    Returns (samples done, last q)."""
    S, valid = ik_batch(robot, Tb, q0)
    slots = [i for i, c in enumerate(CONFIGS) if c.startswith(keep)]
    C, V = S[:, slots], valid[:, slots]
    for i in range(len(slots)):
        if not V[:, i].all():
            continue
        U = _follow(robot, q0, C[:, i])
        if U is None:
            continue
        prev = np.vstack([q0[None, :], U[:-1]])
        far = np.abs(U - prev).max(axis=1)
        if far.max() > max_jump:
            continue
        nearest = True
        for j in range(len(slots)):
            if j != i:
                W, ok = _nearest_equivalents(robot, np.nan_to_num(C[:, j]), prev)
                other = np.where(V[:, j] & ok, np.abs(W - prev).max(axis=1), np.inf)
                nearest &= bool(np.all(far <= other))
        if nearest:
            Q[:] = U
            return len(Tb), U[-1]
    prev = q0
    for k in range(len(Tb)):  # one by one (the configuration changes on the way)
        W, ok = _nearest_equivalents(robot, np.nan_to_num(C[k]), prev)
        d = np.where(V[k] & ok, np.abs(W - prev).max(axis=1), np.inf)
        best = int(np.argmin(d))
        if not np.isfinite(d[best]) or d[best] > max_jump:
            return k, prev
        Q[k] = prev = W[best]
    return len(Tb), prev


def _follow(robot: Robot, q0: Array, C: Array) -> Array | None:
    """Solutions C (k, n) made continuous from q0 (each the 2 pi-equivalent nearest the
    one before), or None when one leaves the limits."""
    W, ok = _nearest_equivalents(robot, C, q0)  # nearest q0 first, then fix the drift
    if not ok.all():
        return None
    two_pi = 2.0 * math.pi
    d = np.diff(np.vstack([q0[None, :], W]), axis=0)
    drift = np.cumsum(two_pi * np.rint(d / two_pi), axis=0)  # whole turns crossed so far
    U = np.where(robot.revolute, W - drift, W)
    lo, hi = robot.lower - 1e-12, robot.upper + 1e-12
    return U if np.all((lo <= U) & (hi >= U)) else None


def _where(fraction: float, pose: Array, what: str) -> str:
    at = ", ".join(f"{v:.4g}" for v in pose[:3, 3])
    return f"at {fraction:.0%} of the {what}, tool at ({at}) m"


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
    path = CartesianPath([Line(T_start[:3, 3], T_goal[:3, 3], T_start[:3, :3], T_goal[:3, :3])])
    s = sample_params(path, step)[1:]
    poses = path.poses(s)
    poses[-1] = T_goal
    Q = path_joints(placement, q0, poses, s / max(path.span, 1e-300), max_jump=max_jump)
    return Q, poses


def line_deviation(placement: RobotPlacement, Q: Array, p0: Array, p1: Array) -> tuple[float, int]:
    """Largest distance (m) of the tool positions at joint values Q (k, dof) from the
    segment p0-p1 (world, m), and the row where it occurs."""
    if len(Q) == 0:
        return 0.0, 0
    P = (placement.base @ placement.robot.fk_batch(Q))[:, :3, 3]
    d = p1 - p0
    L2 = float(d @ d)
    s = np.clip(((P - p0) @ d) / L2, 0.0, 1.0) if L2 > 0 else np.zeros(len(P))
    dev = np.linalg.norm(P - (p0 + np.outer(s, d)), axis=1)
    i = int(np.argmax(dev))
    return float(dev[i]), i


def _line_asked(placement: RobotPlacement, target: Array) -> dict[str, object]:
    """A straight line's ``program`` record (:mod:`workcell.sim.cycle`): its target in the
    robot's base frame, no tool speed (the joints' limits or the thesis's timing)."""
    Tb = invert(placement.base) @ target
    return {"kind": "line", "pose": Tb.tolist(), "speed": None, "acceleration": None, "zone": 0.0}


class CartesianCommands:
    """``move_end_effector`` and ``move_straight_line`` (a mixin of Simulator)."""

    def move_end_effector(
        self,
        robot: str,
        T: ArrayLike,
        config: str | None = None,
        *,
        zone: float = 0.0,
        plan: bool = False,
    ) -> None:
        """Move the tool to the world pose ``T`` (4x4, m): IK, then a joint move.

        ``config``: configuration letters to require (e.g. "ru"): the in-limit solution
        of that configuration nearest the current joints. Default: of the in-limit
        solutions, nearest first, the first whose joint move keeps the planning clearance
        (checked as ``plan`` checks: :mod:`workcell.sim.planned`), else the nearest; the
        move's event says which configuration and why. ``zone`` (m): blend into the next
        move. Raises UnreachableError saying why. With ``plan``, a collision-free joint
        path to the nearest solution that has one (:mod:`workcell.sim.planned`; it stops
        at its end: no zone); PlanningError when the pose is unreachable, every solution
        is in collision or no path is found.
        """
        name = self._robot(robot)
        target = world_target(T, "move_end_effector", name)
        try:
            sols = pose_solutions(self.cell.robots[name], target, self.joints(name), config)
        except UnreachableError as exc:
            if plan:
                raise PlanningError(f"move_end_effector '{name}': goal unreachable: {exc}") from exc
            raise UnreachableError(f"move_end_effector '{name}': {exc}") from exc
        if plan:
            self._move_planned(name, sols, "move_end_effector")
            return
        pick, why = (0, "") if config is not None else self._default_solution(name, sols)
        Tb = invert(self.cell.robots[name].base) @ target
        asked = {"pose": Tb.tolist(), "config": config}
        self._move(name, sols[pick], "move_end_effector", zone, note=why, program=asked)

    def move_straight_line(
        self, robot: str, T: ArrayLike, step: float = 0.005, *, max_jump: float = math.radians(10)
    ) -> None:
        """Move the tool along the straight line to the world pose ``T`` (4x4, m).

        Samples at most ``step`` (m) apart (orientation slerped, held when unchanged),
        IK at each warm-started at the previous; a sample out of reach or a joint jump
        above ``max_jump`` (rad) raises UnreachableError saying where. Under the thesis
        profiles the robot moves linearly in joints between samples at its speed (frames
        straying more than ``line_tolerance`` from the line raise UnreachableError too);
        under profile "jerk" the line is timed as ``move_linear``'s, with no tool speed:
        as fast as the joints' limits allow.
        """
        command = "move_straight_line"
        name = self._robot(robot)
        target = world_target(T, command, name)
        for what, v, quote in (("step", step, quote_length), ("max_jump", max_jump, quote_angle)):
            if not (is_finite_number(v) and v > 0):
                raise ProgramError(f"{command} '{name}': {what} must be > 0, got {quote(v)}")
        placement = self.cell.robots[name]
        start = self.tool_pose(name)
        length = float(np.linalg.norm(target[:3, 3] - start[:3, 3]))
        if self.profile == "jerk":
            require_finite(self._limits(name), name, command, ("speed", "acceleration"))
            line = Line(start[:3, 3], target[:3, 3], start[:3, :3], target[:3, :3])
            detail = f"{length * 1e3:.4g} mm line"
            self._path_move(
                name, command, detail, CartesianPath([line]), None, None, 0.0,
                step=float(step), max_jump=float(max_jump), program=_line_asked(placement, target),
            )  # fmt: skip
            return
        q0 = self.joints(name)
        try:
            Qw, _ = line_waypoints(
                placement, q0, start, target, step=float(step), max_jump=float(max_jump)
            )
        except UnreachableError as exc:
            raise UnreachableError(f"{command} '{name}': {exc}") from exc
        motion = plan_waypoints(
            q0, Qw, speed=self.speed(name) * self._override[name], dt=self.dt,
            what=f"{command} '{name}'",
        )  # fmt: skip
        t0 = self._start_time(name)
        dev, i = line_deviation(placement, motion.rows, start[:3, 3], target[:3, 3])
        if dev > self.line_tolerance:
            raise UnreachableError(
                f"{command} '{name}': the tool strays {dev * 1e3:.3g} mm from the "
                f"line at t = {t0 + motion.t[i]:.4g} s (line_tolerance "
                f"{self.line_tolerance * 1e3:.3g} mm); use a smaller step"
            )
        program = self._program_settings(name, _line_asked(placement, target))
        program["q"] = Qw[-1].tolist()
        rec = command_record(name, command, t0, motion.duration, motion.activity, program=program)
        detail = f"{length * 1e3:.4g} mm line, {len(Qw)} samples"
        self._run(name, t0 + motion.t, motion.rows, command, detail, rec)
