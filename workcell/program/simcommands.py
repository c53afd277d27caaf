"""The command vocabulary, simulation part (thesis §4.4-4.6).

``simulate`` starts a :class:`~workcell.sim.Simulator` on the session's cell (see
:mod:`workcell.program.cellcommands`). Simulation commands carry the
Simulator's method names and SI arguments (rad, m, s; a pose is a 4x4 world pose of the
robot's tool, or a :class:`~workcell.program.targets.Target`) and call that method; the
Simulator validates before it changes anything, so a failed command changes nothing.
Commands for Simulator methods that this build of the simulator does not have yet raise
ProgramError saying so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from workcell.errors import ProgramError
from workcell.program import args as a
from workcell.program.args import arg
from workcell.program.base import Command
from workcell.program.targets import Target, target, via_target
from workcell.sim.profiles import PROFILES

if TYPE_CHECKING:
    from workcell.program.session import Session

__all__ = [
    "MODES",
    "Clearance",
    "CloseGripper",
    "ConcurrentlyBegin",
    "ConcurrentlyEnd",
    "CycleTime",
    "Events",
    "Frames",
    "GripperPose",
    "Handover",
    "Held",
    "Joints",
    "MoveCircular",
    "MoveEndEffector",
    "MoveJointsAbsolute",
    "MoveJointsRelative",
    "MoveLinear",
    "MoveStraightLine",
    "OpenGripper",
    "PartPose",
    "PartPositions",
    "Pick",
    "Place",
    "Play",
    "Robots",
    "SetMode",
    "SetOverride",
    "SetPlanning",
    "SetProfile",
    "SetSpeed",
    "SimTime",
    "Simulate",
    "Speed",
    "StopSimulation",
    "Summary",
    "ToolPose",
    "Trajectory",
    "Wait",
    "WallTime",
]

MODES = ("path", "joint-by-joint", "playback")
_name = a.name


def _call(session: Session, method: str, *args: Any, **kw: Any) -> Any:
    """Call the session simulator's ``method``; ProgramError when it has none."""
    sim = session.require_sim()
    fn = getattr(sim, method, None)
    if fn is None:
        raise ProgramError(f"{method}: this simulator does not provide {method} yet")
    return fn(*args, **kw)


# ---------------------------------------------------------------- simulation
@dataclass(frozen=True)
class Simulate(Command, wire="simulate"):
    """Start simulating the cell in ``mode`` with sampling interval ``dt`` (s); replaces
    any running simulation (its clock and timeline start anew)."""

    mode: str = arg(a.choice(*MODES), "path")
    dt: float = arg(a.number, 0.01, "s")
    realtime: bool = arg(a.boolean, False)

    def execute(self, session: Session) -> str:
        from workcell.sim.simulator import Simulator

        cell = session.require_cell()
        session.sim = Simulator(cell, mode=self.mode, dt=self.dt, realtime=self.realtime)
        return f"simulating cell '{cell.name}': {self.mode} mode, dt {self.dt:g} s"


@dataclass(frozen=True)
class StopSimulation(Command, wire="stop_simulation"):
    """End the simulation (the cell stays and can be edited again)."""

    def execute(self, session: Session) -> None:
        session.require_sim()
        session.sim = None


@dataclass(frozen=True)
class SetMode(Command, wire="set_mode"):
    """Switch the simulation mode: path, joint-by-joint or playback."""

    mode: str = arg(a.choice(*MODES))

    def execute(self, session: Session) -> None:
        _call(session, "set_mode", self.mode)


@dataclass(frozen=True)
class SetSpeed(Command, wire="set_speed"):
    """Set a robot's speed (rad/s): the speed of the joint that moves most."""

    robot: str = arg(a.name)
    speed: float = arg(a.number, doc="rad/s")

    def execute(self, session: Session) -> None:
        _call(session, "set_speed", self.robot, self.speed)


