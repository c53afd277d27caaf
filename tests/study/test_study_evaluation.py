"""One candidate's row against hand formulas and independent runs.

Cycle times come from the simulator run on a cell moved by hand (JSON edited, compiled
afresh); speeds from eq. 4.27; the clearance of example 2 from its geometry (the finger
tips 7.5 mm over the table at the grasp) and from ``mj_geomDistance`` on every frame;
the reach margin from the Puma 260's reach sphere (DESIGN.md's DH table); the joint-limit
margin from the joint limits table and example 1's poses.
"""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest
import study_programs as sp

from workcell.cell import Workcell
from workcell.examples import thesis_joints, thesis_pick_place
from workcell.program.interpreter import run_script
from workcell.program.session import Session
from workcell.sim import Simulator
from workcell.study import Study
from workcell.study.candidates import Candidate
from workcell.study.evaluation import Evaluator
from workcell.study.prepare import prepare

ASSETS = Path(__file__).resolve().parents[2] / "assets"
# Puma 260 (DESIGN.md): d1, a2 (exact), d3, d4; flange; default gripper (parallel_gripper)
D1, D3, D4 = 0.3302, 0.12446, 0.2032
A2 = 0.0254 * math.hypot(7.8, 0.75)
FLANGE, PALM, FINGER = 0.05588, 0.03, 0.05
TOOL = FLANGE + PALM + FINGER - FINGER / 4  # flange to TCP (tcp_depth = finger_length / 4)
REACH = math.hypot(A2 + D4, D3)  # farthest wrist centre from the shoulder


def _evaluate(study: Study, *values) -> dict:
    setup, _ = prepare(study)
    return Evaluator(setup).evaluate(Candidate(0, tuple(values)))


def _moved_cell(x: float, y: float) -> Workcell:
    """Example 2's cell with the robot's base at (x, y), by editing its saved form."""
    data = thesis_pick_place.build().to_dict()
    data["robots"][0]["base"][0][3] = x
    data["robots"][0]["base"][1][3] = y
    return Workcell.from_dict(data)


@pytest.mark.parametrize(("x", "y"), [(0.0, 0.0), (0.05, -0.1), (0.1, -0.05)])
def test_cycle_time_is_the_simulated_time_of_the_moved_cell(x, y):
    study = Study(cell="pick-place", vary={"puma.base.x": [x], "puma.base.y": [y]})
    row = _evaluate(study, x, y)
    sim = Simulator(_moved_cell(x, y))
    thesis_pick_place.program(sim)
    assert row["feasible"], row["error"]
    assert row["cycle_time_s"] == sim.sim_time
    assert (row["error"], row["error_type"]) == ("", "")


def test_clearance_of_example_2_is_the_finger_tips_over_the_table():
    row = _evaluate(Study(cell="pick-place", vary={"puma.base.x": [0.0]}), 0.0)
    tips = thesis_pick_place.CUBE_SIZE / 2 - FINGER / 4  # TCP at the cube's centroid
    assert row["min_clearance_m"] == pytest.approx(tips, abs=1e-6)
    assert row["clearance_pair"] in ("puma.gripper.left / table", "puma.gripper.right / table")
    tol = Study(cell="pick-place", vary={"puma.base.x": [0.0]}).clearance_tolerance
    assert tips - tol - 1e-9 <= row["clearance_bound_m"] <= row["min_clearance_m"]


def test_clearance_agrees_with_geom_distance_on_every_frame():
    study = Study(cell="pick-place", vary={"puma.base.x": [0.05]})
    setup, _ = prepare(study)
    ev = Evaluator(setup)
    row = ev.evaluate(Candidate(0, (0.05,)))
    sim = ev.run(Candidate(0, (0.05,)))
    m, d = sim.model, mujoco.MjData(sim.model)
    robot = [
        g for g in sim.contacts.geoms_of("puma") if m.geom_bodyid[g] != m.body("puma.link0").id
    ]
    static = [g for g in sim.contacts.colliding if m.geom_bodyid[g] == 0]
    lowest = math.inf
    for q in sim.timeline.qpos():
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        for g in robot:
            for h in static:
                lowest = min(lowest, mujoco.mj_geomDistance(m, d, int(g), int(h), 0.1, None))
    tol = study.clearance_tolerance
    assert row["clearance_bound_m"] <= lowest + 1e-9  # a lower bound of every frame
    assert row["min_clearance_m"] <= lowest + tol + 1e-9
    assert row["min_clearance_m"] - row["clearance_bound_m"] <= tol + 1e-12


@pytest.mark.parametrize(("speed", "override"), [(0.6, None), (None, 0.5), (0.2, None)])
def test_pinned_speed_and_override_follow_eq_4_27(speed, override):
    vary = {"puma.speed": [speed]} if speed else {"puma.override": [override]}
    row = _evaluate(Study(cell="joints", vary=vary), speed or override)
    effective = speed or thesis_joints.SPEED * override
    assert row["cycle_time_s"] == pytest.approx(
        thesis_joints.expected_sim_time(effective), abs=1e-9
    )


def test_a_pinned_override_scales_jerk_limited_moves_by_its_inverse():
    """Speeds x f, accelerations x f^2, jerks x f^3: the same path in exactly 1/f the time,
    whatever override the program itself sets."""
    study = Study(cell="joints", program=sp.jerk_joint_moves, vary={"puma.override": "1,0.5,0.25"})
    setup, _ = prepare(study)
    ev = Evaluator(setup)
    t = {c.values[0]: ev.evaluate(c)["cycle_time_s"] for c in study.candidates()}
    assert t[0.5] == pytest.approx(2 * t[1.0], rel=1e-9)
    assert t[0.25] == pytest.approx(4 * t[1.0], rel=1e-9)


