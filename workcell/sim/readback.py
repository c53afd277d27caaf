"""Read-back of the simulator's state: robots, joints, tool poses, clocks, frames, events,
part positions, clearances and the run's summary (a mixin of
:class:`~workcell.sim.simulator.Simulator`; the gripper's read-back, ``held``,
``part_pose`` and ``gripper_pose``, is in :mod:`workcell.sim.gripping`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from workcell.sim.timeline import Events

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["ReadBack"]

Array = NDArray[np.float64]


class ReadBack:
    """Read-only queries of a simulator (module doc)."""

    @property
    def robots(self: Simulator) -> tuple[str, ...]:
        """The cell's robot names."""
        return tuple(self._qadr)

    @property
    def wall_time(self: Simulator) -> float:
        """The wall clock (s): time the simulator has spent on commands and replays."""
        return self._wall

    @property
    def frames(self: Simulator) -> int:
        """Number of frames on the timeline (frame 0 is the initial state)."""
        return len(self.timeline)

    @property
    def events(self: Simulator) -> Events:
        """The timeline's events, in order: ``sim.events()`` (read-outs are calls), or
        ``sim.events`` (the same tuple)."""
        return self.timeline.events

    def joints(self: Simulator, robot: str) -> Array:
        """The robot's current joint values (rad/m), a copy."""
        return self.data.qpos[self._qadr[self._robot(robot)]].copy()

    def tool_pose(self: Simulator, robot: str) -> Array:
        """The robot's current tool pose in the world (4x4), from MuJoCo's tool site."""
        i = self._site[self._robot(robot)]
        T = np.eye(4)
        T[:3, :3] = self.data.site_xmat[i].reshape(3, 3)
        T[:3, 3] = self.data.site_xpos[i]
        return T

    def speed(self: Simulator, robot: str) -> float:
        """The robot's speed (rad/s): the speed of the joint that moves most."""
        return self._speed[self._robot(robot)]

    def trajectory(self: Simulator, robot: str) -> tuple[Array, Array]:
        """(simulated times (N,), joint values (N, dof)) of every frame for one robot."""
        adr = self._qadr[self._robot(robot)]
        return self.timeline.sim_times(), self.timeline.qpos()[:, adr]

    def part_positions(self: Simulator) -> dict[str, list[float]]:
        """World position (m) of each movable part's centroid, by name: the point grasps
        aim at and ``place`` sets down (``part_pose`` gives the part frame's pose)."""
        d = self.data
        return {
            p: (d.xpos[b] + d.xmat[b].reshape(3, 3) @ self._centroids[p]).tolist()
            for p, b in self._part_body.items()
        }

    def clearance(self: Simulator, a: str, b: str) -> float:
        """Minimum distance (m) between two things now; negative: penetration depth.

        A thing is a robot (all its links and gripper), a link or gripper body
        (``"puma_1.link3"``), a movable or static part, or ``"ground"``; the distance is
        MuJoCo's ``mj_geomDistance`` between their convex collision pieces.
        """
        return self.contacts.clearance(self.data, a, b)[0]

    def summary(self: Simulator) -> dict[str, Any]:
        """The DESIGN.md ``workcell demo --json`` fields this slice knows (``mjcf`` None),
        and ``commands``: the cycle-time records (:meth:`cycle_time`)."""
        return {
            "sim_time_s": self.sim_time,
            "wall_time_s": self._wall,
            "frames": self.frames,
            "events": [e.to_dict() for e in self.events],
            "collisions": sum(1 for e in self.events if e.kind == "collision"),
            "objects": self.part_positions(),
            "mjcf": None,
            "commands": self.cycle_time()["commands"],
        }