def _joints_or_pose(v: object, what: str) -> tuple[float, ...] | str:
    """Joint values (a list of numbers) or the name of one of the robot's poses."""
    if isinstance(v, str) and v:
        return v
    try:
        return a.vector(v, what)
    except ProgramError:
        raise ProgramError(
            f"{what} must be a list of numbers (joint values, rad/m) or a pose name such as "
            f"'home', got {v!r}"[:200]
        ) from None


_joints_or_pose.label = "number[] | name"  # type: ignore[attr-defined]


@dataclass(frozen=True)
class MoveJointsAbsolute(Command, wire="move_joints_absolute"):
    """Move a robot's joints to ``q`` (rad/m), or to a named pose of the robot ("home");
    ``plan``: along a collision-free path; ``zone`` (m): blend into the next move."""

    robot: str = arg(a.name)
    q: tuple[float, ...] | str = arg(_joints_or_pose, doc="rad/m")
    plan: bool = arg(a.boolean, False)
    zone: float = arg(a.number, 0.0, "m")

    def execute(self, session: Session) -> None:
        q = self.q if isinstance(self.q, str) else np.array(self.q)
        _call(session, "move_joints_absolute", self.robot, q, plan=self.plan, zone=self.zone)


@dataclass(frozen=True)
class MoveJointsRelative(Command, wire="move_joints_relative"):
    """Move a robot's joints by ``dq`` (rad/m); ``zone`` (m): blend into the next move."""

    robot: str = arg(a.name)
    dq: tuple[float, ...] = arg(a.vector, doc="rad/m")
    zone: float = arg(a.number, 0.0, "m")

    def execute(self, session: Session) -> None:
        _call(session, "move_joints_relative", self.robot, np.array(self.dq), zone=self.zone)


@dataclass(frozen=True)
class MoveEndEffector(Command, wire="move_end_effector"):
    """Move the tool to pose ``T`` (IK, then a joint move); ``config`` picks the Puma
    solution (three letters l|r, u|d, n|f; default: the nearest); ``plan``: along a
    collision-free path; ``zone`` (m): blend into the next move."""

    robot: str = arg(a.name)
    T: Target = arg(target)  # noqa: RUF009 - arg() returns a dataclasses.field
    config: str | None = arg(a.optional(a.name), None)
    plan: bool = arg(a.boolean, False)
    zone: float = arg(a.number, 0.0, "m")

    def execute(self, session: Session) -> None:
        T = self.T.resolve(session, self.robot)
        _call(
            session, "move_end_effector", self.robot, T,
            config=self.config, plan=self.plan, zone=self.zone,
        )  # fmt: skip


@dataclass(frozen=True)
class MoveStraightLine(Command, wire="move_straight_line"):
    """Move the tool along a straight line to ``T``, samples ``step`` (m) apart."""

    robot: str = arg(a.name)
    T: Target = arg(target)  # noqa: RUF009 - arg() returns a dataclasses.field
    step: float = arg(a.number, 0.005, "m")

    def execute(self, session: Session) -> None:
        T = self.T.resolve(session, self.robot)
        _call(session, "move_straight_line", self.robot, T, step=self.step)


@dataclass(frozen=True)
class MoveLinear(Command, wire="move_linear"):
    """Move the tool point along a straight line to ``T`` at ``speed`` (m/s) and
    ``acceleration`` (m/s^2; null: 1.2), orientation interpolated, slower only where the
    joints' limits demand; ``zone`` (m): blend into the next move."""

    robot: str = arg(a.name)
    T: Target = arg(target)  # noqa: RUF009 - arg() returns a dataclasses.field
    speed: float = arg(a.number, doc="m/s")
    acceleration: float | None = arg(a.optional(a.number), None, "m/s^2")
    zone: float = arg(a.number, 0.0, "m")

    def execute(self, session: Session) -> None:
        T = self.T.resolve(session, self.robot)
        _call(
            session, "move_linear", self.robot, T,
            speed=self.speed, acceleration=self.acceleration, zone=self.zone,
        )  # fmt: skip


