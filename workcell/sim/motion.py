"""Motion like an industrial controller: profiles, override, linear and circular moves,
zones, and the cycle-time report (a mixin of :class:`~workcell.sim.simulator.Simulator`).

- **Profiles** (``Simulator(profile=...)``, :meth:`MotionCommands.set_profile`): the
  thesis's constant speed ``"linear"`` (the default, so the thesis's examples keep their
  times), ``"trapezoid"``, ``"quintic"`` (all three run at the robot's one speed,
  ``set_speed``), and ``"jerk"``: every joint move is the time-optimal, synchronised,
  jerk-limited motion under each joint's own speed, acceleration and jerk limits
  (:mod:`workcell.sim.jerk`; a robot without finite limits raises ProgramError).
- **Override** (:meth:`MotionCommands.set_override`): the teach pendant's speed override
  f in (0, 1]: joint and tool speeds x f, accelerations x f^2, jerks x f^3, the robot's
  thesis speed x f: the same path in 1/f the time.
- **Linear and circular moves** (:meth:`MotionCommands.move_linear`,
  :meth:`MotionCommands.move_circular`): the tool point on the line or arc at the
  programmed tool speed and acceleration, orientation slerped, timed under the joints'
  limits too (:mod:`workcell.sim.timing`), in every mode. Under profile "jerk",
  ``move_straight_line`` is timed the same way with no tool speed (as fast as the joints
  allow); under the thesis profiles it keeps the thesis's timing.
- **Zones** (``zone`` m on joint, linear and circular moves): see
  :mod:`workcell.sim.blending` (a zone move stops until the next motion command of the
  same robot takes its tail back and runs the corner).
- **Cycle time** (:meth:`MotionCommands.cycle_time`, ``summary()["commands"]``): one
  record per command (:mod:`workcell.sim.cycle`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.checks import is_finite_number
from workcell.errors import ProgramError
from workcell.sim import profiles
from workcell.sim.cartesian import world_target
from workcell.sim.cycle import cycle_report
from workcell.sim.motion_run import DEFAULT_TOOL_ACCELERATION, MotionRunner
from workcell.sim.paths import CartesianPath, Line, arc_through
from workcell.spatial import invert

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["DEFAULT_TOOL_ACCELERATION", "MotionCommands"]

Array = NDArray[np.float64]


class MotionCommands(MotionRunner):
    """Profiles, override, linear/circular moves, zones, cycle time (module doc)."""

    # ------------------------------------------------------------------ settings
    def set_override(self: Simulator, robot: str, override: float) -> None:
        """Set the robot's speed override f, 0 < f <= 1 (module doc): its moves keep their
        paths and take 1/f the time."""
        name = self._robot(robot)
        if not (is_finite_number(override) and 0.0 < float(override) <= 1.0):
            raise ProgramError(
                f"set_override '{name}': the override must be a number in (0, 1] "
                f"(1: full speed, 0.5: 50 %), got {override!r}"
            )
        self._not_in_block("set_override")
        self._override[name] = float(override)
        self.timeline.add_event(self.sim_time, name, "override", f"override {override:.4g}")

    def set_profile(self: Simulator, profile: str, acceleration: float | None = None) -> None:
        """Set the joint-move profile: "linear", "trapezoid", "quintic" or "jerk";
        ``acceleration`` (rad/s^2): the trapezoid's acceleration (default: unchanged)."""
        if profile not in profiles.PROFILES:
            raise ProgramError(
                f"unknown profile {profile!r}; valid: {', '.join(profiles.PROFILES)}"
            )
        if acceleration is not None and not (is_finite_number(acceleration) and acceleration > 0):
            raise ProgramError(
                f"set_profile: acceleration must be a number of rad/s^2 > 0, got {acceleration!r}"
            )
        self._not_in_block("set_profile")
        self.profile = profile
        if acceleration is not None:
            self.acceleration = float(acceleration)
        self.timeline.add_event(self.sim_time, None, "profile", f"profile {profile}")

    def cycle_time(self: Simulator) -> dict[str, Any]:
        """The cycle-time report: ``total_s`` (the simulated clock, s) and ``commands`` (one
        record per command, see :mod:`workcell.sim.cycle`)."""
        return cycle_report(self.timeline.events, self.sim_time)

    # ------------------------------------------------------------------ Cartesian moves
    def move_linear(
        self: Simulator,
        robot: str,
        T: ArrayLike,
        *,
        speed: float,
        acceleration: float | None = None,
        zone: float = 0.0,
    ) -> None:
        """Move the tool point along the straight line to world pose ``T`` (4x4, m) at
        ``speed`` (m/s) and ``acceleration`` (m/s^2, default 1.2), orientation slerped;
        slower only where the joints' limits demand. ``zone`` (m): blend into the next
        move. UnreachableError says where the line cannot be followed."""
        command = "move_linear"
        name = self._robot(robot)
        target = world_target(T, command, name)
        v, a, z = self._tool_args(command, name, speed, acceleration, zone)
        start = self.tool_pose(name)
        line = Line(start[:3, 3], target[:3, 3], start[:3, :3], target[:3, :3])
        if line.length <= 1e-9:
            raise ProgramError(
                f"{command} '{name}': the tool point would not move (a pure turn of the tool "
                "has no tool speed); use move_end_effector or move_straight_line"
            )
        detail = f"{line.length * 1e3:.4g} mm line at {v * 1e3:.4g} mm/s"
        program = _asked("linear", self, name, target, v, a, z)
        self._path_move(name, command, detail, CartesianPath([line]), v, a, z, program=program)

    def move_circular(
        self: Simulator,
        robot: str,
        via: ArrayLike,
        T: ArrayLike,
        *,
        speed: float,
        acceleration: float | None = None,
        zone: float = 0.0,
    ) -> None:
        """Move the tool point along the circle through its current position, ``via`` (a
        point (3,) or a pose (4x4), world, m) and the position of ``T`` (4x4), to ``T``,
        at ``speed`` (m/s), orientation slerped from the start to T's. Collinear points
        raise ProgramError; otherwise as :meth:`move_linear`."""
        command = "move_circular"
        name = self._robot(robot)
        target = world_target(T, command, name)
        p_via = _via_point(via, name)
        v, a, z = self._tool_args(command, name, speed, acceleration, zone)
        start = self.tool_pose(name)
        arc = arc_through(
            start[:3, 3], p_via, target[:3, 3], start[:3, :3], target[:3, :3], f"{command} '{name}'"
        )
        detail = f"{arc.length * 1e3:.4g} mm arc (radius {arc.radius * 1e3:.4g} mm) at {v * 1e3:.4g} mm/s"
        program = _asked("circular", self, name, target, v, a, z)
        program["via"] = (invert(self.cell.robots[name].base) @ np.append(p_via, 1.0))[:3].tolist()
        self._path_move(name, command, detail, CartesianPath([arc]), v, a, z, program=program)

    # ------------------------------------------------------------------ internals


def _asked(
    kind: str, sim: Simulator, name: str, target: Array, v: float, a: float, z: float
) -> dict[str, Any]:
    """A Cartesian move's ``program`` record (:mod:`workcell.sim.cycle`): the target in the
    robot's base frame, the tool speed and acceleration before the override, the zone."""
    Tb = invert(sim.cell.robots[name].base) @ target
    return {"kind": kind, "pose": Tb.tolist(), "speed": v, "acceleration": a, "zone": z}


def _via_point(via: ArrayLike, name: str) -> Array:
    try:
        v = np.asarray(via, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ProgramError(
            f"move_circular '{name}': via must be a point (3,) or a pose (4x4)"
        ) from exc
    if v.shape == (4, 4):
        v = v[:3, 3]
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ProgramError(
            f"move_circular '{name}': via must be a point (3 numbers, m) or a 4x4 pose, got shape {v.shape}"
        )
    return v
