"""``workcell demo obstacle`` and the benchmark's problems, end to end.

References: the wall stands between the stages, so the direct program's collisions
involve it; every planned path is re-checked at 10x the frame density by plain MuJoCo on
the exported MJCF (``workcell.examples.plan_problems.penetrations``).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from workcell.cli import main
from workcell.examples import obstacle
from workcell.examples.plan_problems import ROBOT, penetrations, random_problem
from workcell.sim import Simulator


def test_demo_lists_the_direct_collisions_and_runs_pick_place_clean(tmp_path, capsys):
    png = tmp_path / "obstacle.png"
    assert main(["demo", "obstacle", "--json", "--render", str(png)]) == 0
    out = json.loads(capsys.readouterr().out)
    direct = [e for e in out["direct"]["events"] if e["kind"] == "collision"]
    assert out["collisions"] == {"direct": len(direct), "planned": 0}
    assert direct
    assert all("wall" in e["detail"] for e in direct)
    cube = out["planned"]["objects"]["cube"]
    x, y = obstacle.STAGE_CENTRES[obstacle.STAGE_2]
    half = obstacle.CUBE_SIZE / 2
    top = obstacle.TABLE_TOP + obstacle.STAGE_SIZE[2]
    np.testing.assert_allclose(cube, [x, y, top + half], atol=1e-6)  # its centroid
    img = np.asarray(Image.open(png).convert("RGB")).astype(int)
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    assert ((r > 150) & (g < 90) & (b < 90)).sum() > 200  # the direct path, red
    assert ((g > 130) & (r < 90) & (b < 120)).sum() > 200  # the planned path, green
    assert main(["demo", "obstacle"]) == 0
    text = capsys.readouterr().out
    assert f"direct program (poses by hand, joint-space moves): {len(direct)} collision(s)" in text
    assert "pick/place program (task level, planned paths): 0 collision(s)" in text


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_problems_are_solved_without_penetrations(seed):
    problem = random_problem(seed)
    sim = Simulator(problem.cell)
    direct = Simulator(problem.cell)
    direct.move_joints_absolute(ROBOT, problem.goal)
    assert any(e.kind == "collision" for e in direct.events)  # the problem needs a planner
    sim.move_joints_absolute(ROBOT, problem.goal, plan=True)
    np.testing.assert_array_equal(sim.joints(ROBOT), problem.goal)
    samples, bad, found = penetrations(sim, density=10)
    assert bad == 0, found
    assert samples == 10 * (sim.frames - 1) + 1
    assert random_problem(seed).goal.tolist() == problem.goal.tolist()  # seeded
