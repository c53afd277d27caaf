"""move_linear and move_circular: the tool on the line or arc at its programmed speed,
the joints within their limits; move_straight_line as a case of the same machinery."""

from __future__ import annotations

import numpy as np
import pytest
from motion_helpers import (
    ACCELERATION,
    SPEED,
    derivatives,
    limited,
    make,
    pose,
    tool_points,
)

from workcell import ProgramError, UnreachableError, Workcell, compile_cell
from workcell.sim import Simulator
from workcell.spatial import angle_between, rot_z, translation

V, A = 0.25, 0.5  # m/s, m/s^2 (within what this arm's joints allow here)


def at_start(key: str = "limited", offset=(0.0, 0.0, 0.0), **kw) -> Simulator:
    sim = make(key, **kw)
    sim.move_end_effector("puma", pose(offset), config="ru")
    return sim


def own_frames(sim: Simulator, first: int) -> tuple[np.ndarray, np.ndarray]:
    """Times and tool points of the frames from ``first`` on (with the one before)."""
    P = tool_points(sim)
    return sim.timeline.sim_times()[first - 1 :], P[first - 1 :]


def test_a_line_is_followed_exactly_at_the_programmed_speed():
    sim = at_start(dt=0.005)
    first = sim.frames
    start = sim.tool_pose("puma")
    goal = translation(0.0, 0.2, -0.04) @ start
    sim.move_linear("puma", goal, speed=V, acceleration=A)
    t, P = own_frames(sim, first)
    p0, p1 = start[:3, 3], goal[:3, 3]
    u = (p1 - p0) / np.linalg.norm(p1 - p0)
    rel = P - p0
    off_line = np.linalg.norm(rel - np.outer(rel @ u, u), axis=1)
    assert off_line.max() < 1e-6  # on the line, to MuJoCo's own FK
    assert np.allclose(P[-1], p1, atol=1e-9)
    speed = np.linalg.norm(np.diff(P, axis=0), axis=1) / np.diff(t)
    assert speed.max() <= V * (1 + 1e-6)
    cruise = speed[speed > 0.99 * V]
    assert np.abs(cruise - V).max() < 0.01 * V
    assert len(cruise) > 20
    L = np.linalg.norm(p1 - p0)  # a trapezoid in tool speed: L / v + v / a
    assert sim.cycle_time()["commands"][-1]["duration_s"] == pytest.approx(L / V + V / A, rel=0.01)
    assert sim.cycle_time()["commands"][-1]["limited_by"] in ("tool speed", "tool acceleration")


def test_the_orientation_is_slerped_along_the_line():
    sim = at_start(dt=0.01)
    first = sim.frames
    start = sim.tool_pose("puma")
    goal = translation(0.0, 0.12, 0.0) @ start @ rot_z(np.radians(60.0))
    sim.move_linear("puma", goal, speed=V)
    P = tool_points(sim)[first - 1 :]
    frac = np.linalg.norm(P - P[0], axis=1) / np.linalg.norm(P[-1] - P[0])
    Q = sim.timeline.qpos()[first - 1 :, sim._qadr["puma"]]
    robot = sim.cell.robots["puma"]
    for q, f in zip(Q[::7], frac[::7], strict=True):
        R = (robot.base @ robot.robot.fk(q))[:3, :3]
        expected = start[:3, :3] @ rot_z(np.radians(60.0) * f)[:3, :3]  # same axis: tool z
        assert angle_between(R, expected) < 1e-6


def test_the_joints_stay_within_their_limits_and_slow_the_tool_where_they_must():
    slow_j1 = SPEED.copy()
    slow_j1[0] = np.radians(10.0)  # joint 1 can hardly move
    cell = Workcell("slow")
    cell.add_robot("puma", limited(speed=slow_j1), base=translation(0, 0, 0.4), q=np.zeros(6))
    sim = Simulator(cell, compiled=compile_cell(cell), dt=0.005, check_collisions=False)
    sim.move_end_effector("puma", pose(), config="ru")
    first = sim.frames
    goal = translation(0.0, 0.2, 0.0) @ sim.tool_pose("puma")  # sideways: joint 1 turns
    sim.move_linear("puma", goal, speed=V)
    t = sim.timeline.sim_times()[first - 1 :]
    Q = sim.timeline.qpos()[first - 1 :, sim._qadr["puma"]]
    v, a, _ = derivatives(t, Q)
    assert (np.abs(v) / slow_j1).max() <= 1.0 + 1e-3
    assert (np.abs(a) / ACCELERATION).max() <= 1.0 + 1e-3
    rec = sim.cycle_time()["commands"][-1]
    assert rec["limited_by"] == "j1 speed"
    assert rec["duration_s"] > 2 * 0.2 / V  # far slower than the programmed speed


