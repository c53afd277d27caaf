"""A wall between two stages: the thesis's direct program collides, pick and place do not.

One Puma 260 with a gripper on a table, two stages 0.4 m apart and a 250 mm wall between
them; a 40 mm aluminium cube on stage 1 is to go to stage 2. :func:`direct_program`
is written the thesis's way (the grasp and release poses by hand, a joint-space move
between them), and the arm sweeps the cube through the wall. :func:`program` says the
same task at the task level (``pick``, ``place ... on stage_2``, a planned move home) and
runs clean. ``workcell demo obstacle`` runs both, lists the direct program's collisions
and draws both tool paths
(:func:`workcell.record.obstacle_demo.picture`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from workcell import solids
from workcell.cell.workcell import Workcell
from workcell.examples import run_program
from workcell.moved import moved
from workcell.sim.grasp import tool_down
from workcell.sim.simulator import Simulator
from workcell.sim.tasks import pick, place
from workcell.spatial import translation

__all__ = [
    "CUBE",
    "ROBOT",
    "STAGE_1",
    "STAGE_2",
    "build",
    "compare",
    "demo",  # noqa: F822 (moved; found by __getattr__)
    "direct_program",
    "picture",  # noqa: F822 (moved; found by __getattr__)
    "program",
    "run",
    "tool_path",
]

ROBOT, CUBE, STAGE_1, STAGE_2 = "puma", "cube", "stage_1", "stage_2"
TABLE_TOP = 0.4  # m
STAGE_SIZE = (0.12, 0.12, 0.1)  # m
STAGE_CENTRES = {STAGE_1: (0.28, -0.2), STAGE_2: (0.28, 0.2)}  # m (x, y)
WALL = (0.3, 0.02, 0.25)  # m: length (x), thickness (y), height
WALL_START = 0.14  # m: the wall runs along x from here, centred on y = 0
CUBE_SIZE = 0.04  # m
SPEED = 0.3  # rad/s
APPROACH = 0.08  # m
DIRECT_COLOUR = (0.9, 0.15, 0.1, 1.0)
PLANNED_COLOUR = (0.1, 0.75, 0.25, 1.0)


def build() -> Workcell:
    """The cell: table, two stages, the wall, the cube on stage 1, one Puma 260, a camera."""
    cell = Workcell("obstacle")
    m = cell.model
    solids.box(m, "table_block", size=(1.0, 1.0, TABLE_TOP))
    solids.box(m, "stage_block", size=STAGE_SIZE)
    solids.box(m, "wall_block", size=WALL)
    solids.cube(m, "cube_block", size=CUBE_SIZE)
    cell.add_static("table", "table_block", translation(-0.3, -0.5, 0.0), colour=(0.55, 0.45, 0.35))
    sx, sy, sz = STAGE_SIZE
    for name, (x, y) in STAGE_CENTRES.items():
        cell.add_static(
            name,
            "stage_block",
            translation(x - sx / 2, y - sy / 2, TABLE_TOP),
            colour=(0.3, 0.5, 0.8),
        )
    cell.add_static(
        "wall",
        "wall_block",
        translation(WALL_START, -WALL[1] / 2, TABLE_TOP),
        colour=(0.8, 0.8, 0.75),
    )
    x, y = STAGE_CENTRES[STAGE_1]
    cell.add_movable(
        CUBE,
        "cube_block",
        translation(x - CUBE_SIZE / 2, y - CUBE_SIZE / 2, TABLE_TOP + sz),
        density=2700.0,
        colour=(0.85, 0.2, 0.15),
    )
    cell.add_robot(ROBOT, "puma260", gripper=True, base=translation(0.0, 0.0, TABLE_TOP))
    cell.add_camera("overview", (1.35, -0.3, 0.95), (0.25, 0.0, 0.58), fovy=42)
    return cell


def _centroid_on(stage: str) -> NDArray[np.float64]:
    x, y = STAGE_CENTRES[stage]
    return np.array([x, y, TABLE_TOP + STAGE_SIZE[2] + CUBE_SIZE / 2])


def direct_program(sim: Simulator) -> None:
    """The thesis's way: grasp and release poses by hand, joint-space moves between them."""
    sim.set_speed(ROBOT, SPEED)
    pick(sim, ROBOT, tool_down(_centroid_on(STAGE_1)), approach=APPROACH, config="ru")
    place(sim, ROBOT, tool_down(_centroid_on(STAGE_2)), approach=APPROACH, config="ru")
    sim.move_joints_absolute(ROBOT, sim.cell.robots[ROBOT].robot.poses["home"])


def program(sim: Simulator) -> None:
    """The same task at the task level: poses, configurations and paths found by the
    simulator, collision-free."""
    sim.set_speed(ROBOT, SPEED)
    sim.pick(ROBOT, CUBE)
    sim.place(ROBOT, CUBE, on=STAGE_2)
    sim.move_joints_absolute(ROBOT, sim.cell.robots[ROBOT].robot.poses["home"], plan=True)


def run(mode: str = "path", dt: float = 0.01, **options: object) -> Simulator:
    """Build the cell, run the task-level program in ``mode``."""
    return run_program(build(), program, mode, dt, **options)


def compare(mode: str = "path", dt: float = 0.01) -> tuple[Simulator, Simulator]:
    """(the direct program's run, the task-level program's run) on the same cell."""
    cell = build()
    return run_program(cell, direct_program, mode, dt), run_program(cell, program, mode, dt)


def tool_path(sim: Simulator, robot: str = ROBOT) -> NDArray[np.float64]:
    """World tool positions (k, 3), m, of every frame of a run."""
    _, Q = sim.trajectory(robot)
    placement = sim.cell.robots[robot]
    return (placement.base @ placement.robot.fk_batch(Q))[:, :3, 3]


# the picture and the demo's front end draw and record: they live above the examples
__getattr__ = moved(__name__, dict.fromkeys(("demo", "picture"), "workcell.record.obstacle_demo"))
