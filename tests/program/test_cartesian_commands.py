"""Cartesian and gripper commands, and tool targets built from parts (thesis example 2's cell)."""

from __future__ import annotations

import numpy as np
import pytest
from program_helpers import needs_cartesian, needs_pick_place, snapshot

from workcell import GraspError, ProgramError, UnreachableError
from workcell.program import Session, Target, from_wire
from workcell.program import cellcommands as cellc
from workcell.program import simcommands as simc
from workcell.program.targets import part_anchor

DOWN = ((1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, -1.0))  # tool z pointing down

pytestmark = needs_pick_place


@pytest.fixture
def pick(tmp_path) -> Session:
    s = Session(base_dir=tmp_path)
    s.execute(cellc.ExampleCell("pick-place"))
    s.execute(simc.Simulate("path", 0.01))
    return s


def test_part_anchors_are_the_centroid_and_the_top_centre(pick):
    from workcell.examples import thesis_pick_place as ex

    corner, size = np.array(ex.CUBE_CORNER), ex.CUBE_SIZE
    assert np.allclose(part_anchor(pick, "cube", "centroid"), corner + size / 2)
    _sx, _sy, sz = ex.STAGE_1_SIZE
    top = [ex.STAGE_1_CENTRE[0], ex.STAGE_1_CENTRE[1], ex.TABLE_TOP + sz]
    assert np.allclose(part_anchor(pick, "stage_1", "top"), top)
    with pytest.raises(ProgramError, match="parts: table, stage_1"):
        part_anchor(pick, "nothing", "top")


@needs_cartesian
def test_move_end_effector_reaches_the_target_pose(pick):
    target = Target(position=(0.3, -0.1, 0.6), rotation=DOWN)
    pick.execute(simc.MoveEndEffector("puma", target, "ru"))
    T = pick.execute(simc.ToolPose("puma"))
    assert np.allclose(T[:3, 3], [0.3, -0.1, 0.6], atol=1e-6)
    assert np.allclose(T[:3, :3], DOWN, atol=1e-6)
    # a target without orientation keeps the tool's; offset moves it (world axes)
    pick.execute(simc.MoveStraightLine("puma", Target(offset=(0.0, 0.0, -0.05)), 0.005))
    T2 = pick.execute(simc.ToolPose("puma"))
    assert np.allclose(T2[:3, 3], [0.3, -0.1, 0.55], atol=1e-6)
    assert np.allclose(T2[:3, :3], DOWN, atol=1e-6)


@needs_cartesian
def test_grasp_carry_and_release_through_commands(pick):
    from workcell.examples import thesis_pick_place as ex

    above = Target(part="cube", offset=(0, 0, 0.1), rotation=DOWN)
    pick.execute(simc.MoveEndEffector("puma", above, "ru"))
    pick.execute(simc.MoveStraightLine("puma", Target(part="cube", rotation=DOWN)))
    assert pick.execute(simc.CloseGripper("puma")) == "cube"
    assert pick.execute(simc.Held("puma")) == "cube"
    pick.execute(simc.MoveStraightLine("puma", above))
    # carried: the cube's centroid rose with the tool by 0.1 m
    pos = pick.execute(simc.PartPositions())["cube"]
    centroid = np.add(ex.CUBE_CORNER, ex.CUBE_SIZE / 2)
    assert np.allclose(pos, np.add(centroid, (0, 0, 0.1)), atol=1e-6)
    before = snapshot(pick)
    with pytest.raises(GraspError):
        pick.execute(simc.CloseGripper("puma"))  # already holds it
    assert snapshot(pick) == before
    assert pick.execute(simc.OpenGripper("puma")) == "cube"
    assert pick.execute(simc.Held("puma")) is None
    assert pick.execute(simc.OpenGripper("puma")) is None
    kinds = [e["kind"] for e in pick.execute(simc.Events())]
    assert "grasp" in kinds
    assert "release" in kinds


@needs_cartesian
def test_unreachable_and_bad_targets_change_nothing(pick):
    before = snapshot(pick)
    with pytest.raises(UnreachableError):
        pick.execute(simc.MoveEndEffector("puma", Target(position=(3.0, 0, 0.5), rotation=DOWN)))
    with pytest.raises(ProgramError, match="parts:"):
        pick.execute(simc.MoveEndEffector("puma", Target(part="ghost")))
    with pytest.raises(ProgramError):
        pick.execute(simc.MoveStraightLine("puma", Target(offset=(0, 0, 0.01)), -1.0))
    assert snapshot(pick) == before


@needs_cartesian
def test_mode_switch_clearance_and_play(pick):
    pick.execute(simc.SetMode("playback"))
    assert pick.sim.mode == "playback"
    pick.execute(simc.MoveJointsRelative("puma", (0.2, 0, 0, 0, 0, 0)))
    frames = pick.execute(simc.Frames())
    assert pick.execute(simc.Play(False)) == frames
    d = pick.execute(simc.Clearance("puma", "stage_1"))
    assert isinstance(d, float)
    assert d > 0


def test_targets_from_the_wire_and_their_checks():
    T = np.eye(4)
    T[:3, 3] = (0.1, 0.2, 0.3)
    c = from_wire("move_end_effector", {"robot": "puma", "T": T.tolist()})
    assert c.T.matrix is not None
    assert c.T.matrix[0][3] == 0.1
    c = from_wire("move_end_effector", {"robot": "p", "T": {"part": "cube", "offset": [0, 0, 1]}})
    assert Target(part="cube", offset=(0.0, 0.0, 1.0)) == c.T
    for bad, words in [
        ({"part": "cube", "position": [0, 0, 0]}, "not both"),
        ({"matrix": T.tolist(), "rotation": DOWN}, "not both"),
        ({"rotation": [[2, 0, 0], [0, 1, 0], [0, 0, 1]]}, "rotation"),
        ({"anchor": "middle"}, "centroid, top"),
        ({"colour": 1}, "unknown key"),
        ([[1, 2, 3]], "4x4"),
    ]:
        with pytest.raises(ProgramError, match=words):
            from_wire("move_end_effector", {"robot": "p", "T": bad})
