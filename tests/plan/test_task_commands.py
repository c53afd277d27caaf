"""pick, place and handover, from Python, the command language and the server.

References: the thesis's examples 2 and 3 as hand-written programs (poses and IK
configurations chosen by hand, ``workcell.examples``): the task-level versions must end
with every part where those end, to 1e-6 m; the bin's floor height and the stage's top
from the solids' sizes; the simulator's own collision events.
"""

from __future__ import annotations

import numpy as np
import pytest

from workcell import Workcell, solids, spatial
from workcell.errors import GraspError, PlanningError, ProgramError, UnreachableError
from workcell.examples import thesis_handoff as ho
from workcell.examples import thesis_pick_place as pp
from workcell.program import Session
from workcell.program.language import parse_line
from workcell.sim import Simulator


def no_collisions(sim: Simulator) -> list[str]:
    return [e.detail for e in sim.events if e.kind in ("collision", "warning")]


def example_2_task_level(sim: Simulator) -> None:
    sim.set_speed(pp.ROBOT, pp.SPEED)
    sim.pick(pp.ROBOT, pp.CUBE)
    sim.place(pp.ROBOT, pp.CUBE, on=pp.STAGE_1)
    sim.move_joints_absolute(pp.ROBOT, sim.cell.robots[pp.ROBOT].robot.poses["home"], plan=True)


def example_3_task_level(sim: Simulator) -> None:
    for r in (ho.GIVER, ho.RECEIVER):
        sim.set_speed(r, 0.3)
    sim.pick(ho.GIVER, ho.SPHERE)
    sim.handover(ho.GIVER, ho.RECEIVER, ho.SPHERE)
    sim.move_joints_absolute(ho.GIVER, sim.cell.robots[ho.GIVER].robot.poses["home"], plan=True)
    sim.place(ho.RECEIVER, ho.SPHERE, on="table_2", position=ho.PLACE[:2])
    home = sim.cell.robots[ho.RECEIVER].robot.poses["home"]
    sim.move_joints_absolute(ho.RECEIVER, home, plan=True)


@pytest.mark.parametrize(
    ("example", "task_level"), [(pp, example_2_task_level), (ho, example_3_task_level)]
)
def test_thesis_examples_by_task_end_where_the_hand_written_ones_end(example, task_level):
    by_hand = example.run()
    sim = Simulator(example.build())
    task_level(sim)
    assert no_collisions(sim) == []
    for part, pos in by_hand.part_positions().items():
        np.testing.assert_allclose(sim.part_positions()[part], pos, atol=1e-6)
    assert [g.kind for g in sim.grasps] == [g.kind for g in by_hand.grasps]


def test_picks_and_places_from_the_command_language(tmp_path):
    s = Session(base_dir=tmp_path)
    lines = [
        "cell example pick-place",
        "simulate path dt 0.01",
        "pick cube with puma",
        "place cube on stage_1 with puma at 0.26 0.2",
        "move joints absolute puma 0 0 -90 0 90 0 plan",
    ]
    for line in lines:
        for c in parse_line(line, s):
            s.execute(c)
    # the cube's centroid over (0.26, 0.2), resting on the stage's top (z = 0.5)
    np.testing.assert_allclose(s.sim.part_positions()["cube"], [0.26, 0.2, 0.52], atol=1e-6)
    assert no_collisions(s.sim) == []


def bin_cell() -> Workcell:
    cell = pp.build()
    m = cell.model
    # the bin of tests/test_decompose.py (the same mesh: one decomposition, cached)
    solids.box(m, "outer", size=(0.2, 0.15, 0.1))
    solids.box(m, "inner", size=(0.18, 0.13, 0.1))
    solids.difference(
        m, "bin", "outer", "inner", transforms=[None, spatial.translation(0.01, 0.01, 0.01)]
    )
    cell.add_static("bin_1", "bin", spatial.translation(0.14, 0.045, pp.TABLE_TOP))
    return cell


