"""The thesis's example workcells 2 (pick and place) and 3 (handoff), in every mode."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest

from workcell.examples import thesis_handoff as ho
from workcell.examples import thesis_pick_place as pp

MODES = ["path", "joint-by-joint", "playback"]


@functools.cache
def run(example: str, mode: str):
    return {"pp": pp, "ho": ho}[example].run(mode, 0.005)


@pytest.mark.parametrize("mode", MODES)
def test_pick_place_ends_with_the_cube_resting_on_stage_1(mode):
    sim = run("pp", mode)
    pose = sim.part_pose(pp.CUBE)
    # the cube's bottom face lies on the stage's top face, inside its footprint
    corners = pose[:3, :3] @ (np.array([[0, 0, 0], [1, 1, 1]]) * pp.CUBE_SIZE).T
    bottom = pose[2, 3] + corners[2].min()
    assert bottom == pytest.approx(pp.STAGE_1_TOP, abs=1e-9)
    centre = pose[:3, :3] @ np.full(3, pp.CUBE_SIZE / 2) + pose[:3, 3]
    assert np.abs(centre - pp.place_position()).max() < 1e-9
    assert abs(sim.clearance(pp.CUBE, pp.STAGE_1)) < 1e-6  # touching
    hits = [e for e in sim.events if e.kind == "collision"]
    if mode == "joint-by-joint":
        # joint by joint, the return home (joint 2 before joint 3) dips a finger into the
        # table: the mode shows what a robot moving one joint at a time would hit
        assert [(e.robot, e.detail.split(":")[0]) for e in hits] == [
            (pp.ROBOT, f"{pp.ROBOT}.gripper.right with table")
        ]
        moves = [e.t for e in sim.events if e.kind == "move"]
        assert moves[-2] <= hits[0].t <= moves[-1]  # during the last move
    else:
        assert hits == []
    assert [e.kind for e in sim.events if e.kind in ("grasp", "release")] == ["grasp", "release"]
    assert np.allclose(sim.joints(pp.ROBOT), sim.cell.robots[pp.ROBOT].robot.poses["home"])


@pytest.mark.parametrize("mode", MODES)
def test_handoff_moves_the_sphere_to_table_2(mode):
    sim = run("ho", mode)
    assert np.abs(sim.part_pose(ho.SPHERE)[:3, 3] - ho.PLACE).max() < 1e-9
    assert sim.part_pose(ho.SPHERE)[2, 3] - ho.RADIUS == pytest.approx(ho.TABLE_TOP, abs=1e-12)
    hits = [e for e in sim.events if e.kind == "collision"]
    if mode == "joint-by-joint":
        # one joint at a time, puma_1's first joint swings the sphere into puma_2's waiting
        # gripper, and puma_2's return home drags its fingers through the table
        assert hits
        assert all(e.robot in (ho.GIVER, ho.RECEIVER) for e in hits)
        assert any("sphere" in e.detail and e.robot == ho.GIVER for e in hits)
    else:
        assert hits == []
    events = [(e.robot, e.kind) for e in sim.events if e.kind in ("grasp", "release")]
    assert events == [
        (ho.GIVER, "grasp"),
        (ho.RECEIVER, "grasp"),
        (ho.GIVER, "release"),
        (ho.RECEIVER, "release"),
    ]
    for robot in (ho.GIVER, ho.RECEIVER):
        assert np.allclose(sim.joints(robot), sim.cell.robots[robot].robot.poses["home"])
    summary = sim.summary()
    assert set(summary) >= {
        "sim_time_s",
        "wall_time_s",
        "frames",
        "events",
        "collisions",
        "objects",
    }
    assert summary["objects"][ho.SPHERE] == pytest.approx(ho.PLACE.tolist(), abs=1e-9)


def test_path_and_playback_give_the_same_frames_and_clock():
    for ex in ("pp", "ho"):
        a, b = run(ex, "path"), run(ex, "playback")
        assert a.frames == b.frames
        assert a.sim_time == b.sim_time
        assert np.array_equal(a.timeline.qpos(), b.timeline.qpos())


def test_the_clock_is_the_sum_of_the_moves_durations():
    # every move event reports its duration; they add up to the simulated time
    sim = run("ho", "path")
    total = sum(
        float(e.detail.rsplit(", ", 1)[1].split(" s")[0]) for e in sim.events if e.kind == "move"
    )
    assert total == pytest.approx(sim.sim_time, rel=1e-5)


def test_demo_handoff_json(tmp_path, capsys):
    from workcell.cli import main

    assert main(["demo", "handoff", "--json", "--dt", "0.01", "--mjcf", str(tmp_path)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["collisions"] == 0
    assert out["objects"][ho.SPHERE] == pytest.approx(ho.PLACE.tolist(), abs=1e-9)
    kinds = [(e["robot"], e["kind"]) for e in out["events"] if e["kind"] in ("grasp", "release")]
    assert kinds[0] == (ho.GIVER, "grasp")
    assert kinds[-1] == (ho.RECEIVER, "release")
    assert out["frames"] > 0
    assert out["sim_time_s"] == pytest.approx(run("ho", "path").sim_time, rel=1e-9)
    assert (tmp_path / "thesis_handoff.xml").exists()


def test_demo_pick_place_human(capsys):
    from workcell.cli import main

    assert main(["demo", "pick-place", "--dt", "0.01"]) == 0
    text = capsys.readouterr().out
    assert "grasp 'cube'" in text
    assert "0 collision(s)" in text
    assert "cube's centroid ends at (0.2400, 0.2200, 0.5200) m" in text  # on stage 1's top centre


@pytest.mark.parametrize("mode", MODES)
def test_events_point_at_the_frame_that_shows_them(mode):
    from workcell.examples import thesis_joints

    sim = thesis_joints.run(mode, 0.01)
    moves = [e for e in sim.events if e.kind == "move"]
    counts = [int(e.detail.split(" frames")[0].rsplit(" ", 1)[1]) for e in moves]
    assert [e.frame for e in moves] == list(np.cumsum(counts))  # frame 0 is the start
    start, a, b = (
        np.radians(d)
        for d in (thesis_joints.START_DEG, thesis_joints.ABSOLUTE_DEG, thesis_joints.START_DEG)
    )
    Q = sim.timeline.qpos()
    assert np.allclose(Q[moves[1].frame], a, atol=1e-12)
    assert np.allclose(Q[moves[2].frame], b, atol=1e-12)
    assert np.allclose(Q[moves[0].frame], start + np.radians(thesis_joints.RELATIVE_DEG))


def test_example_cells_load_by_name_for_every_cli_command(tmp_path, capsys):
    from workcell import ProgramError
    from workcell.cli import main
    from workcell.examples import CELLS, example, load_cell

    assert set(CELLS) == {"joints", "pick-place", "handoff", "obstacle", "conveyor"}
    cell = load_cell("handoff")
    assert set(cell.robots) == {ho.GIVER, ho.RECEIVER}
    cell.save(tmp_path / "h.json")
    assert load_cell(tmp_path / "h.json") == cell
    assert main(["info", "pick-place", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in info["robots"]] == [pp.ROBOT]
    assert main(["export", "handoff", "--out", str(tmp_path / "x")]) == 0
    assert (tmp_path / "x" / "thesis_handoff.xml").exists()
    with pytest.raises(
        ProgramError, match="examples: joints, pick-place, handoff, obstacle, conveyor"
    ):
        example("welding")
