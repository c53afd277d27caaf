"""The study's pictures: a panel per robot when the robot varies, no candidate hidden, and
no empty histogram.

References: the rows' own values, grouped by hand here (which points of which robot have
a feasible and an infeasible candidate), against what the figure's markers hold.
"""

from __future__ import annotations

import pyarrow.parquet as pq

from workcell.cli import main
from workcell.study.plots import HIST_PNG, XY_PNG, placement_figure
from workcell.study.spec import parameter

ROBOT = parameter("arm.robot", "ur5e,puma260")
X, Y = parameter("arm.base.x", "0,0.1"), parameter("arm.base.y", "0,0.1")


def row(robot: str, x: float, y: float, t: float | None) -> dict:
    return {"arm.robot": robot, "arm.base.x": x, "arm.base.y": y, "feasible": t is not None,
            "cycle_time_s": t}  # fmt: skip


def markers(ax) -> tuple[set, set]:
    """(points drawn as squares, points drawn as red crosses) of a panel."""
    squares, crosses = set(), set()
    for c in ax.collections:
        points = {tuple(round(float(v), 9) for v in p) for p in c.get_offsets()}
        if c.get_label() == "infeasible":
            crosses |= points
        elif c.get_array() is not None:
            squares |= points
    return squares, crosses


def test_a_varied_robot_gets_a_panel_each_and_no_infeasible_candidate_is_hidden():
    # two robots on the same squares; a third parameter (not drawn) varies too, so two
    # candidates share each point of each robot
    rows = [
        row("ur5e", 0.0, 0.0, 10.0), row("ur5e", 0.0, 0.0, None),  # mixed: both marks
        row("ur5e", 0.1, 0.0, 12.0), row("ur5e", 0.1, 0.0, 11.0),
        row("puma260", 0.0, 0.0, None), row("puma260", 0.0, 0.0, None),  # only a cross
        row("puma260", 0.1, 0.0, 20.0), row("puma260", 0.1, 0.0, None),
    ]  # fmt: skip
    fig = placement_figure(rows, X, Y, [ROBOT])
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title() for ax in panels] == [
        "arm = ur5e: 3 of 4 feasible",
        "arm = puma260: 1 of 4 feasible",
    ]
    assert markers(panels[0]) == ({(0.0, 0.0), (0.1, 0.0)}, {(0.0, 0.0)})
    assert markers(panels[1]) == ({(0.1, 0.0)}, {(0.0, 0.0), (0.1, 0.0)})
    # one colour scale for all panels: the feasible cycle times' range
    scales = {(c.norm.vmin, c.norm.vmax) for ax in panels for c in ax.collections
              if c.get_array() is not None}  # fmt: skip
    assert scales == {(10.0, 20.0)}
    # the squares show the best feasible time of their point
    ur5e = next(c for c in panels[0].collections if c.get_array() is not None)
    points, times = ur5e.get_offsets().tolist(), ur5e.get_array().tolist()
    best = dict(zip(map(tuple, points), times, strict=True))
    assert best == {(0.0, 0.0): 10.0, (0.1, 0.0): 11.0}
    assert fig.get_suptitle() == "cycle time over the placement: 4 of 8 feasible"
    # without a robot choice: one panel, as before
    single = placement_figure(rows[:4], X, Y)
    assert [ax.get_title() for ax in single.axes if ax.get_title()] == [
        "cycle time over the placement: 3 of 4 feasible"
    ]


def test_a_study_with_no_feasible_candidate_says_so_instead_of_an_empty_histogram(tmp_path, capsys):
    # the user's steps: example 2's program with the cube moved out of its reach
    out = tmp_path / "none"
    args = ["study", "--example", "pick-place", "--vary", "cube.x=5,6", "--vary", "cube.y=5,6",
            "--backend", "serial", "--out", str(out)]  # fmt: skip
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "0 of 4 candidates feasible" in text
    assert "no cycle-time histogram: none of the 4 candidate(s) is feasible" in text
    assert not (out / HIST_PNG).exists()
    assert (out / XY_PNG).exists()  # the crosses say where
    assert pq.read_table(out / "results.parquet").num_rows == 4
