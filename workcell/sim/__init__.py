"""Simulation (thesis ch. 4.4-4.6): the kinematic simulator, its modes and clocks, its
timeline, and the physics mode that replays a program with ``mj_step``."""

from workcell.sim.physics import run_physics
from workcell.sim.physics_result import PhysicsResult
from workcell.sim.simulator import JOINT_BY_JOINT_CLOCKS, MODES, Simulator, step_times
from workcell.sim.timeline import Event, Timeline, TimelineMark

__all__ = [
    "JOINT_BY_JOINT_CLOCKS",
    "MODES",
    "Event",
    "PhysicsResult",
    "Simulator",
    "Timeline",
    "TimelineMark",
    "run_physics",
    "step_times",
]