def test_joint_limit_margin_of_example_1_is_joint_5_at_90_deg():
    # limits (deg, DESIGN.md): j1 +-160, j2 -76..256, j3 -214..34, j4 -194..384, j5 +-122,
    # j6 +-267; example 1's poses (start, after the relative move, absolute) are the
    # extremes of its linear moves; the closest is joint 5 at 90 deg: 122 - 90 = 32 deg
    limits = [(-160, 160), (-76, 256), (-214, 34), (-194, 384), (-122, 122), (-267, 267)]
    start = np.array(thesis_joints.START_DEG)
    poses = [start, start + thesis_joints.RELATIVE_DEG, np.array(thesis_joints.ABSOLUTE_DEG)]
    by_hand = min(min(q - lo, hi - q) for p in poses for q, (lo, hi) in zip(p, limits, strict=True))
    assert by_hand == 32
    row = _evaluate(Study(cell="joints", vary={"puma.base.x": [0.3]}), 0.3)
    assert row["joint_limit_margin_deg"] == pytest.approx(by_hand, abs=1e-9)
    assert row["reach_margin_m"] is None  # no Cartesian target in example 1


@pytest.mark.parametrize("x", [0.0, 0.04])
def test_reach_margin_is_the_distance_to_the_reach_sphere(x):
    study = Study(cell="pick-place", program=sp.reach_one_pose, vary={"puma.base.x": [x]})
    row = _evaluate(study, x)
    assert row["feasible"], row["error"]
    shoulder = np.array([x, 0.0, thesis_pick_place.TABLE_TOP + D1])
    p = np.array(sp.TARGET)
    wrist = p + np.array([0.0, 0.0, TOOL])  # the tool points down
    u = (p - shoulder) / np.linalg.norm(p - shoulder)
    b = u @ (wrist - shoulder)
    out = -b + math.sqrt(b * b - ((wrist - shoulder) @ (wrist - shoulder) - REACH**2))
    assert 0.005 < out < 0.1  # near the boundary: the outward distance is the margin
    assert row["reach_margin_m"] == pytest.approx(out, abs=1e-3)  # the search's resolution
    assert row["reach_margin_m"] <= out


def test_infeasible_candidates_say_why():
    study = Study(
        cell="pick-place",
        vary={"puma.base.z": [0.4, 0.3], "cube.x": [0.28, 0.9], "stage_1.y": [0.16, -0.2]},
    )
    setup, _ = prepare(study)
    ev = Evaluator(setup)
    rows = {c.values: ev.evaluate(c) for c in study.candidates()}
    assert rows[(0.4, 0.28, 0.16)]["feasible"]
    sunk = rows[(0.3, 0.28, 0.16)]  # the base 0.1 m down in the table
    assert sunk["error_type"] == "CollisionError"
    assert "puma.link0 with table" in sunk["error"]
    assert sunk["cycle_time_s"] is None
    moved_cube = rows[(0.4, 0.9, 0.16)]  # example 2's program grasps where the cube was
    assert moved_cube["error_type"] == "GraspError"
    assert "nearest candidate 'cube'" in moved_cube["error"]
    on_cube = rows[(0.4, 0.28, -0.2)]  # stage 1 moved over the cube
    assert on_cube["error_type"] == "CollisionError"
    assert "cube with stage_1" in on_cube["error"]
    assert not any(r["feasible"] for v, r in rows.items() if v != (0.4, 0.28, 0.16))


def _divide_by_zero(sim) -> None:
    raise ZeroDivisionError("a bug in the program")


def test_any_exception_becomes_the_candidates_error_row():
    row = _evaluate(Study(cell="joints", program=_divide_by_zero, vary={"puma.base.x": [0.0]}), 0.0)
    assert not row["feasible"]
    assert row["error"] == "ZeroDivisionError: a bug in the program"


def test_a_wcl_program_on_a_cell_file_runs_like_the_script_itself(tmp_path):
    """Each candidate of a study of a .wcl program on a cell file (one evaluator for all,
    the script parsed once) against the script run directly on the moved cell."""
    base = thesis_pick_place.build()
    base.save(tmp_path / "cell.json")
    body = (ASSETS / "thesis_example2.wcl").read_text().split("simulate path dt 0.01\n", 1)[1]
    study = Study(
        cell=str(tmp_path / "cell.json"),
        program=ASSETS / "thesis_example2.wcl",
        vary={"puma.base.x": [0.0, 0.05], "puma.base.y": [-0.05]},
    )
    setup, _ = prepare(study)
    ev = Evaluator(setup)
    for c in study.candidates():
        x, y = c.values
        _moved_cell(x, y).save(tmp_path / "moved.json")
        script = tmp_path / "moved.wcl"
        script.write_text(f"cell load moved.json\nsimulate path dt 0.01\n{body}")
        session = run_script(script, Session(base_dir=tmp_path), out=lambda s: None)
        row = ev.evaluate(c)
        assert row["feasible"], row["error"]
        assert row["cycle_time_s"] == session.sim.sim_time
        assert row["cycle_time_s"] > 20  # the whole program ran


def test_work_limits_where_the_study_is_set_up_apply_in_every_worker():
    from workcell import limits
    from workcell.study import run

    study = Study(cell="joints", program=sp.asks_for_5000_frames, vary={"puma.base.x": [0.0]})
    with limits.using(max_frames=1000):
        table = run(study, backend="process", workers=1, progress=False)
    row = table.to_pylist()[0]
    assert row["error_type"] == "LimitError"
    assert "over the limit max_frames = 1,000" in row["error"]
    assert run(study, backend="serial", progress=False).to_pylist()[0]["feasible"]