@dataclass(frozen=True)
class MoveCircular(Command, wire="move_circular"):
    """Move the tool point along the circle through its position, ``via`` (a point or a
    target: its position) and the position of ``T``, to ``T``, at ``speed`` (m/s);
    otherwise as ``move_linear``."""

    robot: str = arg(a.name)
    via: Target = arg(via_target)  # noqa: RUF009 - arg() returns a dataclasses.field
    T: Target = arg(target)  # noqa: RUF009 - arg() returns a dataclasses.field
    speed: float = arg(a.number, doc="m/s")
    acceleration: float | None = arg(a.optional(a.number), None, "m/s^2")
    zone: float = arg(a.number, 0.0, "m")

    def execute(self, session: Session) -> None:
        via = self.via.resolve(session, self.robot)
        T = self.T.resolve(session, self.robot)
        _call(
            session, "move_circular", self.robot, via, T,
            speed=self.speed, acceleration=self.acceleration, zone=self.zone,
        )  # fmt: skip


@dataclass(frozen=True)
class SetOverride(Command, wire="set_override"):
    """Set a robot's speed override (0 < f <= 1): speeds x f, accelerations x f^2, jerks
    x f^3, the same paths in 1/f the time."""

    robot: str = arg(a.name)
    override: float = arg(a.number, doc="fraction")

    def execute(self, session: Session) -> None:
        _call(session, "set_override", self.robot, self.override)


@dataclass(frozen=True)
class SetProfile(Command, wire="set_profile"):
    """Set the joint-move profile: the thesis's linear, trapezoid, quintic (the robot's
    speed), or jerk (each joint's speed, acceleration and jerk limits);
    ``acceleration`` (rad/s^2): the trapezoid's."""

    profile: str = arg(a.choice(*PROFILES))
    acceleration: float | None = arg(a.optional(a.number), None, "rad/s^2")

    def execute(self, session: Session) -> None:
        _call(session, "set_profile", self.profile, self.acceleration)


@dataclass(frozen=True)
class CycleTime(Command, wire="cycle_time"):
    """The cycle-time report: total_s and, per command, robot, command, t_start (s),
    duration_s, limited_by (the limit that set its time), zone_m."""

    def execute(self, session: Session) -> dict[str, Any]:
        return _call(session, "cycle_time")


@dataclass(frozen=True)
class CloseGripper(Command, wire="close_gripper"):
    """Close the gripper: grasp the first movable part within ``max_distance`` (m) of the
    tool with a box axis within ``max_angle`` (rad) of the tool's z axis; returns its name."""

    robot: str = arg(a.name)
    max_distance: float = arg(a.number, 0.02, "m")
    max_angle: float = arg(a.number, math.radians(10), "rad")

    def execute(self, session: Session) -> Any:
        return _call(
            session,
            "close_gripper",
            self.robot,
            max_distance=self.max_distance,
            max_angle=self.max_angle,
        )


@dataclass(frozen=True)
class OpenGripper(Command, wire="open_gripper"):
    """Open the gripper; returns the part released (or null); ``settle``: a part released
    in mid-air drops onto the highest support below it."""

    robot: str = arg(a.name)
    settle: bool = arg(a.boolean, False)

    def execute(self, session: Session) -> Any:
        return _call(session, "open_gripper", self.robot, settle=self.settle)


@dataclass(frozen=True)
class SetPlanning(Command, wire="set_planning"):
    """Change how planned moves search: ``clearance`` and ``near_clearance`` (m),
    ``time_limit`` (s), ``seed``; null keeps a setting. Returns the settings in force."""

    clearance: float | None = arg(a.optional(a.number), None, "m")
    time_limit: float | None = arg(a.optional(a.number), None, "s")
    seed: int | None = arg(a.optional(a.count), None)
    near_clearance: float | None = arg(a.optional(a.number), None, "m")

    def execute(self, session: Session) -> Any:
        return _call(
            session,
            "set_planning",
            clearance=self.clearance,
            time_limit=self.time_limit,
            seed=self.seed,
            near_clearance=self.near_clearance,
        )


