"""``workcell study``: the command line, its summary table, plots and the best run's recording."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest
from PIL import Image

from workcell.cli import main
from workcell.study.plots import HIST_PNG, XY_PNG, placement_axes
from workcell.study.spec import parameter

ASSETS = Path(__file__).resolve().parents[2] / "assets"
GRID = ["--vary", "puma.base.x=0:0.1:3", "--vary", "puma.base.y=-0.1:0:3"]


def test_placement_study_from_the_command_line(tmp_path, capsys):
    """Example 2 over a 3 x 3 placement grid, with plots and the best run recorded."""
    placement = tmp_path
    args = [
        "study",
        "--example",
        "pick-place",
        *GRID,
        "--backend",
        "serial",
        "--out",
        str(placement),
    ]
    assert main([*args, "--record-best", str(placement / "best.rrd"), "--top", "3"]) == 0
    text = capsys.readouterr().out
    table = pq.read_table(placement / "results.parquet")
    assert table.num_rows == 9
    feasible = table.filter(pc.field("feasible"))
    assert f"{feasible.num_rows} of 9 candidates feasible" in text
    # the first line of the table is the shortest feasible cycle time
    best = min(feasible.column("cycle_time_s").to_pylist())
    lines = text.splitlines()
    first = lines[lines.index(next(ln for ln in lines if ln.startswith("best 3"))) + 2]
    assert float(first.split()[3]) == pytest.approx(best, abs=5e-4)
    assert "9 candidate(s) evaluated" in text
    assert (placement / "best.rrd").stat().st_size > 10_000
    for png in (XY_PNG, HIST_PNG):
        img = np.asarray(Image.open(placement / png).convert("RGB"))
        assert img.shape[0] > 300
        assert img.shape[1] > 500
        assert img.reshape(-1, 3).std(axis=0).max() > 20  # something is drawn
    # infeasible candidates are red crosses, feasible ones coloured squares
    img = np.asarray(Image.open(placement / XY_PNG).convert("RGB")).astype(int)
    red = (img[..., 0] > 180) & (img[..., 1] < 80) & (img[..., 2] < 80)
    assert red.sum() > 50
    # a second run into the same folder has nothing left to do
    assert main([*args, "--no-plots"]) == 0
    assert "0 candidate(s) evaluated, 9 already done" in capsys.readouterr().out


def test_a_wcl_program_that_builds_its_own_cell(tmp_path, capsys):
    script = ASSETS / "thesis_example2.wcl"
    vary = ["--vary", "puma.base.x=0,0.05"]
    assert (
        main(
            [
                "study",
                "--program",
                str(script),
                *vary,
                "--backend",
                "serial",
                "--out",
                str(tmp_path / "a"),
            ]
        )
        == 0
    )
    own = pq.read_table(tmp_path / "a" / "results.parquet")
    assert main(
        ["study", "--example", "pick-place", "--program", str(script), *vary,
         "--backend", "serial", "--out", str(tmp_path / "b")]
    ) == 0  # fmt: skip
    given = pq.read_table(tmp_path / "b" / "results.parquet")
    assert own.column("feasible").to_pylist() == [True, True]
    assert min(own.column("cycle_time_s").to_pylist()) > 20  # the whole program ran
    assert own.column("cycle_time_s").equals(given.column("cycle_time_s"))
    capsys.readouterr()


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--cell", "x.json", "--vary", "puma.base.x=0,1"], "--cell needs --program"),
        (["--example", "pick-place"], "at least one --vary"),
        (["--vary", "puma.base.x=0,1"], "give --example NAME"),
        (["--example", "pick-place", "--vary", "robot.base.x=0,1"], "no robot or part 'robot'"),
        (["--example", "pick-place", "--vary", "cube.base.x=0,1"], "'cube' is a part"),
        (["--example", "pick-place", "--vary", "puma.robot=puma999"], "puma999"),
        (
            ["--example", "pick-place", "--vary", "puma.base.x=0,1", "--address", "auto"],
            "ray backend",
        ),
    ],
)
def test_mistakes_exit_2_with_what_is_valid(args, says, tmp_path, capsys):
    serial = [] if "--address" in args else ["--backend", "serial"]
    assert main(["study", *args, *serial, "--out", str(tmp_path / "o")]) == 2
    assert says in capsys.readouterr().err


def test_placement_axes():
    x, y = parameter("puma.base.x", "0,1"), parameter("puma.base.y", "0,1")
    yaw, speed = parameter("puma.base.yaw", "0,90"), parameter("puma.speed", "0.1,0.2")
    cx, cy = parameter("cube.x", "0,1"), parameter("cube.y", "0,1")
    assert placement_axes([yaw, y, speed, x]) == (x, y)
    assert placement_axes([cy, cx, yaw]) == (cx, cy)
    assert placement_axes([yaw, speed]) == (yaw, speed)
    assert placement_axes([x]) is None


def test_the_progress_bar_shows_the_running_best(capsys):
    from workcell.study import Study, run

    table = run(
        Study(cell="pick-place", vary={"puma.base.x": "0:0.1:3"}), backend="serial", progress=True
    )
    best = min(t for t in table.column("cycle_time_s").to_pylist() if t is not None)
    err = capsys.readouterr().err
    assert "3/3" in err
    assert f"best {best:.3f} s" in err


TALL_PICK_PLACE = """# a 50 x 50 x 80 mm brick off a table onto a stage, task level
cell new tall
create box table size 0.8 0.8 0.4
create box stage size 0.12 0.12 0.1
create box brick size 0.05 0.05 0.08
add static table table translate -0.3 -0.4 0
add static stage stage translate 0.22 0.14 0.4
add movable brick brick density 2700 translate 0.255 -0.225 0.4
add robot arm puma260 gripper translate 0 0 0.4
simulate path dt 0.02
pick brick with arm
place brick on stage with arm
"""
ROBOTS = ("puma260", "ur3e", "kuka_kr6_r700", "abb_irb120", "fanuc_lrmate200id")


def test_a_pick_and_place_study_of_a_tall_part_over_five_robots_has_feasible_rows(tmp_path, capsys):
    # the user's steps (issue 19): every row was a CollisionError, the palm in the part
    script = tmp_path / "tall.wcl"
    script.write_text(TALL_PICK_PLACE)
    args = [
        "study", "--program", str(script), "--vary", f"arm.robot={','.join(ROBOTS)}",
        "--vary", "brick.x=0.225,0.255,0.285", "--backend", "serial", "--no-plots",
        "--out", str(tmp_path / "out"),
    ]  # fmt: skip
    assert main(args) == 0
    assert "15 of 15 candidates feasible" in capsys.readouterr().out
    rows = pq.read_table(tmp_path / "out" / "results.parquet").to_pylist()
    assert sorted((r["arm.robot"], r["brick.x"]) for r in rows) == sorted(
        (m, x) for m in ROBOTS for x in (0.225, 0.255, 0.285)
    )
    for r in rows:
        assert r["feasible"], r["error"]
        assert r["cycle_time_s"] > 1.0
        assert r["min_clearance_m"] > 0.0
