"""A belt brings boxes, a light beam stops it, a UR5e stacks them 2 x 2 x 2 on a pallet.

The cell (:func:`build`): a UR5e with a parallel gripper on a pedestal; a belt along +x
whose top is :data:`BELT_TOP` high, running at :data:`BELT_SPEED` while the signal
``run`` is true; a source at the belt's start that puts a 60 x 60 x 50 mm box on it every
:data:`EVERY` seconds, :data:`BOXES` in all (``box_1`` ... ``box_8``); a light beam
``beam`` across the belt :data:`BEAM_BEFORE_END` before its end; a pallet; the signal
``placed``.

Two programs run together (:func:`programs`, ``Simulator.run_programs``):

- the robot's (:func:`robot_program`): for each box, wait above the belt for the beam,
  go down, grip, lift, carry the box over its place on the pallet (layer by layer,
  :func:`stack_positions`), go down, release, lift, set ``placed``; at the end, home;
- the cell controller's (:func:`controller`): for each box, wait for the beam and stop
  the belt, wait for ``placed``, take it back and restart the belt.

``workcell demo conveyor`` runs them (:mod:`workcell.record.conveyor_demo`), prints the
throughput (boxes per hour, from ``placed``) and each robot's moving / waiting / idle
time, and writes a picture (the cell while it works, at the end, and the Gantt chart of
both programs) and a recording. Lengths m, times s.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell import solids
from workcell.cell.workcell import Workcell
from workcell.sim.grasp import tool_down
from workcell.sim.simulator import Simulator
from workcell.spatial import rot_z, translation

__all__ = [
    "BEAM_BEFORE_END",
    "BELT_SPEED",
    "BELT_TOP",
    "BOXES",
    "EVERY",
    "ROBOT",
    "build",
    "controller",
    "pick_position",
    "program",
    "programs",
    "robot_program",
    "run",
    "stack_positions",
]

ROBOT = "ur5e"
BOXES = 8
EVERY = 6.0  # s between two boxes from the source
BELT_SPEED = 0.25  # m/s
BELT_TOP = 0.40  # m
BELT_START, BELT_END, BELT_Y, BELT_WIDTH = -1.10, 0.55, 0.40, 0.20  # m
BEAM_BEFORE_END = 0.10  # m
BOX = (0.06, 0.06, 0.05)  # m
PALLET_CENTRE, PALLET_SIZE = (0.40, -0.35), (0.30, 0.30, 0.30)  # m (x, y); size x, y, height
PITCH = 0.09  # m between the boxes' centres on the pallet
BASE_HEIGHT = 0.40  # m: the pedestal
APPROACH = 0.10  # m above a grasp or place
TOOL_SPEED = 0.5  # m/s of the straight moves down and up
SOURCE_X = BELT_START + 0.02  # m: where the source puts a box's back face


def build() -> Workcell:
    """The cell (module doc)."""
    cell = Workcell("conveyor")
    m = cell.model
    solids.box(m, "pedestal_block", size=(0.30, 0.30, BASE_HEIGHT))
    solids.box(m, "pallet_block", size=PALLET_SIZE)
    solids.box(m, "box_block", size=BOX)
    cell.add_static("pedestal", "pedestal_block", translation(-0.15, -0.15, 0.0))
    px, py = PALLET_CENTRE
    cell.add_static(
        "pallet",
        "pallet_block",
        translation(px - PALLET_SIZE[0] / 2, py - PALLET_SIZE[1] / 2, 0.0),
        colour=(0.72, 0.58, 0.38),
    )
    cell.add_movable("box", "box_block", translation(0.0, 1.0, 0.0), density=300.0)
    cell.add_robot(
        ROBOT, "ur5e", gripper=True, base=translation(0.0, 0.0, BASE_HEIGHT) @ rot_z(math.pi)
    )
    cell.add_signal("run", True)
    cell.add_signal("placed", False)
    beam_x = BELT_END - BEAM_BEFORE_END
    z = BELT_TOP + BOX[2] / 2
    cell.add_sensor(
        "beam", "beam", start=(beam_x, BELT_Y - 0.20, z), end=(beam_x, BELT_Y + 0.20, z)
    )
    cell.add_conveyor(
        "belt",
        start=(BELT_START, BELT_Y, BELT_TOP),
        end=(BELT_END, BELT_Y, BELT_TOP),
        width=BELT_WIDTH,
        speed=BELT_SPEED,
        run_signal="run",
    )
    at = translation(SOURCE_X, BELT_Y - BOX[1] / 2, BELT_TOP)
    cell.add_source("feeder", "box", at=at, every=EVERY, count=BOXES)
    cell.add_camera("overview", (0.35, -1.8, 1.5), (-0.3, 0.1, 0.32), fovy=45)
    return cell


def pick_position() -> NDArray[np.float64]:
    """Where a box's centroid stops at the beam (m, world)."""
    beam_x = BELT_END - BEAM_BEFORE_END
    return np.array([beam_x - BOX[0] / 2, BELT_Y, BELT_TOP + BOX[2] / 2])


def stack_positions() -> list[NDArray[np.float64]]:
    """The boxes' centroids on the pallet (m, world), in order: layer by layer, 2 x 2."""
    px, py = PALLET_CENTRE
    out = []
    for layer in range(2):
        for i, j in ((0, 0), (1, 0), (0, 1), (1, 1)):
            x = px + (i - 0.5) * PITCH
            y = py + (j - 0.5) * PITCH
            out.append(np.array([x, y, PALLET_SIZE[2] + BOX[2] / 2 + layer * BOX[2]]))
    return out


def _above(p: NDArray[np.float64]) -> NDArray[np.float64]:
    return tool_down(p + np.array([0.0, 0.0, APPROACH]))


def robot_program(sim: Simulator) -> None:
    """The UR5e's program (module doc)."""
    pick = pick_position()
    for place in stack_positions()[:BOXES]:
        sim.move_end_effector(ROBOT, _above(pick))
        sim.wait_signal("beam", True)
        sim.move_linear(ROBOT, tool_down(pick), speed=TOOL_SPEED)
        sim.close_gripper(ROBOT)
        sim.move_linear(ROBOT, _above(pick), speed=TOOL_SPEED)
        sim.move_end_effector(ROBOT, _above(place))
        sim.move_linear(ROBOT, tool_down(place), speed=TOOL_SPEED)
        sim.open_gripper(ROBOT)
        sim.move_linear(ROBOT, _above(place), speed=TOOL_SPEED)
        sim.set_signal("placed", True)
    sim.move_joints_absolute(ROBOT, "home")


def controller(sim: Simulator) -> None:
    """The cell controller's program (module doc)."""
    for _ in range(BOXES):
        sim.wait_signal("beam", True)
        sim.set_signal("run", False)
        sim.wait_signal("placed", True)
        sim.set_signal("placed", False)
        sim.set_signal("run", True)


def programs() -> dict[str, Any]:
    """The two programs by name: the robot's (named as the robot) and the controller's."""
    return {ROBOT: robot_program, "controller": controller}


def program(sim: Simulator) -> None:
    """Both programs together (what ``workcell demo conveyor`` runs)."""
    sim.run_programs(programs())


def run(mode: str = "path", dt: float = 0.01, **options: object) -> Simulator:
    """Build the cell and run both programs (jerk-limited profiles) in ``mode``."""
    from workcell.examples import run_program

    options.setdefault("profile", "jerk")
    return run_program(build(), program, mode, dt, **options)
