"""What a physics run reports (see :mod:`workcell.sim.physics`): tracking, settled parts.

:class:`PhysicsResult` has the attributes the recording and rendering code reads from a
:class:`~workcell.sim.simulator.Simulator` (``cell``, ``compiled``, ``model``, ``data``,
``timeline``, ``events``, ``robots``, ``frames``, ``sim_time``, ``wall_time``), so a
physics run is recorded or rendered like a kinematic one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.cell.compile import CompiledCell
from workcell.cell.workcell import Workcell
from workcell.sim.timeline import Events, Timeline
from workcell.spatial import pose_from_pos_quat

__all__ = ["PhysicsResult", "SettledPart", "Tracking"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Tracking:
    """How closely one robot followed its plan while the program ran.

    ``joint_max`` and ``joint_rms`` (rad): the largest and the root-mean-square arm joint
    error (actual - planned) over every physics step and joint; ``joint_max_each`` (dof,)
    the largest per joint; ``tool_max`` and ``tool_rms`` (m): the distance between the
    actual tool point and the planned one (forward kinematics of the planned joints);
    ``peak_force`` (dof,): the largest actuator force of each arm joint (N m; N for a
    prismatic joint), what the (unlimited) servos needed.
    """

    joint_max: float
    joint_rms: float
    joint_max_each: Array
    tool_max: float
    tool_rms: float
    peak_force: Array

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able values (units in the key names)."""
        return {
            "joint_max_rad": self.joint_max,
            "joint_rms_rad": self.joint_rms,
            "joint_max_each_rad": self.joint_max_each.tolist(),
            "tool_max_m": self.tool_max,
            "tool_rms_m": self.tool_rms,
            "peak_force": self.peak_force.tolist(),
        }


