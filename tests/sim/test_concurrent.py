"""Robots moving at the same time: ``with sim.concurrently():`` merges their plans."""

from __future__ import annotations

import functools

import mujoco
import numpy as np
import pytest

from workcell import ProgramError, UnreachableError, compile_cell
from workcell.examples import thesis_handoff as ho
from workcell.sim import Simulator
from workcell.sim.grasp import tool_down
from workcell.sim.tasks import pick

A, B = ho.GIVER, ho.RECEIVER
DQ_A = np.radians([30.0, -10.0, 20.0, 0.0, 15.0, 40.0])  # largest: 40 deg
DQ_B = np.radians([-20.0, 10.0, 0.0, 25.0, 0.0, 0.0])  # largest: 25 deg


@functools.cache
def _cell():
    cell = ho.build()
    return cell, compile_cell(cell)


def make(**kw) -> Simulator:
    cell, cc = _cell()
    kw.setdefault("dt", 0.01)
    return Simulator(cell, compiled=cc, **kw)


def state(sim: Simulator):
    return sim.frames, len(sim.events), sim.sim_time, sim.data.qpos.copy()


@pytest.mark.parametrize("mode", ["path", "playback"])
def test_two_robots_move_together_and_the_clock_takes_the_longer(mode):
    sim = make(mode=mode)
    qa, qb = sim.joints(A), sim.joints(B)
    with sim.concurrently():
        sim.move_joints_relative(A, DQ_A)
        sim.move_joints_relative(B, DQ_B)
        assert sim.frames == 1  # nothing runs before the block ends
    if mode == "playback":
        sim.play()
    speed = sim.speed(A)
    assert sim.sim_time == pytest.approx(np.radians(40.0) / speed, rel=1e-12)  # not the sum
    assert np.allclose(sim.joints(A), qa + DQ_A, atol=1e-12)
    assert np.allclose(sim.joints(B), qb + DQ_B, atol=1e-12)
    t, QA = sim.trajectory(A)
    _, QB = sim.trajectory(B)
    assert np.all(np.diff(t) > 0)
    # each robot moves linearly in joints over its own duration, then holds
    TB = np.radians(25.0) / speed
    sa = np.clip(t / t[-1], 0, 1)[:, None]
    sb = np.clip(t / TB, 0, 1)[:, None]
    assert np.abs(QA - (qa + sa * DQ_A)).max() < 1e-12
    assert np.abs(QB - (qb + sb * DQ_B)).max() < 1e-12
    moves = [e for e in sim.events if e.kind == "move"]
    assert [(e.robot, round(e.t, 9)) for e in moves] == [(B, round(TB, 9)), (A, round(t[-1], 9))]
    assert all(e.frame == int(np.searchsorted(t, e.t + 1e-12) - 1) for e in moves)


def test_a_robots_commands_in_a_block_follow_each_other():
    sim = make()
    q0 = sim.joints(A)
    with sim.concurrently():
        sim.move_joints_relative(A, DQ_A)
        sim.move_joints_relative(A, -DQ_A)
        sim.move_joints_relative(B, DQ_B)
    speed = sim.speed(A)
    assert sim.sim_time == pytest.approx(2 * np.radians(40.0) / speed, rel=1e-12)
    assert np.allclose(sim.joints(A), q0, atol=1e-12)
    t, QA = sim.trajectory(A)
    i = int(np.argmin(np.abs(t - np.radians(40.0) / speed)))
    assert np.allclose(QA[i], q0 + DQ_A, atol=1e-12)  # the turning point


def test_carrying_and_straight_lines_in_a_block():
    sim = make(dt=0.005)
    pick(sim, A, tool_down(ho.SPHERE_START), approach=ho.APPROACH, config=ho.CONFIG)
    start = sim.frames
    up = tool_down(ho.SPHERE_START + np.array([0.0, 0.0, 0.15]))
    with sim.concurrently():
        sim.move_straight_line(A, up)  # carrying the sphere
        sim.move_joints_relative(B, DQ_B)
    assert np.abs(sim.tool_pose(A) - up).max() < 1e-9
    m, d = sim.model, mujoco.MjData(sim.model)
    g, s = m.body(sim.compiled.gripper_bodies[A]).id, m.body(ho.SPHERE).id
    rel = None
    for q in sim.timeline.qpos()[start - 1 :]:
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        G, P = np.eye(4), np.eye(4)
        G[:3, :3], G[:3, 3] = d.xmat[g].reshape(3, 3), d.xpos[g]
        P[:3, :3], P[:3, 3] = d.xmat[s].reshape(3, 3), d.xpos[s]
        r = np.linalg.inv(G) @ P
        rel = r if rel is None else rel
        assert np.abs(r - rel).max() < 1e-9  # the sphere rides with the gripper
    assert sim.summary()["collisions"] == 0


def test_refusals_and_undo():
    sim = make()
    before = state(sim)

    def grasp_in_block():
        with sim.concurrently():
            sim.move_joints_relative(A, DQ_A)
            sim.close_gripper(A)

    def unreachable_in_block():
        with sim.concurrently():
            sim.move_joints_relative(B, DQ_B)
            sim.move_end_effector(A, tool_down((3.0, 0.0, 0.5)))

    with pytest.raises(ProgramError, match="close_gripper cannot run inside"):
        grasp_in_block()
    with pytest.raises(ProgramError, match="wait cannot run inside"), sim.concurrently():
        sim.wait(1.0)
    with pytest.raises(ProgramError, match="do not nest"), sim.concurrently(), sim.concurrently():
        pass
    with pytest.raises(UnreachableError):
        unreachable_in_block()
    after = state(sim)
    assert before[:3] == after[:3]
    assert np.array_equal(before[3], after[3])
    jbj = make(mode="joint-by-joint")
    with pytest.raises(ProgramError, match="joint-by-joint"), jbj.concurrently():
        pass
    with sim.concurrently():  # an empty block does nothing
        pass
    assert state(sim)[:3] == before[:3]
