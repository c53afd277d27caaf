"""move_end_effector with no configuration: a solution whose joint move is clear first.

The issue's case: a UR5e standing on a table, tool pointing down at a point behind it.
The in-limit solution nearest the current joints (smallest largest joint change,
computed here from ``ik_closed_form``) is elbow-down with joint 2 past -180 deg: the
upper arm swings down through the table. Checked from outside the choice:

- the nearest solution's joint move really goes through the table: the elbow (the origin
  of link frame 3, by the robot's own FK) dips below the table top on the way, and the
  simulator's contact check (MuJoCo's collision of the compiled cell) reports table
  collisions when that configuration is asked for;
- the default move ends at the target pose, its elbow stays above the table top on every
  frame, no collision is reported, and the event names the configuration and why.
"""

from __future__ import annotations

import numpy as np
import pytest

from workcell import solids
from workcell.cell.workcell import Workcell
from workcell.robots.ik_closed import config_of
from workcell.sim.simulator import Simulator
from workcell.spatial import rot_x, translation

TOP = 0.75  # m: the table top, where the UR5e stands
Q0 = np.radians([0, -90, 90, -90, -90, 0])  # upper arm straight up, forearm forward
TARGET = translation(0.3, 0.0, TOP + 0.1) @ rot_x(np.pi)  # tool down, 0.1 m above the top


def ur_on_a_table() -> Workcell:
    cell = Workcell("ur_table")
    solids.box(cell.model, "table_block", size=(1.6, 1.2, TOP))
    cell.add_static("table", "table_block", translation(-0.8, -0.6, 0.0))
    cell.add_robot("ur", "ur5e", base=translation(0, 0, TOP), q=Q0)
    return cell


def nearest_solution(robot, T_base, q0):
    """The in-limit closed-form solution with the smallest largest joint change."""
    sols = [s for s in robot.ik_closed_form(T_base, q0) if s.within_limits]
    return min(sols, key=lambda s: float(np.abs(s.q - q0).max()))


def elbow_heights(robot, Q):
    """World z (m) of the elbow at joint rows Q: the origin of UR DH frame 2, on axis 3
    at the end of the upper arm."""
    return np.array([TOP + robot.link_frames(q)[2][2, 3] for q in Q])


def moves(sim):
    return [e for e in sim.events if e.kind == "move"]


def collisions(sim):
    return [e for e in sim.events if e.kind == "collision"]


@pytest.mark.parametrize("mode", ["path", "joint-by-joint"])
def test_the_default_configuration_avoids_the_table_the_nearest_hits(mode):
    cell = ur_on_a_table()
    robot = cell.robots["ur"].robot
    near = nearest_solution(robot, np.linalg.inv(cell.robots["ur"].base) @ TARGET, Q0)
    assert near.config == "ldn"
    assert np.degrees(near.q[1]) < -180  # the upper arm below horizontal, backwards
    # the nearest, asked for by its letters: the upper arm goes through the table
    asked = Simulator(cell, mode=mode)
    asked.move_end_effector("ur", TARGET, config=near.config)
    _, Q = asked.trajectory("ur")
    assert elbow_heights(robot, Q).min() < TOP - 0.05
    hits = [e.detail for e in collisions(asked)]
    assert any("table" in d and "ur.link3" in d for d in hits), hits
    # no configuration: another one, whose move is clear
    sim = Simulator(cell, mode=mode)
    sim.move_end_effector("ur", TARGET)
    assert collisions(sim) == []
    _, Q = sim.trajectory("ur")
    assert elbow_heights(robot, Q).min() > TOP + 0.05
    q = sim.joints("ur")
    np.testing.assert_allclose(sim.tool_pose("ur"), TARGET, atol=1e-9)
    chosen = config_of(robot, q)
    assert chosen != near.config
    detail = moves(sim)[-1].detail
    assert f"configuration '{chosen}', the nearest whose move is clear" in detail
    assert "'ldn' is nearer: table overlaps ur.link3" in detail


def test_the_nearest_is_kept_when_its_move_is_clear():
    cell = ur_on_a_table()
    robot = cell.robots["ur"].robot
    q_goal = Q0 + np.radians([20, 10, -15, 5, 10, 30])  # a small move above the table
    T = cell.robots["ur"].base @ robot.fk(q_goal)
    near = nearest_solution(robot, robot.fk(q_goal), Q0)
    sim = Simulator(cell)
    sim.move_end_effector("ur", T)
    np.testing.assert_allclose(sim.joints("ur"), near.q, atol=1e-9)
    assert (
        f"configuration '{near.config}', the nearest (its move is clear)" in moves(sim)[-1].detail
    )


def test_when_no_move_is_clear_the_nearest_is_taken_and_the_event_says_so():
    cell = ur_on_a_table()
    solids.box(cell.model, "post_block", size=(0.06, 0.06, 0.2))
    # a post the tool touches at the target: every solution's end breaks the clearance
    cell.add_static("post", "post_block", translation(0.27, -0.03, TOP))
    robot = cell.robots["ur"].robot
    near = nearest_solution(robot, np.linalg.inv(cell.robots["ur"].base) @ TARGET, Q0)
    sim = Simulator(cell)
    sim.set_planning(clearance=0.01)
    sim.move_end_effector("ur", TARGET)
    np.testing.assert_allclose(sim.joints("ur"), near.q, atol=1e-9)
    assert "the nearest (no solution's move is clear" in moves(sim)[-1].detail


def test_a_configuration_asked_for_is_taken_as_it_is():
    cell = ur_on_a_table()
    sim = Simulator(cell)
    sim.move_end_effector("ur", TARGET, config="ldn")
    assert config_of(cell.robots["ur"].robot, sim.joints("ur")) == "ldn"
    assert "configuration" not in moves(sim)[-1].detail