@dataclass(frozen=True)
class Pick(Command, wire="pick"):
    """Pick ``part`` with ``robot``: grasp chosen automatically, collision-free approach,
    grasp, retreat ``approach`` (m) along the tool axis; returns the part's name."""

    robot: str = arg(a.name)
    part: str = arg(a.name)
    approach: float = arg(a.number, 0.08, "m")

    def execute(self, session: Session) -> Any:
        return _call(session, "pick", self.robot, self.part, approach=self.approach)


@dataclass(frozen=True)
class Place(Command, wire="place"):
    """Put ``part`` (held by ``robot``) down on the part ``on``, its centroid over
    ``position`` (x, y in m; null: the centre of the support's top face); released,
    retreat ``approach`` (m)."""

    robot: str = arg(a.name)
    part: str = arg(a.name)
    on: str = arg(a.name)
    position: tuple[float, ...] | None = arg(a.optional(a.sized(2)), None, "m")
    approach: float = arg(a.number, 0.08, "m")

    def execute(self, session: Session) -> None:
        pos = None if self.position is None else np.array(self.position)
        _call(
            session,
            "place",
            self.robot,
            self.part,
            on=self.on,
            position=pos,
            approach=self.approach,
        )


@dataclass(frozen=True)
class Handover(Command, wire="handover"):
    """Hand ``part`` from ``giver`` to ``receiver`` at a meeting pose found in both
    workspaces; both back off ``approach`` (m) afterwards."""

    giver: str = arg(a.name)
    receiver: str = arg(a.name)
    part: str = arg(a.name)
    approach: float = arg(a.number, 0.08, "m")

    def execute(self, session: Session) -> None:
        _call(session, "handover", self.giver, self.receiver, self.part, approach=self.approach)


@dataclass(frozen=True)
class Wait(Command, wire="wait"):
    """Let ``seconds`` of simulated time pass."""

    seconds: float = arg(a.number, doc="s")

    def execute(self, session: Session) -> None:
        _call(session, "wait", self.seconds)


@dataclass(frozen=True)
class Play(Command, wire="play"):
    """Replay the stored frames (playback mode); ``realtime`` null: the simulator's setting.
    Returns the number of frames shown."""

    realtime: bool | None = arg(a.optional(a.boolean), None)

    def execute(self, session: Session) -> int:
        return _call(session, "play", self.realtime)


# ---------------------------------------------------------------- read-back
@dataclass(frozen=True)
class Joints(Command, wire="joints"):
    """A robot's joint values now (rad/m)."""

    robot: str = arg(a.name)

    def execute(self, session: Session) -> np.ndarray:
        return _call(session, "joints", self.robot)


@dataclass(frozen=True)
class ToolPose(Command, wire="tool_pose"):
    """A robot's tool pose now (4x4 world, m)."""

    robot: str = arg(a.name)

    def execute(self, session: Session) -> np.ndarray:
        return _call(session, "tool_pose", self.robot)


@dataclass(frozen=True)
class Held(Command, wire="held"):
    """The part a robot holds (or null)."""

    robot: str = arg(a.name)

    def execute(self, session: Session) -> Any:
        return _call(session, "held", self.robot)


@dataclass(frozen=True)
class Clearance(Command, wire="clearance"):
    """The distance (m) between two things of the cell (parts, robots)."""

    a: str = arg(_name)  # (the field ``a`` hides the module alias ``a`` in this body)
    b: str = arg(_name)

    def execute(self, session: Session) -> float:
        return _call(session, "clearance", self.a, self.b)


@dataclass(frozen=True)
class Robots(Command, wire="robots"):
    """The cell's robot names."""

    def execute(self, session: Session) -> tuple[str, ...]:
        return session.require_sim().robots