def test_an_unreachable_line_says_where_and_changes_nothing():
    sim = at_start()
    before = sim.frames, len(sim.events), sim.sim_time, sim.joints("puma")
    far = translation(0.4, 0.0, 0.0) @ sim.tool_pose("puma")
    with pytest.raises(
        UnreachableError, match=r"move_linear 'puma': at \d+% of the move_linear, tool at"
    ):
        sim.move_linear("puma", far, speed=V)
    assert (sim.frames, len(sim.events), sim.sim_time) == before[:3]
    assert np.array_equal(sim.joints("puma"), before[3])


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"speed": 0.0}, "speed must be a number of m/s > 0"),
        ({"speed": V, "acceleration": -1.0}, "acceleration must be a number of m/s\\^2 > 0"),
        ({"speed": V, "zone": -0.01}, "zone must be a number of m >= 0"),
        ({"speed": float("inf")}, "speed must be"),
    ],
)
def test_bad_tool_arguments_are_refused(kw, match):
    sim = at_start()
    with pytest.raises(ProgramError, match=match):
        sim.move_linear("puma", translation(0, 0.05, 0) @ sim.tool_pose("puma"), **kw)


def test_a_pure_turn_is_no_linear_move():
    sim = at_start()
    with pytest.raises(ProgramError, match="would not move"):
        sim.move_linear("puma", sim.tool_pose("puma") @ rot_z(0.3), speed=V)


def test_the_override_scales_a_linear_move_by_one_over_f():
    times = []
    for f in (1.0, 0.5):
        sim = at_start()
        sim.set_override("puma", f)
        t0 = sim.sim_time
        sim.move_linear("puma", translation(0, 0.15, 0) @ sim.tool_pose("puma"), speed=V)
        times.append(sim.sim_time - t0)
    assert times[1] == pytest.approx(2 * times[0], rel=1e-6)


def test_an_arc_passes_through_its_three_points_on_the_circle():
    sim = at_start(dt=0.005)
    first = sim.frames
    p0 = sim.tool_pose("puma")[:3, 3]
    via = p0 + np.array([-0.05, 0.06, 0.0])
    goal = translation(0.0, 0.12, 0.0) @ sim.tool_pose("puma")
    sim.move_circular("puma", via, goal, speed=0.2)
    P = tool_points(sim)[first - 1 :]
    # the circle through p0, via, p2 by perpendicular bisectors (independent of the code)
    p2 = goal[:3, 3]
    n = np.cross(via - p0, p2 - p0)
    M = np.array([via - p0, p2 - p0, n])
    rhs = np.array([(via @ via - p0 @ p0) / 2, (p2 @ p2 - p0 @ p0) / 2, n @ p0])
    c = np.linalg.solve(M, rhs)
    r = np.linalg.norm(p0 - c)
    assert np.abs(np.linalg.norm(P - c, axis=1) - r).max() < 1e-6
    assert np.abs((P - c) @ (n / np.linalg.norm(n))).max() < 1e-6
    assert np.linalg.norm(P - via, axis=1).min() < 0.2 * sim.dt  # passes the via point
    assert np.allclose(P[-1], p2, atol=1e-9)


def test_collinear_arc_points_are_refused():
    sim = at_start()
    p0 = sim.tool_pose("puma")[:3, 3]
    goal = translation(0.0, 0.1, 0.0) @ sim.tool_pose("puma")
    with pytest.raises(ProgramError, match="collinear"):
        sim.move_circular("puma", p0 + np.array([0.0, 0.05, 0.0]), goal, speed=0.2)
    with pytest.raises(ProgramError, match="via must be"):
        sim.move_circular("puma", [1.0, 2.0], goal, speed=0.2)


def test_under_profile_jerk_a_straight_line_is_as_fast_as_the_joints_allow():
    thesis = at_start()  # the thesis's timing (checked in test_motion): 0.3 rad/s joints
    t0 = thesis.sim_time
    goal = translation(0.0, 0.0, -0.05) @ thesis.tool_pose("puma")
    thesis.move_straight_line("puma", goal)
    jerk = at_start(profile="jerk", dt=0.005)
    first = jerk.frames
    jerk.move_straight_line("puma", goal)
    t = jerk.timeline.sim_times()[first - 1 :]
    Q = jerk.timeline.qpos()[first - 1 :, jerk._qadr["puma"]]
    v, a, _ = derivatives(t, Q)
    assert (np.abs(v) / SPEED).max() <= 1.0 + 1e-3
    assert (np.abs(a) / ACCELERATION).max() <= 1.0 + 1e-3
    assert max((np.abs(v) / SPEED).max(), (np.abs(a) / ACCELERATION).max()) > 0.98
    assert t[-1] - t[0] < thesis.sim_time - t0
    P = tool_points(jerk)[first - 1 :]
    u = goal[:3, 3] - P[0]
    rel = P - P[0]
    assert np.linalg.norm(rel - np.outer(rel @ u / (u @ u), u), axis=1).max() < 1e-6
    assert jerk.cycle_time()["commands"][-1]["limited_by"].startswith("j")
