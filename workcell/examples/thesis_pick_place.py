"""The thesis's example 2 (ch. 5): pick and place with one Puma 260.

One Puma 260 with a parallel-jaw gripper on a table, a movable aluminium cube (40 mm)
and two fixed stages. The thesis's program: move_end_effector to a grasp pose over the
cube; close_gripper; move_end_effector above stage 1; open_gripper; move_joints_absolute
home. Here each grasp and release is approached and left along a vertical straight line
(``move_straight_line``, 100 mm), so the fingers never sweep through the table or the
cube; the cube is set down with its bottom face on stage 1's top and stays there.
"""

from __future__ import annotations

import numpy as np

from workcell import solids
from workcell.cell.workcell import Workcell
from workcell.examples import run_program
from workcell.sim.grasp import tool_down
from workcell.sim.simulator import Simulator
from workcell.sim.tasks import pick, place
from workcell.spatial import translation

__all__ = [
    "CONFIG",
    "CUBE",
    "CUBE_SIZE",
    "ROBOT",
    "SPEED",
    "STAGE_1",
    "STAGE_1_TOP",
    "build",
    "place_position",
    "program",
    "run",
]

ROBOT = "puma"
CUBE = "cube"
STAGE_1 = "stage_1"
SPEED = 0.3  # rad/s, the thesis's nominal speed
CUBE_SIZE = 0.04  # m
TABLE_TOP = 0.4  # m
CUBE_CORNER = (0.28, -0.18, TABLE_TOP)  # m: the cube's part frame (a corner) on the table
STAGE_1_CENTRE = (0.24, 0.22)  # m (x, y)
STAGE_1_SIZE = (0.12, 0.12, 0.10)  # m
STAGE_1_TOP = TABLE_TOP + STAGE_1_SIZE[2]
APPROACH = 0.1  # m: vertical approach and retreat
CONFIG = "ru"  # right arm, elbow up: the Puma's usual working posture


def build() -> Workcell:
    """The cell: table, two stages, the cube, one Puma 260 with a gripper, two cameras."""
    cell = Workcell("thesis_pick_place")
    m = cell.model
    solids.box(m, "table_block", size=(1.0, 0.8, TABLE_TOP))
    solids.box(m, "stage_block", size=STAGE_1_SIZE)
    solids.cylinder(m, "stage_2_block", radius=0.06, height=0.06, n=24)
    solids.cube(m, "cube_block", size=CUBE_SIZE)
    cell.add_static("table", "table_block", translation(-0.3, -0.4, 0.0), colour=(0.55, 0.45, 0.35))
    sx, sy, _ = STAGE_1_SIZE
    cell.add_static(
        STAGE_1,
        "stage_block",
        translation(STAGE_1_CENTRE[0] - sx / 2, STAGE_1_CENTRE[1] - sy / 2, TABLE_TOP),
        colour=(0.3, 0.5, 0.8),
    )
    cell.add_static(
        "stage_2", "stage_2_block", translation(-0.15, 0.28, TABLE_TOP), colour=(0.3, 0.7, 0.5)
    )
    cell.add_movable(
        CUBE, "cube_block", translation(*CUBE_CORNER), density=2700.0, colour=(0.85, 0.2, 0.15)
    )
    cell.add_robot(ROBOT, "puma260", gripper=True, base=translation(0.0, 0.0, TABLE_TOP))
    cell.add_camera("overview", (1.3, -1.1, 1.2), (0.15, 0.0, 0.5), fovy=45)
    cell.add_camera("side", (0.2, -1.6, 0.7), (0.2, 0.0, 0.5), fovy=45)
    return cell


def grasp_position() -> np.ndarray:
    """World position (m) of the cube's centroid at the start: where the tool grasps it."""
    return np.asarray(CUBE_CORNER) + CUBE_SIZE / 2


def place_position() -> np.ndarray:
    """World position (m) of the cube's centroid when it sits on stage 1."""
    return np.array([*STAGE_1_CENTRE, STAGE_1_TOP + CUBE_SIZE / 2])


def program(sim: Simulator) -> None:
    """The thesis's pick-and-place program (with straight approach and retreat lines)."""
    sim.set_speed(ROBOT, SPEED)
    pick(sim, ROBOT, tool_down(grasp_position()), approach=APPROACH, config=CONFIG)
    place(sim, ROBOT, tool_down(place_position()), approach=APPROACH, config=CONFIG)
    sim.move_joints_absolute(ROBOT, sim.cell.robots[ROBOT].robot.poses["home"])


def run(mode: str = "path", dt: float = 0.01, **options: object) -> Simulator:
    """Build the cell, run the program in ``mode`` (playback: computed, then replayed)."""
    return run_program(build(), program, mode, dt, **options)
