"""Cartesian commands: move_end_effector and move_straight_line, and the time profiles."""

from __future__ import annotations

import functools
import math

import mujoco
import numpy as np
import pytest

from workcell import KinematicsError, ProgramError, UnreachableError, compile_cell
from workcell.examples import thesis_pick_place as ex
from workcell.robots.ik_closed import config_of as puma_config
from workcell.sim import Simulator
from workcell.sim.grasp import tool_down
from workcell.spatial import angle_between, rot_x, translation

ROBOT = ex.ROBOT


@functools.cache
def _cell():
    cell = ex.build()
    return cell, compile_cell(cell)


def make(**kw) -> Simulator:
    cell, cc = _cell()
    kw.setdefault("dt", 0.005)
    return Simulator(cell, compiled=cc, **kw)


def site_poses(sim: Simulator, robot: str) -> np.ndarray:
    """Tool poses (N, 4, 4) of every frame, replayed through MuJoCo on a fresh MjData."""
    m = sim.model
    d = mujoco.MjData(m)
    site = m.site(sim.compiled.tool_sites[robot]).id
    Q = sim.timeline.qpos()
    out = np.repeat(np.eye(4)[None], len(Q), axis=0)
    for i, q in enumerate(Q):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        out[i, :3, :3] = d.site_xmat[site].reshape(3, 3)
        out[i, :3, 3] = d.site_xpos[site]
    return out


def state(sim: Simulator):
    return (sim.frames, len(sim.events), sim.sim_time, sim.data.qpos.copy(), list(sim.grasps))


def same_state(a, b) -> bool:
    return a[:3] == b[:3] and np.array_equal(a[3], b[3]) and a[4] == b[4]


def test_move_end_effector_reaches_the_pose_linearly_in_joints():
    sim = make()
    T = translation(0, 0, 0.05) @ tool_down(ex.grasp_position(), 0.4)
    q0 = sim.joints(ROBOT)
    sim.move_end_effector(ROBOT, T)
    got = sim.tool_pose(ROBOT)
    assert np.abs(got[:3, 3] - T[:3, 3]).max() < 1e-9
    assert angle_between(got, T) < 1e-9
    t, Q = sim.trajectory(ROBOT)
    q1 = Q[-1]
    # eq. 4.27: the motion takes max |dq| / speed, every joint linear in time
    assert math.isclose(t[-1], np.abs(q1 - q0).max() / sim.speed(ROBOT), rel_tol=1e-12)
    s = t[1:] / t[-1]
    assert np.abs(Q[1:] - (q0 + np.outer(s, q1 - q0))).max() < 1e-12


def test_configuration_is_honoured_and_listed_when_missing():
    sim = make()
    T = translation(0, 0, 0.05) @ tool_down(ex.grasp_position())
    for config in ("ru", "ld", "rdf"):
        sim.move_end_effector(ROBOT, T, config=config)
        letters = puma_config(sim.cell.robots[ROBOT].robot, sim.joints(ROBOT))
        assert all(c in letters for c in config)
        assert np.abs(sim.tool_pose(ROBOT)[:3, 3] - T[:3, 3]).max() < 1e-9
    with pytest.raises(KinematicsError, match="letters"):
        sim.move_end_effector(ROBOT, T, config="xyz")


def test_unreachable_pose_raises_and_changes_nothing():
    sim = make()
    before = state(sim)
    with pytest.raises(UnreachableError, match="out of reach"):
        sim.move_end_effector(ROBOT, tool_down((2.0, 0.0, 0.5)))
    with pytest.raises(KinematicsError, match="rigid"):
        sim.move_end_effector(ROBOT, np.diag([2.0, 1.0, 1.0, 1.0]))
    assert same_state(before, state(sim))


@pytest.mark.parametrize("mode", ["path", "joint-by-joint", "playback"])
def test_straight_line_stays_on_the_line_with_orientation_held(mode):
    sim = make(mode=mode, dt=0.002)
    start = translation(0, 0, 0.06) @ tool_down(ex.grasp_position(), 0.2)
    sim.move_end_effector(ROBOT, start)
    n0 = sim.frames
    goal = translation(-0.1, 0.14, -0.02) @ start
    sim.move_straight_line(ROBOT, goal, step=0.01)
    if mode == "playback":
        sim.play()
    P = site_poses(sim, ROBOT)[n0 - 1 :]
    p0, p1 = start[:3, 3], goal[:3, 3]
    d = p1 - p0
    s = np.clip((P[:, :3, 3] - p0) @ d / (d @ d), 0, 1)
    dev = np.linalg.norm(P[:, :3, 3] - (p0 + np.outer(s, d)), axis=1)
    assert dev.max() <= sim.line_tolerance
    assert max(angle_between(start, T) for T in P) < 1e-3  # held (joint-linear between samples)
    assert np.abs(P[-1] - goal).max() < 1e-9
    assert np.all(np.diff(s) >= -1e-9)  # monotone along the line


