"""The thesis's example 3 (ch. 5): two Puma 260s hand a sphere over.

Two Puma 260s, each on its own table, and a movable steel sphere (50 mm) on puma_1's
table. The thesis's program: puma_1 grasps the sphere and brings it to a point in both
workspaces; puma_2 reaches the same point with a grasping orientation and closes its
gripper; puma_1 opens and returns home; puma_2 places the sphere on its own table and
returns home.

Here puma_1 holds the sphere from above (tool z down, fingers closing along the world's
y axis) and puma_2 takes it from the side (tool z along -x, fingers closing along the
vertical), so the two grippers never meet; puma_1's fingers are 70 mm long to leave room
above the sphere for puma_2's upper finger. Every grasp and release is approached and
left along a straight line (puma_2 waits 80 mm back from the handoff point while puma_1
brings the sphere down to it), and puma_2 turns the sphere to a top grasp before setting
it down on its table.
"""

from __future__ import annotations

import numpy as np

from workcell import solids
from workcell.cell.workcell import Workcell
from workcell.examples import run_program
from workcell.sim.grasp import tool_down
from workcell.sim.simulator import Simulator
from workcell.sim.tasks import approach_pose, pick, place
from workcell.spatial import rot_z, translation

__all__ = [
    "GIVER",
    "HANDOFF",
    "PLACE",
    "RADIUS",
    "RECEIVER",
    "SPHERE",
    "SPHERE_START",
    "TABLE_TOP",
    "build",
    "program",
    "run",
    "side_grasp",
]

GIVER, RECEIVER, SPHERE = "puma_1", "puma_2", "sphere"
SPEED = 0.3  # rad/s
RADIUS = 0.025  # m
TABLE_TOP = 0.4  # m
BASE_2 = (0.85, 0.0)  # m: puma_2's base (x, y); puma_1's is the origin
SPHERE_START = np.array([0.22, -0.15, TABLE_TOP + RADIUS])  # m: centre, on table 1
HANDOFF = np.array([0.38, 0.0, 0.6])  # m: the sphere's centre at the handoff
PLACE = np.array([0.62, 0.15, TABLE_TOP + RADIUS])  # m: centre, on table 2
APPROACH = 0.08  # m
CONFIG = "ru"


def build() -> Workcell:
    """The cell: two tables, two Puma 260s with grippers, the sphere, two cameras."""
    cell = Workcell("thesis_handoff")
    m = cell.model
    solids.box(m, "table_block", size=(0.6, 0.6, TABLE_TOP))
    solids.sphere(m, "sphere_block", radius=RADIUS, m=24, n=12)
    wood = (0.55, 0.45, 0.35)
    cell.add_static("table_1", "table_block", translation(-0.3, -0.3, 0.0), colour=wood)
    cell.add_static(
        "table_2", "table_block", translation(BASE_2[0] - 0.3, BASE_2[1] - 0.3, 0.0), colour=wood
    )
    cell.add_movable(
        SPHERE, "sphere_block", translation(*SPHERE_START), density=7800.0, colour=(0.8, 0.8, 0.85)
    )
    cell.add_robot(
        GIVER, "puma260", gripper={"finger_length": 0.07}, base=translation(0.0, 0.0, TABLE_TOP)
    )
    cell.add_robot(
        RECEIVER, "puma260", gripper=True, base=translation(*BASE_2, TABLE_TOP) @ rot_z(np.pi)
    )
    cell.add_camera("overview", (0.42, -1.7, 1.3), (0.42, 0.0, 0.5), fovy=50)
    cell.add_camera("handoff", (0.38, -0.6, 0.75), tuple(HANDOFF), fovy=40)
    return cell


def side_grasp(position: np.ndarray) -> np.ndarray:
    """puma_2's grasp pose at ``position`` (m): tool z along the world's -x axis (towards
    puma_1), fingers closing along the vertical."""
    T = np.eye(4)
    T[:3, :3] = [[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    T[:3, 3] = position
    return T


def program(sim: Simulator) -> None:
    """The thesis's handoff program (with straight approach and retreat lines)."""
    for robot in (GIVER, RECEIVER):
        sim.set_speed(robot, SPEED)
    give, take = tool_down(HANDOFF), side_grasp(HANDOFF)
    pick(sim, GIVER, tool_down(SPHERE_START), approach=APPROACH, config=CONFIG)
    sim.move_end_effector(RECEIVER, approach_pose(take, APPROACH), config=CONFIG)
    sim.move_end_effector(GIVER, approach_pose(give, APPROACH), config=CONFIG)
    sim.move_straight_line(GIVER, give)
    sim.move_straight_line(RECEIVER, take)
    sim.close_gripper(RECEIVER)
    sim.open_gripper(GIVER)
    sim.move_straight_line(GIVER, approach_pose(give, APPROACH))
    sim.move_joints_absolute(GIVER, sim.cell.robots[GIVER].robot.poses["home"])
    sim.move_straight_line(RECEIVER, approach_pose(take, APPROACH))
    place(sim, RECEIVER, tool_down(PLACE), approach=APPROACH, config=CONFIG)
    sim.move_joints_absolute(RECEIVER, sim.cell.robots[RECEIVER].robot.poses["home"])


def run(mode: str = "path", dt: float = 0.01, **options: object) -> Simulator:
    """Build the cell, run the program in ``mode`` (playback: computed, then replayed)."""
    return run_program(build(), program, mode, dt, **options)