def test_a_part_placed_in_a_bin_rests_on_its_floor():
    sim = Simulator(bin_cell())
    sim.pick(pp.ROBOT, pp.CUBE)
    sim.place(pp.ROBOT, pp.CUBE, on="bin_1")
    floor = pp.TABLE_TOP + 0.01  # the bin's floor is 10 mm thick
    x, y, z = sim.part_positions()[pp.CUBE]
    # (x, y, z) is the cube's centroid; it rests on the bin's collision pieces, which
    # CoACD fits to the surface within ~25 um here (test_decompose bounds them by 50 um)
    assert z - 0.02 == pytest.approx(floor, abs=5e-5)
    # centroid over the centre of the bin's rim
    np.testing.assert_allclose([x, y], [0.24, 0.12], atol=1e-6)
    assert no_collisions(sim) == []


def test_errors_name_the_part_and_change_nothing():
    sim = Simulator(pp.build())
    before = (sim.frames, tuple(sim.events))
    with pytest.raises(ProgramError, match="no movable part 'ball'"):
        sim.pick(pp.ROBOT, "ball")
    with pytest.raises(GraspError, match="does not hold 'cube'"):
        sim.place(pp.ROBOT, pp.CUBE, on=pp.STAGE_1)
    assert (sim.frames, tuple(sim.events)) == before
    sim.pick(pp.ROBOT, pp.CUBE)
    after_pick = (sim.frames, tuple(sim.events))
    with pytest.raises(GraspError, match="already holds 'cube'"):
        sim.pick(pp.ROBOT, pp.CUBE)
    with pytest.raises(ProgramError, match="no support 'shelf'"):
        sim.place(pp.ROBOT, pp.CUBE, on="shelf")
    with pytest.raises(ProgramError, match="would rest on stage_1"):
        sim.place(pp.ROBOT, pp.CUBE, on="table", position=(0.24, 0.22))
    with pytest.raises(UnreachableError, match="'cube' cannot be reached"):
        sim.place(pp.ROBOT, pp.CUBE, on="table", position=(-0.25, 0.35))
    assert (sim.frames, tuple(sim.events)) == after_pick


def test_a_part_too_wide_or_out_of_reach_is_refused():
    cell = pp.build()
    solids.box(cell.model, "plank", size=(0.3, 0.2, 0.1))
    cell.add_movable("plank", "plank", spatial.translation(-0.1, 0.1, pp.TABLE_TOP), density=500)
    solids.cube(cell.model, "far", size=0.03)
    cell.add_movable("far", "far", spatial.translation(0.6, -0.3, pp.TABLE_TOP), density=500)
    sim = Simulator(cell)
    with pytest.raises(
        GraspError, match="no grasp of 'plank' fits the gripper: its box is 300 x 200 x 100 mm"
    ):
        sim.pick(pp.ROBOT, "plank")
    with pytest.raises(UnreachableError, match="'far' cannot be reached"):
        sim.pick(pp.ROBOT, "far")


def test_handover_needs_the_giver_to_hold_the_part():
    sim = Simulator(ho.build())
    with pytest.raises(GraspError, match="does not hold 'sphere'"):
        sim.handover(ho.GIVER, ho.RECEIVER, ho.SPHERE)
    with pytest.raises(ProgramError, match="giver and receiver are both"):
        sim.handover(ho.GIVER, ho.GIVER, ho.SPHERE)
    sim.set_planning(time_limit=1e-3, clearance=0.3)  # nothing is 30 cm from everything
    with pytest.raises(PlanningError):
        sim.pick(ho.GIVER, ho.SPHERE)


def test_the_task_level_example_2_runs_unchanged_against_the_server():
    from workcell.client import Client
    from workcell.program.server import Server

    srv = Server(port=0)
    srv.serve_in_thread()
    try:
        with Client(port=srv.port, timeout=60) as c:
            c.example_cell("pick-place")
            c.simulate("path", dt=0.01)
            example_2_task_level(c)  # the same function that drives a Simulator
            by_hand = pp.run()
            np.testing.assert_allclose(
                c.part_positions()["cube"], by_hand.part_positions()["cube"], atol=1e-6
            )
            assert c.set_planning()["clearance"] == 0.005
            with pytest.raises(GraspError, match="does not hold 'cube'"):
                c.place(pp.ROBOT, pp.CUBE, on=pp.STAGE_1, position=(0.24, 0.22))
    finally:
        srv.stop()