def test_straight_line_slerps_orientation():
    sim = make(dt=0.005)
    start = translation(0, 0, 0.06) @ tool_down(ex.grasp_position())
    sim.move_end_effector(ROBOT, start)
    goal = start @ rot_x(math.radians(20))
    sim.move_straight_line(ROBOT, goal, step=0.01)
    assert angle_between(sim.tool_pose(ROBOT), goal) < 1e-9
    assert np.abs(sim.tool_pose(ROBOT)[:3, 3] - start[:3, 3]).max() < 1e-9


def test_impossible_lines_say_where_and_change_nothing():
    sim = make()
    start = translation(0, 0, 0.06) @ tool_down(ex.grasp_position())
    sim.move_end_effector(ROBOT, start)
    before = state(sim)
    with pytest.raises(UnreachableError, match=r"at \d+% of the line.*out of reach"):
        sim.move_straight_line(ROBOT, translation(0.6, 0, 0) @ start)
    with pytest.raises(UnreachableError, match="would jump"):
        sim.move_straight_line(ROBOT, translation(0, 0.1, 0) @ start, max_jump=1e-4)
    fussy = make(line_tolerance=1e-7)
    fussy.move_end_effector(ROBOT, start)
    with pytest.raises(UnreachableError, match="strays"):
        fussy.move_straight_line(ROBOT, translation(0, 0.1, 0) @ start)
    with pytest.raises(ProgramError, match="step"):
        sim.move_straight_line(ROBOT, start, step=0.0)
    assert same_state(before, state(sim))


@pytest.mark.parametrize("profile", ["trapezoid", "quintic"])
def test_profiles_respect_speed_and_acceleration(profile):
    sim = make(profile=profile, acceleration=1.5, dt=0.001)
    q0 = sim.joints(ROBOT)
    dq = np.radians([40.0, -20.0, 10.0, 0.0, 5.0, -30.0])
    sim.move_joints_relative(ROBOT, dq)
    t, Q = sim.trajectory(ROBOT)
    big, v, a = np.abs(dq).max(), sim.speed(ROBOT), 1.5
    T = big / v + v / a if profile == "trapezoid" else 1.875 * big / v
    assert math.isclose(t[-1], T, rel_tol=1e-12)
    assert np.abs(Q[-1] - (q0 + dq)).max() < 1e-12
    vel = np.diff(Q[:, 0]) / np.diff(t)
    assert np.abs(vel).max() <= v * (1 + 1e-6)
    assert np.abs(vel).max() >= v * 0.99  # the peak speed is reached
    mid = (t[1:] + t[:-1]) / 2
    acc = np.diff(vel) / np.diff(mid)
    if profile == "trapezoid":
        assert np.abs(acc).max() <= a * 1.01
    # every joint follows the same normalised progress
    s = (Q - q0)[:, 0] / dq[0]
    assert np.abs((Q - q0)[:, 5] / dq[5] - s).max() < 1e-12


def test_short_trapezoid_is_a_triangle():
    sim = make(profile="trapezoid", acceleration=0.5, dt=0.001)
    sim.move_joints_relative(ROBOT, np.radians([2.0, 0, 0, 0, 0, 0]))
    t, _ = sim.trajectory(ROBOT)
    assert math.isclose(t[-1], 2 * math.sqrt(math.radians(2.0) / 0.5), rel_tol=1e-12)


def test_bad_options_are_refused():
    cell, cc = _cell()
    with pytest.raises(ProgramError, match="profile"):
        Simulator(cell, compiled=cc, profile="cubic")
    with pytest.raises(ProgramError, match="acceleration"):
        Simulator(cell, compiled=cc, acceleration=-1.0)
    sim = make()
    with pytest.raises(ProgramError, match="mode"):
        sim.set_mode("fast")
    sim.set_mode("joint-by-joint")
    assert sim.mode == "joint-by-joint"


def test_long_commands_show_progress(capsys):
    sim = make(dt=0.001, progress=True)
    sim.set_speed(ROBOT, 0.01)
    sim.move_joints_relative(ROBOT, np.radians([70.0, 0, 0, 0, 0, 0]))  # 122,173 frames
    err = capsys.readouterr().err
    assert "move_joints_relative" in err
    assert "frame" in err
    quiet = make(dt=0.001, progress=False)
    quiet.set_speed(ROBOT, 0.01)
    quiet.move_joints_relative(ROBOT, np.radians([70.0, 0, 0, 0, 0, 0]))
    assert capsys.readouterr().err == ""