@dataclass(frozen=True)
class SettledPart:
    """A movable part at the end of a physics run (after settling).

    ``position`` (3,, m) and ``quat`` (wxyz) the world pose of its body frame;
    ``kinematic_position`` and ``kinematic_quat`` where the kinematic run left it;
    ``distance`` (m) between the two positions and ``angle`` (rad) between the two
    orientations; ``speed`` (m/s) and ``angular_speed`` (rad/s) at the end, ``resting``
    when both are small (below 1 mm/s and 0.01 rad/s); ``carry_error`` (m) and
    ``carry_angle`` (rad): the largest deviation of the part from its gripper pose x weld
    pose while it was held (NaN if never held).
    """

    name: str
    position: Array
    quat: Array
    kinematic_position: Array
    kinematic_quat: Array
    distance: float
    angle: float
    speed: float
    angular_speed: float
    carry_error: float = float("nan")
    carry_angle: float = float("nan")

    @classmethod
    def of(
        cls,
        name: str,
        pose: Array,
        velocity: Array,
        kinematic: Array,
        carry: tuple[float, float] | None = None,
    ) -> SettledPart:
        """From free-joint values: ``pose`` (7: position, wxyz), ``velocity`` (6: linear
        m/s, angular rad/s), the kinematic result's ``kinematic`` pose (7) and the largest
        carry deviations (m, rad; None: never held)."""
        pos, quat = np.array(pose[:3], dtype=float), np.array(pose[3:7], dtype=float)
        kpos, kquat = np.array(kinematic[:3], dtype=float), np.array(kinematic[3:7], dtype=float)
        dot = min(abs(float(quat @ kquat)) / (np.linalg.norm(quat) * np.linalg.norm(kquat)), 1.0)
        e, a = carry if carry is not None else (float("nan"), float("nan"))
        return cls(
            name,
            pos,
            quat,
            kpos,
            kquat,
            distance=float(np.linalg.norm(pos - kpos)),
            angle=2.0 * math.acos(dot),
            speed=float(np.linalg.norm(velocity[:3])),
            angular_speed=float(np.linalg.norm(velocity[3:6])),
            carry_error=float(e),
            carry_angle=float(a),
        )

    @property
    def resting(self) -> bool:
        """True when the part has come to rest (speed < 1 mm/s, angular < 0.01 rad/s)."""
        return self.speed < 1e-3 and self.angular_speed < 1e-2

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able values (units in the key names)."""
        return {
            "position_m": self.position.tolist(),
            "kinematic_position_m": self.kinematic_position.tolist(),
            "distance_m": self.distance,
            "angle_rad": self.angle,
            "speed_m_s": self.speed,
            "angular_speed_rad_s": self.angular_speed,
            "resting": self.resting,
            "carry_error_m": None if np.isnan(self.carry_error) else self.carry_error,
            "carry_angle_rad": None if np.isnan(self.carry_angle) else self.carry_angle,
        }


@dataclass
class PhysicsResult:
    """A physics run of a program (see :func:`workcell.sim.physics.run_physics`).

    ``model`` and ``data``: the physics model (a copy of the simulator's, with its
    ``timestep``, s) and its final state; ``timeline``: the physics frames sampled at
    ``dt`` (the kinematic run's sampling interval, s), full ``qpos`` as the simulator's;
    ``events``: the plan's commands, the physics grasps and releases, collisions and the
    settled parts; ``sim_time`` (s): the program's duration plus ``settle``;
    ``wall_time`` (s): the wall time of the physics loop; ``tracking`` per robot;
    ``parts`` per movable part; ``commands``: the plan's cycle-time records (the program
    the physics replays, :mod:`workcell.sim.cycle`).
    """

    cell: Workcell
    compiled: CompiledCell
    model: mujoco.MjModel
    data: mujoco.MjData
    timeline: Timeline
    dt: float
    timestep: float
    settle: float
    program_time: float
    sim_time: float
    wall_time: float
    tracking: dict[str, Tracking] = field(default_factory=dict)
    parts: dict[str, SettledPart] = field(default_factory=dict)
    options: dict[str, Any] = field(default_factory=dict)
    commands: list[dict[str, Any]] = field(default_factory=list)

    @property
    def events(self) -> Events:
        """The timeline's events: ``result.events()`` or ``result.events`` (the same)."""
        return self.timeline.events

    @property
    def robots(self) -> tuple[str, ...]:
        """The cell's robot names."""
        return tuple(self.compiled.joint_names)

    @property
    def frames(self) -> int:
        """Number of frames on the timeline."""
        return len(self.timeline)

    @property
    def steps(self) -> int:
        """Number of physics steps (``mj_step`` calls)."""
        return round(self.sim_time / self.timestep)

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second of the physics loop."""
        return self.sim_time / self.wall_time if self.wall_time > 0 else float("inf")

    def part_positions(self) -> dict[str, list[float]]:
        """World position (m) of each movable part's centroid at the end, by name (as
        :meth:`Simulator.part_positions <workcell.sim.simulator.Simulator.part_positions>`)."""
        return {
            p: (pose_from_pos_quat(s.position, s.quat) @ self.cell.centroid_frame(p))[
                :3, 3
            ].tolist()
            for p, s in self.parts.items()
        }

    def summary(self) -> dict[str, Any]:
        """The DESIGN.md ``workcell demo --json`` fields, plus ``physics``: timestep,
        settle time, steps, real-time factor, tracking per robot and settled parts."""
        return {
            "sim_time_s": self.sim_time,
            "wall_time_s": self.wall_time,
            "frames": self.frames,
            "events": [e.to_dict() for e in self.events],
            "collisions": sum(1 for e in self.events if e.kind == "collision"),
            "objects": self.part_positions(),
            "mjcf": None,
            "commands": [dict(c) for c in self.commands],
            "physics": {
                "timestep_s": self.timestep,
                "settle_s": self.settle,
                "program_time_s": self.program_time,
                "steps": self.steps,
                "real_time_factor": self.real_time_factor,
                "options": dict(self.options),
                "tracking": {r: t.to_dict() for r, t in self.tracking.items()},
                "parts": {p: s.to_dict() for p, s in self.parts.items()},
            },
        }

    def __repr__(self) -> str:
        worst = max((t.tool_max for t in self.tracking.values()), default=0.0)
        moved = max((s.distance for s in self.parts.values()), default=0.0)
        return (
            f"PhysicsResult(cell '{self.cell.name}', {self.frames} frames, "
            f"t_sim={self.sim_time:.6g} s, {self.real_time_factor:.3g}x real time, "
            f"tool error <= {worst * 1e3:.3g} mm, parts within {moved * 1e3:.3g} mm "
            f"of the kinematic result)"
        )
