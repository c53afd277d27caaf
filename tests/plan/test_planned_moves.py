"""``plan=True`` on the simulator's moves: collision-free, reproducible, failing cleanly.

References: the independent re-check of every frame interval at 10x density with plain
MuJoCo on the exported MJCF (``workcell.examples.plan_problems.penetrations``); the goal
given; the direct move's collisions as the simulator reports them.
"""

from __future__ import annotations

import numpy as np
import pytest

from workcell.errors import JointLimitError, PlanningError, ProgramError
from workcell.examples import obstacle
from workcell.examples.plan_problems import penetrations
from workcell.sim import Simulator
from workcell.sim.grasp import tool_down

ROBOT = obstacle.ROBOT
# above stage 1 and above stage 2, the wall between them (tool down, config ru)
ABOVE_1 = tool_down([0.28, -0.2, 0.62])
ABOVE_2 = tool_down([0.28, 0.2, 0.62])


def state(sim: Simulator) -> tuple:
    return (sim.frames, sim.sim_time, tuple(sim.events), tuple(sim.joints(ROBOT)))


@pytest.fixture(scope="module")
def cell():
    return obstacle.build()


def test_the_direct_move_collides_the_planned_one_does_not(cell):
    direct = Simulator(cell)
    direct.move_end_effector(ROBOT, ABOVE_1, config="ru")
    direct.move_end_effector(ROBOT, ABOVE_2, config="ru")
    assert any(e.kind == "collision" and "wall" in e.detail for e in direct.events)
    sim = Simulator(cell)
    sim.move_end_effector(ROBOT, ABOVE_1, config="ru")
    sim.move_end_effector(ROBOT, ABOVE_2, config="ru", plan=True)
    assert not [e for e in sim.events if e.kind == "collision"]
    np.testing.assert_allclose(sim.tool_pose(ROBOT), ABOVE_2, atol=1e-9)
    samples, bad, found = penetrations(sim, density=10)
    assert samples > 10 * (sim.frames - 1)
    assert bad == 0, found
    # every frame of the planned move stays clear of the wall by the clearance's half
    assert "via point" in [e for e in sim.events if e.kind == "move"][-1].detail


def test_same_program_same_frames_and_the_profile_is_the_simulators(cell):
    goal = np.radians([60, 40, -170, 0, -50, 150])
    runs = []
    for profile in ("linear", "linear", "trapezoid"):
        sim = Simulator(cell, profile=profile)
        sim.move_end_effector(ROBOT, ABOVE_1, config="ru")
        sim.move_joints_absolute(ROBOT, goal, plan=True)
        runs.append(sim)
    np.testing.assert_array_equal(runs[0].timeline.qpos(), runs[1].timeline.qpos())
    trap = runs[2]
    np.testing.assert_allclose(trap.joints(ROBOT), goal, atol=0)
    # trapezoid: each segment starts and ends at rest (the thesis profiles are rest to rest)
    t, Q = trap.trajectory(ROBOT)
    start = int(np.searchsorted(t, runs[0].trajectory(ROBOT)[0][0], side="right"))
    v = np.abs(np.diff(Q, axis=0)).max(axis=1) / np.maximum(np.diff(t), 1e-12)
    assert trap.sim_time > runs[0].sim_time  # accelerating costs time
    assert v[start:].max() <= trap.speed(ROBOT) * (1 + 1e-6)


def test_joint_by_joint_mode_moves_a_planned_path_with_all_joints_together(cell):
    sim = Simulator(cell, mode="joint-by-joint")
    sim.move_joints_absolute(ROBOT, np.radians([20, 10, -100, 10, 80, 10]), plan=True)
    _, Q = sim.trajectory(ROBOT)
    moving = (np.abs(np.diff(Q, axis=0)) > 1e-12).sum(axis=1)
    assert moving.max() == 6  # not one joint at a time


def test_failures_say_why_and_change_nothing(cell):
    sim = Simulator(cell)
    sim.move_end_effector(ROBOT, ABOVE_1, config="ru")
    before = state(sim)
    # a goal with the gripper inside the wall
    inside = tool_down([0.3, 0.0, 0.55])
    with pytest.raises(PlanningError, match=r"goal in collision: .*wall"):
        sim.move_end_effector(ROBOT, inside, plan=True)
    with pytest.raises(PlanningError, match="goal unreachable"):
        sim.move_end_effector(ROBOT, tool_down([2.0, 0.0, 0.5]), plan=True)
    with pytest.raises(JointLimitError):
        sim.move_joints_absolute(ROBOT, np.radians([200, 0, 0, 0, 0, 0]), plan=True)
    with pytest.raises(ProgramError, match="concurrently"), sim.concurrently():
        sim.move_joints_absolute(ROBOT, sim.joints(ROBOT) + 0.1, plan=True)
    assert state(sim) == before
    sim.set_planning(time_limit=1e-3)
    with pytest.raises(PlanningError, match="time limit reached"):
        sim.move_end_effector(ROBOT, ABOVE_2, config="ru", plan=True)
    assert state(sim) == before
    with pytest.raises(ProgramError, match=r"clearance must be a number in \(0, 1\]"):
        sim.set_planning(clearance=-1.0)
    with pytest.raises(ProgramError, match=r"time_limit must be a number in \(0, 600\]"):
        sim.set_planning(time_limit=1e9)
    assert sim.set_planning(time_limit=5.0, seed=3)["seed"] == 3
