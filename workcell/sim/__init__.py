"""Simulation (thesis ch. 4.4): the kinematic simulator, its modes and clocks, and its timeline."""

from workcell.sim.simulator import JOINT_BY_JOINT_CLOCKS, MODES, Simulator, step_times
from workcell.sim.timeline import Event, Timeline, TimelineMark

__all__ = [
    "JOINT_BY_JOINT_CLOCKS",
    "MODES",
    "Event",
    "Simulator",
    "Timeline",
    "TimelineMark",
    "step_times",
]
