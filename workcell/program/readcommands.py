"""The command vocabulary, read-backs: what a simulation holds now (joint values, tool,
part and gripper poses, the part held, clearances, speeds) and its clocks and records
(``sim_time``, ``wall_time``, frames, events, the summary, a robot's trajectory, the
cycle-time report). SI values (rad, m, s). Re-exported by
:mod:`workcell.program.simcommands`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from workcell.program import args as a
from workcell.program.args import arg
from workcell.program.base import Command
from workcell.program.runcommands import call_sim

if TYPE_CHECKING:
    from workcell.program.session import Session

__all__ = [
    "Clearance",
    "CycleTime",
    "Events",
    "Frames",
    "GripperPose",
    "Held",
    "Joints",
    "PartPose",
    "PartPositions",
    "Robots",
    "SimTime",
    "Speed",
    "Summary",
    "ToolPose",
    "Trajectory",
    "WallTime",
]

_name = a.name


@dataclass(frozen=True)
class CycleTime(Command, wire="cycle_time"):
    """The cycle-time report: total_s and, per command, robot, command, t_start (s),
    duration_s, limited_by (the limit that set its time), zone_m."""

    def execute(self, session: Session) -> dict[str, Any]:
        return call_sim(session, "cycle_time")


@dataclass(frozen=True)
class Joints(Command, wire="joints"):
    """A robot's joint values now (rad/m)."""

    robot: str = arg(a.name)

    def execute(self, session: Session) -> np.ndarray:
        return call_sim(session, "joints", self.robot)


@dataclass(frozen=True)
class ToolPose(Command, wire="tool_pose"):
    """A robot's tool pose now (4x4 world, m)."""

    robot: str = arg(a.name)

    def execute(self, session: Session) -> np.ndarray:
        return call_sim(session, "tool_pose", self.robot)


@dataclass(frozen=True)
class Held(Command, wire="held"):
    """The part a robot holds (or null)."""

    robot: str = arg(a.name)

    def execute(self, session: Session) -> Any:
        return call_sim(session, "held", self.robot)


@dataclass(frozen=True)
class Clearance(Command, wire="clearance"):
    """The distance (m) between two things of the cell (parts, robots)."""

    a: str = arg(_name)  # (the field ``a`` hides the module alias ``a`` in this body)
    b: str = arg(_name)

    def execute(self, session: Session) -> float:
        return call_sim(session, "clearance", self.a, self.b)


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
        events = session.require_sim().events
        session.check_reply(4 * len(events), "events")  # 4 fields each
        return [e.to_dict() for e in events]


@dataclass(frozen=True)
class Summary(Command, wire="summary"):
    """sim_time_s, wall_time_s, frames, events, collisions, objects (part centroids, m)."""

    def execute(self, session: Session) -> dict[str, Any]:
        return call_sim(session, "summary")


@dataclass(frozen=True)
class PartPose(Command, wire="part_pose"):
    """World pose (4x4) of a movable part's frame (its centroid: ``part_positions``)."""

    part: str = arg(a.name)

    def execute(self, session: Session) -> np.ndarray:
        return call_sim(session, "part_pose", self.part)


@dataclass(frozen=True)
class GripperPose(Command, wire="gripper_pose"):
    """World pose (4x4) of a robot's gripper body."""

    robot: str = arg(a.name)

    def execute(self, session: Session) -> np.ndarray:
        return call_sim(session, "gripper_pose", self.robot)


@dataclass(frozen=True)
class Speed(Command, wire="speed"):
    """A robot's speed (rad/s): the speed of the joint that moves most."""

    robot: str = arg(a.name)

    def execute(self, session: Session) -> float:
        return call_sim(session, "speed", self.robot)


@dataclass(frozen=True)
class Trajectory(Command, wire="trajectory"):
    """Every frame of one robot: {t: simulated times (s), q: joint values (rad/m), one
    row per frame}."""

    robot: str = arg(a.name)

    def execute(self, session: Session) -> dict[str, Any]:
        sim = session.require_sim()
        if self.robot in sim.robots:  # a server's reply bound, before anything is built
            dof = sim.cell.robots[self.robot].robot.dof
            session.check_reply(sim.frames * (dof + 1), f"trajectory '{self.robot}'")
        t, q = call_sim(session, "trajectory", self.robot)
        return {"t": t, "q": q}


@dataclass(frozen=True)
class WallTime(Command, wire="wall_time"):
    """The wall clock (s): time the simulator has spent on commands and replays."""

    def execute(self, session: Session) -> float:
        return session.require_sim().wall_time


@dataclass(frozen=True)
class PartPositions(Command, wire="part_positions"):
    """World position (m) of each movable part's centroid, by name."""

    def execute(self, session: Session) -> dict[str, list[float]]:
        return call_sim(session, "part_positions")
