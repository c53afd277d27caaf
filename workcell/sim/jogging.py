"""Jogging: setting a robot's joints at once, as a teach pendant does (a mixin of
:class:`~workcell.sim.simulator.Simulator`).

``Simulator.jog(robot, q)`` puts the robot's joints at ``q`` (rad/m) with no simulated
time passing: one frame at the current time (a part the robot holds moves with its
gripper; contacts are checked as for any frame) and a ``jog`` event, whose data says
what an exported robot program does there (a joint move to ``q``: a real robot cannot
jump; :mod:`workcell.robotprog`). A target outside
the joint limits raises :class:`~workcell.errors.JointLimitError` naming the joint and its
range, and changes nothing. The live view (:mod:`workcell.view`) calls it for its joint
inputs and its tool gizmo.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["JogCommands"]


class JogCommands:
    """``jog`` (module doc)."""

    def jog(self: Simulator, robot: str, q: ArrayLike) -> None:
        """Set the robot's joints to ``q`` (rad, m for prismatic joints) at once: no
        simulated time passes; one frame and a ``jog`` event are recorded. Outside the
        joint limits: JointLimitError, nothing changes."""
        name = self._robot(robot)
        self._not_in_block("jog")
        target = self._vector(name, q, "jog", "q")
        self._check_target(name, target, "jog")
        carried = self._carried(name)  # refuses a robot sharing a part with another
        with self._transaction():
            row = self.data.qpos.copy()
            row[self._qadr[name]] = target
            self._emit(np.array([self.sim_time]), row[None, :], carried, name)
            revolute = self.cell.robots[name].robot.revolute
            shown = np.where(revolute, np.degrees(target), target * 1e3)
            text = ", ".join(f"{v:.6g}" for v in shown)
            unit = "deg" if all(revolute) else "deg/mm"
            # what an exported robot program does here: a joint move to the jogged joints
            # (:mod:`workcell.robotprog`); not a timed command (no cycle-time record)
            asked = {"kind": "joint", "q": target.tolist(), "zone": 0.0, "jog": True}
            rec = {
                "robot": name,
                "t_start": self.sim_time,
                "duration_s": 0.0,
                "program": self._program_settings(name, asked),
            }
            self.timeline.add_event(self.sim_time, name, "jog", f"jog to ({text}) {unit}", data=rec)
