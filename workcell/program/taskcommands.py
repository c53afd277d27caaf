"""The command vocabulary, grippers and task-level commands: ``close_gripper``,
``open_gripper``, ``set_planning`` (how planned moves search), ``pick``, ``place``,
``handover``. SI arguments (m, rad, s). Re-exported by
:mod:`workcell.program.simcommands`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from workcell.program import args as a
from workcell.program.args import arg
from workcell.program.base import Command
from workcell.program.runcommands import call_sim

if TYPE_CHECKING:
    from workcell.program.session import Session

__all__ = ["CloseGripper", "Handover", "OpenGripper", "Pick", "Place", "SetPlanning"]


@dataclass(frozen=True)
class CloseGripper(Command, wire="close_gripper"):
    """Close the gripper: grasp the first movable part within ``max_distance`` (m) of the
    tool with a box axis within ``max_angle`` (rad) of the tool's z axis; returns its name."""

    robot: str = arg(a.name)
    max_distance: float = arg(a.number, 0.02, "m")
    max_angle: float = arg(a.number, math.radians(10), "rad")

    def execute(self, session: Session) -> Any:
        return call_sim(
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
        return call_sim(session, "open_gripper", self.robot, settle=self.settle)


@dataclass(frozen=True)
class SetPlanning(Command, wire="set_planning"):
    """Change how planned moves search: ``clearance`` and ``near_clearance`` (m),
    ``time_limit`` (s), ``seed``; null keeps a setting. Returns the settings in force."""

    clearance: float | None = arg(a.optional(a.number), None, "m")
    time_limit: float | None = arg(a.optional(a.number), None, "s")
    seed: int | None = arg(a.optional(a.count), None)
    near_clearance: float | None = arg(a.optional(a.number), None, "m")

    def execute(self, session: Session) -> Any:
        return call_sim(
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
        return call_sim(session, "pick", self.robot, self.part, approach=self.approach)


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
        call_sim(
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
        call_sim(session, "handover", self.giver, self.receiver, self.part, approach=self.approach)
