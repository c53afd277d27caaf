"""The two-Puma cell shared by the cell tests (a module of its own name: see
tests/program/program_helpers.py)."""

from __future__ import annotations

import numpy as np

from workcell import solids
from workcell.cell import Workcell
from workcell.spatial import rot_z, translation


def two_puma_cell() -> Workcell:
    """Two Puma 260s with grippers on two tables, a movable cube and sphere, a static stage."""
    cell = Workcell("two_pumas")
    m = cell.model
    solids.box(m, "table", size=(0.6, 0.6, 0.4))
    solids.box(m, "stage", size=(0.2, 0.2, 0.1))
    solids.cube(m, "cube_block", size=0.04)
    solids.sphere(m, "ball", radius=0.025, m=16, n=8)
    cell.add_static("table_1", "table", translation(-0.3, -0.3, 0.0), colour=(0.5, 0.4, 0.3))
    cell.add_static("table_2", "table", translation(0.9, -0.3, 0.0), colour=(0.5, 0.4, 0.3))
    cell.add_static("stage", "stage", translation(0.5, 0.4, 0.0) @ rot_z(0.3))
    cell.add_movable("cube", "cube_block", translation(0.35, 0.1, 0.4), density=2700.0)
    cell.add_movable("sphere", "ball", translation(0.7, 0.1, 0.425), density=7800.0)
    cell.add_robot("puma_1", "puma260", gripper=True, base=translation(0.0, 0.0, 0.4))
    cell.add_robot(
        "puma_2",
        "puma260",
        gripper={"max_opening": 0.06},
        base=translation(1.2, 0.0, 0.4) @ rot_z(np.pi),
        q=np.radians([10, 20, -80, 5, 60, 30]),
    )
    cell.add_camera("overview", (0.6, -1.8, 1.4), (0.6, 0.0, 0.5), fovy=50)
    cell.add_camera("top", (0.6, 0.0, 3.0), (0.6, 0.0, 0.0))
    return cell
