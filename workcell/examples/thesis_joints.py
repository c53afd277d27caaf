"""The thesis's example 1 (ch. 5): one Puma 260 moved in joint space.

Speed 0.3 rad/s; start (0, 0, -90, 0, 90, 0) deg; ``move_joints_relative`` by
(-70, -10, 10, 30, -20, -10) deg; ``move_joints_absolute`` to (-60, 0, -70, 0, 90, 30)
deg; ``move_joints_absolute`` back to (0, 0, -90, 0, 90, 0) deg.

The joint that moves most moves 70, 40 and 60 deg in the three commands, so the
simulated time (eq. 4.27) is 170 deg / 0.3 rad/s = 9.89 s. (The thesis reports "about
14 sec" for this program; its figure is not reproducible from its own formula.)
"""

from __future__ import annotations

import itertools

import numpy as np

from workcell.cell.workcell import Workcell
from workcell.examples import run_program
from workcell.sim.simulator import Simulator

__all__ = [
    "ABSOLUTE_DEG",
    "RELATIVE_DEG",
    "ROBOT",
    "SPEED",
    "START_DEG",
    "build",
    "expected_sim_time",
    "program",
    "run",
]

ROBOT = "puma"
SPEED = 0.3  # rad/s
START_DEG = (0.0, 0.0, -90.0, 0.0, 90.0, 0.0)
RELATIVE_DEG = (-70.0, -10.0, 10.0, 30.0, -20.0, -10.0)
ABSOLUTE_DEG = (-60.0, 0.0, -70.0, 0.0, 90.0, 30.0)


def build() -> Workcell:
    """The cell: one Puma 260 (no gripper) with its base at the origin, at the start pose."""
    cell = Workcell("thesis_joints")
    cell.add_robot(ROBOT, "puma260", q=np.radians(START_DEG))
    return cell


def program(sim: Simulator) -> None:
    """The thesis's program for example 1, run on ``sim``."""
    sim.set_speed(ROBOT, SPEED)
    sim.move_joints_relative(ROBOT, np.radians(RELATIVE_DEG))
    sim.move_joints_absolute(ROBOT, np.radians(ABSOLUTE_DEG))
    sim.move_joints_absolute(ROBOT, np.radians(START_DEG))


def run(mode: str = "path", dt: float = 0.01, *, realtime: bool = False) -> Simulator:
    """Build the cell, run the program in ``mode`` (playback: computed, then replayed)."""
    return run_program(build(), program, mode, dt, realtime=realtime)


def expected_sim_time(speed: float = SPEED) -> float:
    """The hand formula: sum over commands of max |Delta theta| / speed (s)."""
    start = np.radians(START_DEG)
    after_rel = start + np.radians(RELATIVE_DEG)
    poses = [start, after_rel, np.radians(ABSOLUTE_DEG), start]
    return sum(float(np.max(np.abs(b - a))) for a, b in itertools.pairwise(poses)) / speed
