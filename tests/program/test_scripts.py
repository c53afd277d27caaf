"""The thesis's examples as .wcl scripts (assets/), and how scripts run and stop."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from program_helpers import EXAMPLE1_SIM_TIME, needs_handoff, needs_pick_place

from workcell import JointLimitError, ModelError, ProgramError
from workcell.program.interpreter import check_script, run_script
from workcell.program.keytree import CommandSyntaxError

ASSETS = Path(__file__).resolve().parents[2] / "assets"


def quiet(path: Path):
    lines: list[str] = []
    return run_script(path, out=lines.append), lines


def test_every_shipped_script_passes_the_syntax_check():
    scripts = sorted(ASSETS.glob("*.wcl"))
    assert len(scripts) >= 5
    for p in scripts:
        assert check_script(p.read_text(), p.name) > 0


def test_the_cube_script_builds_the_thesis_unit_cube():
    s, lines = quiet(ASSETS / "thesis_cube.wcl")
    m = s.model
    assert m.pointed_by("square1") == 6  # one square, six relations (thesis §2)
    p = m.properties("cube1")
    assert p.volume == pytest.approx(1.0, abs=1e-12)
    assert p.area == pytest.approx(6.0, abs=1e-12)
    assert np.allclose(p.centroid, 0.5)
    # a unit cube's inertia about its centroid, unit density: (1 + 1) / 12 on the diagonal
    assert np.allclose(p.inertia, np.eye(3) / 6)
    assert m.validity("cube1").ok
    assert any("volume 1 m^3" in line for line in lines)


def test_the_parallelepiped_script_makes_2_x_3_x_1_5_both_ways():
    s, _ = quiet(ASSETS / "thesis_parallelepiped.wcl")
    for name in ("para_block", "para_object"):
        p = s.model.properties(name)
        assert p.volume == pytest.approx(2 * 3 * 1.5, rel=1e-12)
        assert p.area == pytest.approx(2 * (2 * 3 + 2 * 1.5 + 3 * 1.5), rel=1e-12)
        assert np.allclose(p.centroid, [1.0, 1.5, 0.75])
    # instancing: the copy points to the same square; the object to the cube
    assert s.model.pointed_by("square1") == 12
    assert s.model.pointed_by("cube1") == 1


def test_the_example_1_script_takes_the_simulated_time_of_the_hand_formula():
    from workcell.examples import thesis_joints

    s, lines = quiet(ASSETS / "thesis_example1.wcl")
    assert s.sim.sim_time == pytest.approx(EXAMPLE1_SIM_TIME, abs=1e-9)
    assert round(s.sim.sim_time, 2) == 9.89
    python = thesis_joints.run("path", 0.01)
    assert s.sim.sim_time == pytest.approx(python.sim_time, abs=1e-12)
    assert s.sim.frames == python.frames
    assert np.allclose(s.sim.joints("puma"), np.radians(thesis_joints.START_DEG))
    assert lines[-1] == "9.8902 s"


@needs_pick_place
def test_the_example_2_script_puts_the_cube_on_stage_1():
    from workcell.examples import thesis_pick_place as ex

    s, _ = quiet(ASSETS / "thesis_example2.wcl")
    sim = s.sim
    # the cube's centroid half its size above stage 1's top centre
    half = ex.CUBE_SIZE / 2
    expected = np.array([*ex.STAGE_1_CENTRE, ex.STAGE_1_TOP + half])
    assert np.allclose(sim.part_positions()["cube"], expected, atol=1e-6)
    kinds = [e.kind for e in sim.events]
    assert kinds.count("grasp") == 1
    assert kinds.count("release") == 1
    assert sim.held("puma") is None
    assert np.allclose(sim.joints("puma"), np.radians([0, 0, -90, 0, 90, 0]))
    python = ex.run("path", 0.01)  # the Python program of the same example
    assert sim.sim_time == pytest.approx(python.sim_time, rel=1e-6)


@needs_handoff
def test_the_example_3_script_hands_the_sphere_over():
    from workcell.examples import thesis_handoff as ex

    s, _ = quiet(ASSETS / "thesis_example3.wcl")
    sim = s.sim
    assert np.allclose(sim.part_positions()["sphere"], ex.PLACE, atol=1e-6)
    grasps = [(e.robot, e.kind) for e in sim.events if e.kind in ("grasp", "release")]
    assert grasps == [
        ("puma_1", "grasp"),
        ("puma_2", "grasp"),
        ("puma_1", "release"),
        ("puma_2", "release"),
    ]
    for r in ("puma_1", "puma_2"):
        assert np.allclose(sim.joints(r), np.radians([0, 0, -90, 0, 90, 0]))
    assert sim.sim_time == pytest.approx(ex.run("path", 0.01).sim_time, rel=1e-6)


def write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "prog.wcl"
    p.write_text(text)
    return p


def test_a_syntax_error_anywhere_stops_the_script_before_it_runs(tmp_path):
    p = write(tmp_path, "create cube a size 1\ncreate cube b size 1\nmove jionts p 0\n")
    with pytest.raises(CommandSyntaxError) as e:
        quiet(p)
    assert str(e.value).startswith(f"{p}:3: column 6: unexpected 'jionts'")
    assert e.value.column == 6


def test_a_run_time_error_stops_the_script_with_its_type_and_line(tmp_path):
    p = write(
        tmp_path,
        "cell example joints\nsimulate\nmove joints relative puma 10 0 0 0 0 0\n"
        "move joints absolute puma 170 0 0 0 0 0\nmove joints relative puma 10 0 0 0 0 0\n",
    )
    lines: list[str] = []
    from workcell.program import Session

    s = Session(base_dir=tmp_path)
    with pytest.raises(JointLimitError, match=rf"^{p}:4: move_joints_absolute"):
        run_script(p, s, out=lines.append)
    # line 3 ran, line 4 changed nothing, line 5 never ran
    assert np.degrees(s.sim.joints("puma"))[0] == pytest.approx(10)
    assert s.sim.sim_time == pytest.approx(math.radians(10) / s.sim.speed("puma"))


def test_names_are_checked_as_each_line_runs(tmp_path):
    p = write(tmp_path, "create cube a size 1\nremove b\n")
    with pytest.raises(CommandSyntaxError, match=r"prog.wcl:2: column 8: unknown entity 'b'"):
        quiet(p)
    p = write(tmp_path, "create cube a size 1\ncreate cube a size 2\n")
    with pytest.raises(ModelError, match=r"prog.wcl:2: .*already exists"):
        quiet(p)


def test_relative_files_are_taken_from_the_scripts_folder_and_quit_ends_early(tmp_path):
    (tmp_path / "sub").mkdir()
    p = tmp_path / "sub" / "prog.wcl"
    p.write_text("create cube a size 1\nsave out.json\nquit\ncreate cube b size 1\n")
    s, _ = quiet(p)
    assert (tmp_path / "sub" / "out.json").exists()
    assert not s.model.exists("b")


def test_a_missing_script_is_a_program_error(tmp_path):
    with pytest.raises(ProgramError, match="cannot read script"):
        run_script(tmp_path / "none.wcl")