@pytest.mark.parametrize(("model", "x"), [("ur5e", 0.5), ("kuka_kr6_r700", 0.45)])
def test_library_arms_pick_and_place_too(model, x):
    cell = Workcell("arm_cell")
    m = cell.model
    solids.box(m, "table", size=(1.6, 1.6, 0.4))
    solids.box(m, "stage", size=(0.12, 0.12, 0.1))
    solids.cube(m, "cube", size=0.04)
    cell.add_static("table", "table", spatial.translation(-0.8, -0.8, 0.0))
    cell.add_static("stage_1", "stage", spatial.translation(x - 0.06, 0.2, 0.4))
    cell.add_movable("cube", "cube", spatial.translation(x - 0.02, -0.22, 0.4), density=2700)
    cell.add_robot("arm", model, gripper=True, base=spatial.translation(0.0, 0.0, 0.4))
    sim = Simulator(cell)
    sim.pick("arm", "cube")
    sim.place("arm", "cube", on="stage_1")
    # centroid over the stage's centre (x, 0.26), lowest face on its top (z = 0.5)
    np.testing.assert_allclose(sim.part_positions()["cube"], [x, 0.26, 0.52], atol=1e-6)
    assert no_collisions(sim) == []


def tall_part_cell(x: float = 0.255, model: str = "puma260") -> Workcell:
    """A 50 x 50 x 80 mm block on a table beside a stage, an arm with the default gripper
    (its fingers 50 mm long, the TCP 12.5 mm from their tips: the block is taller than
    twice the 37.5 mm from the TCP back to the palm)."""
    cell = Workcell("tall")
    m = cell.model
    solids.box(m, "table", size=(0.8, 0.8, 0.4))
    solids.box(m, "stage", size=(0.12, 0.12, 0.1))
    solids.box(m, "brick", size=(0.05, 0.05, 0.08))
    cell.add_static("table", "table", spatial.translation(-0.3, -0.4, 0.0))
    cell.add_static("stage", "stage", spatial.translation(0.22, 0.14, 0.4))
    cell.add_movable("brick", "brick", spatial.translation(x, -0.225, 0.4), density=2700.0)
    cell.add_robot("arm", model, gripper=True, base=spatial.translation(0.0, 0.0, 0.4))
    return cell


def test_a_part_taller_than_the_fingers_is_held_by_the_fingers_alone():
    # the user's steps: pick the tall block and put it on the stage; the grasp at its
    # centroid drove the palm 2.5 mm into it (collisions at the grasp and the release)
    from workcell.examples.plan_problems import penetrations

    sim = Simulator(tall_part_cell())
    sim.pick("arm", "brick")
    tool = sim.tool_pose("arm")
    top = sim.part_positions()["brick"][2] + 0.04
    palm_face = tool[2, 3] + 0.0375  # tool z points down: the palm is above the TCP
    assert tool[2, 2] == pytest.approx(-1.0)
    assert palm_face - top == pytest.approx(sim.set_planning()["near_clearance"], abs=1e-6)
    assert top - (tool[2, 3] - 0.0125) > 0.04  # the finger tips well down its sides
    sim.place("arm", "brick", on="stage")
    assert no_collisions(sim) == []
    # the stage's top is z = 0.5: the block's centroid 40 mm above it
    np.testing.assert_allclose(sim.part_positions()["brick"], [0.28, 0.2, 0.54], atol=1e-6)
    # plain MuJoCo on the exported cell, every frame interval at 4x: nothing overlaps
    samples, bad, found = penetrations(sim, density=4)
    assert samples > 1000
    assert (bad, found) == (0, [])
