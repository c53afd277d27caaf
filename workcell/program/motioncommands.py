"""The command vocabulary, motion commands: joint moves (``move_joints_absolute``,
``move_joints_relative``), tool moves (``move_end_effector``, ``move_straight_line``,
``move_linear``, ``move_circular``), each with a blend ``zone`` (m), and a robot's motion
settings (``set_speed``, ``set_override``, ``set_profile``). SI arguments (rad, m, s); a
pose is a :class:`~workcell.program.targets.Target`. Re-exported by
:mod:`workcell.program.simcommands`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from workcell.errors import ProgramError
from workcell.program import args as a
from workcell.program.args import arg
from workcell.program.base import Command
from workcell.program.runcommands import call_sim
from workcell.program.targets import Target, target, via_target
from workcell.sim.profiles import PROFILES

if TYPE_CHECKING:
    from workcell.program.session import Session

__all__ = [
    "MoveCircular",
    "MoveEndEffector",
    "MoveJointsAbsolute",
    "MoveJointsRelative",
    "MoveLinear",
    "MoveStraightLine",
    "SetOverride",
    "SetProfile",
    "SetSpeed",
]


@dataclass(frozen=True)
class SetSpeed(Command, wire="set_speed"):
    """Set a robot's speed (rad/s): the speed of the joint that moves most."""

    robot: str = arg(a.name)
    speed: float = arg(a.number, doc="rad/s")

    def execute(self, session: Session) -> None:
        call_sim(session, "set_speed", self.robot, self.speed)


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
        call_sim(session, "move_joints_absolute", self.robot, q, plan=self.plan, zone=self.zone)


@dataclass(frozen=True)
class Jog(Command, wire="jog"):
    """Set a robot's joints to ``q`` (rad/m) at once: no simulated time passes (one frame,
    a ``jog`` event), as a teach pendant or the live view's inputs do."""

    robot: str = arg(a.name)
    q: tuple[float, ...] = arg(a.vector, doc="rad/m")

    def execute(self, session: Session) -> None:
        call_sim(session, "jog", self.robot, np.array(self.q))


@dataclass(frozen=True)
class MoveJointsRelative(Command, wire="move_joints_relative"):
    """Move a robot's joints by ``dq`` (rad/m); ``zone`` (m): blend into the next move."""

    robot: str = arg(a.name)
    dq: tuple[float, ...] = arg(a.vector, doc="rad/m")
    zone: float = arg(a.number, 0.0, "m")

    def execute(self, session: Session) -> None:
        call_sim(session, "move_joints_relative", self.robot, np.array(self.dq), zone=self.zone)


@dataclass(frozen=True)
class MoveEndEffector(Command, wire="move_end_effector"):
    """Move the tool to pose ``T`` (IK, then a joint move); ``config`` picks the
    configuration (letters l|r, u|d, n|f; default: the nearest solution whose joint move
    is clear, named in the move's event); ``plan``: along a collision-free path; ``zone``
    (m): blend into the next move."""

    robot: str = arg(a.name)
    T: Target = arg(target)  # noqa: RUF009 - arg() returns a dataclasses.field
    config: str | None = arg(a.optional(a.name), None)
    plan: bool = arg(a.boolean, False)
    zone: float = arg(a.number, 0.0, "m")

    def execute(self, session: Session) -> None:
        T = self.T.resolve(session, self.robot)
        call_sim(
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
        call_sim(session, "move_straight_line", self.robot, T, step=self.step)


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
        call_sim(
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
        call_sim(
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
        call_sim(session, "set_override", self.robot, self.override)


@dataclass(frozen=True)
class SetProfile(Command, wire="set_profile"):
    """Set the joint-move profile: the thesis's linear, trapezoid, quintic (the robot's
    speed), or jerk (each joint's speed, acceleration and jerk limits);
    ``acceleration`` (rad/s^2): the trapezoid's."""

    profile: str = arg(a.choice(*PROFILES))
    acceleration: float | None = arg(a.optional(a.number), None, "rad/s^2")

    def execute(self, session: Session) -> None:
        call_sim(session, "set_profile", self.profile, self.acceleration)
