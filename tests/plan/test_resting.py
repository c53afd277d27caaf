"""Parts rest on something: mid-air releases are reported, settling drops them exactly.

References: the heights of the stage's and the table's tops from the solids' sizes.
"""

from __future__ import annotations

import numpy as np
import pytest

from workcell.examples import thesis_handoff as ho
from workcell.examples import thesis_pick_place as pp
from workcell.sim import Simulator
from workcell.sim.grasp import tool_down
from workcell.sim.tasks import approach_pose, pick


def held_cube_over(sim: Simulator, xy: tuple[float, float], z: float) -> None:
    pick(sim, pp.ROBOT, tool_down(pp.grasp_position()), approach=0.1, config="ru")
    sim.move_end_effector(pp.ROBOT, tool_down([*xy, z]), config="ru")


def test_a_part_released_in_mid_air_is_reported_and_stays():
    sim = Simulator(pp.build())
    held_cube_over(sim, (0.24, 0.22), 0.6)  # centroid 80 mm over stage 1 (top at 0.5)
    sim.open_gripper(pp.ROBOT)
    (warning,) = [e for e in sim.events if e.kind == "warning"]
    assert warning.detail == "'cube' released in mid-air, 80 mm above stage_1"
    assert sim.part_positions()["cube"][2] == pytest.approx(0.6, abs=1e-9)  # the centroid


@pytest.mark.parametrize(
    ("xy", "support", "top"),
    [((0.24, 0.22), "stage_1", pp.STAGE_1_TOP), ((0.33, -0.05), "table", pp.TABLE_TOP)],
)
def test_settle_drops_onto_the_highest_support_below_in_one_frame(xy, support, top):
    sim = Simulator(pp.build())
    held_cube_over(sim, xy, 0.65)
    frames, t = sim.frames, sim.sim_time
    sim.open_gripper(pp.ROBOT, settle=True)
    assert sim.sim_time == t  # no simulated time
    assert sim.frames == frames + 2  # the fingers open, then the cube drops
    (settled,) = [e for e in sim.events if e.kind == "settle"]
    drop = 0.65 - pp.CUBE_SIZE / 2 - top
    assert settled.detail == f"'cube' dropped {drop * 1e3:.4g} mm onto {support}"
    # its lowest face on the top, exactly (the stage's mesh is float32 in MuJoCo)
    centroid = top + pp.CUBE_SIZE / 2
    assert sim.part_positions()["cube"][2] == pytest.approx(centroid, abs=1e-6)
    assert not [e for e in sim.events if e.kind in ("collision", "warning")]
    sim.move_straight_line(pp.ROBOT, approach_pose(sim.tool_pose(pp.ROBOT), 0.05))
    assert not [e for e in sim.events if e.kind == "collision"]


def test_a_handoff_release_is_not_mid_air():
    sim = ho.run()
    assert not [e for e in sim.events if e.kind in ("warning", "settle")]
    np.testing.assert_allclose(sim.part_positions()[ho.SPHERE], ho.PLACE, atol=1e-9)