@dataclass(frozen=True)
class Frames(Command, wire="frames"):
    """Number of frames on the timeline (frame 0 is the initial state)."""

    def execute(self, session: Session) -> int:
        return session.require_sim().frames


@dataclass(frozen=True)
class SimTime(Command, wire="sim_time"):
    """The simulated clock (s)."""

    def execute(self, session: Session) -> float:
        return session.require_sim().sim_time


@dataclass(frozen=True)
class Events(Command, wire="events"):
    """The timeline's events, each {t (s), robot, kind, detail}."""

    def execute(self, session: Session) -> list[dict[str, Any]]:
        return [e.to_dict() for e in session.require_sim().events]


@dataclass(frozen=True)
class Summary(Command, wire="summary"):
    """sim_time_s, wall_time_s, frames, events, collisions, objects (part centroids, m)."""

    def execute(self, session: Session) -> dict[str, Any]:
        return _call(session, "summary")


@dataclass(frozen=True)
class PartPose(Command, wire="part_pose"):
    """World pose (4x4) of a movable part's frame (its centroid: ``part_positions``)."""

    part: str = arg(a.name)

    def execute(self, session: Session) -> np.ndarray:
        return _call(session, "part_pose", self.part)


@dataclass(frozen=True)
class GripperPose(Command, wire="gripper_pose"):
    """World pose (4x4) of a robot's gripper body."""

    robot: str = arg(a.name)

    def execute(self, session: Session) -> np.ndarray:
        return _call(session, "gripper_pose", self.robot)


@dataclass(frozen=True)
class Speed(Command, wire="speed"):
    """A robot's speed (rad/s): the speed of the joint that moves most."""

    robot: str = arg(a.name)

    def execute(self, session: Session) -> float:
        return _call(session, "speed", self.robot)


@dataclass(frozen=True)
class Trajectory(Command, wire="trajectory"):
    """Every frame of one robot: {t: simulated times (s), q: joint values (rad/m), one
    row per frame}."""

    robot: str = arg(a.name)

    def execute(self, session: Session) -> dict[str, Any]:
        t, q = _call(session, "trajectory", self.robot)
        return {"t": t, "q": q}


@dataclass(frozen=True)
class WallTime(Command, wire="wall_time"):
    """The wall clock (s): time the simulator has spent on commands and replays."""

    def execute(self, session: Session) -> float:
        return session.require_sim().wall_time


@dataclass(frozen=True)
class ConcurrentlyBegin(Command, wire="concurrently_begin"):
    """Start a block of motion commands that run at the same time (the Simulator's
    ``concurrently()``), ended by ``concurrently_end``."""

    def execute(self, session: Session) -> None:
        sim = session.require_sim()
        if session.block is not None:
            raise ProgramError("concurrently_begin: a block is open already; blocks do not nest")
        block = sim.concurrently()
        block.__enter__()  # refuses (joint-by-joint mode) before anything changes
        session.block = (sim, block)


@dataclass(frozen=True)
class ConcurrentlyEnd(Command, wire="concurrently_end"):
    """End the block: with ``commit`` run its motions together, else drop them all."""

    commit: bool = arg(a.boolean, True)

    def execute(self, session: Session) -> None:
        if session.block is None:
            raise ProgramError("concurrently_end: no block is open (concurrently_begin starts one)")
        (_sim, block), session.block = session.block, None
        if self.commit:
            block.__exit__(None, None, None)  # an error undoes the whole block and is raised
            return
        stop = ProgramError("the block was abandoned")
        block.__exit__(ProgramError, stop, None)  # undoes the block


@dataclass(frozen=True)
class PartPositions(Command, wire="part_positions"):
    """World position (m) of each movable part's centroid, by name."""

    def execute(self, session: Session) -> dict[str, list[float]]:
        return _call(session, "part_positions")
