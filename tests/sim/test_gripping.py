"""Grasping in the simulator: weld carry, release, handoff, collisions and clearance."""

from __future__ import annotations

import functools
import math

import mujoco
import numpy as np
import pytest

from workcell import CollisionError, GraspError, ProgramError, Workcell, compile_cell, solids
from workcell.examples import thesis_handoff as ho
from workcell.examples import thesis_pick_place as pp
from workcell.sim import Simulator
from workcell.sim.grasp import tool_down
from workcell.spatial import rot_y, translation

ROBOT = pp.ROBOT
UP = translation(0, 0, pp.APPROACH)


@functools.cache
def _cell(which: str):
    cell = {"pp": pp.build, "ho": ho.build}[which]()
    return cell, compile_cell(cell)


def make(which: str = "pp", **kw) -> Simulator:
    cell, cc = _cell(which)
    kw.setdefault("dt", 0.005)
    return Simulator(cell, compiled=cc, **kw)


def at_cube(sim: Simulator, T=None) -> None:
    grasp = tool_down(pp.grasp_position()) if T is None else T
    sim.move_end_effector(ROBOT, UP @ grasp, config="ru")
    sim.move_straight_line(ROBOT, grasp)


def body_pose(m, d, body: int) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = d.xmat[body].reshape(3, 3)
    T[:3, 3] = d.xpos[body]
    return T


def replay(sim: Simulator, start: int = 0):
    """(frame index, MjData) for every frame from ``start``, on a fresh MjData."""
    d = mujoco.MjData(sim.model)
    for i, q in enumerate(sim.timeline.qpos()[start:], start):
        d.qpos[:] = q
        mujoco.mj_kinematics(sim.model, d)
        yield i, d


def snapshot(sim: Simulator):
    return (
        sim.frames,
        len(sim.events),
        sim.sim_time,
        sim.data.qpos.copy(),
        {r: sim.held(r) for r in sim.robots},
        sim.data.eq_active.copy(),
        len(sim.grasps),
    )


def unchanged(a, b) -> bool:
    return all(
        np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y
        for x, y in zip(a, b, strict=True)
    )


@pytest.mark.parametrize("mode", ["path", "playback"])
def test_carried_part_follows_the_gripper_exactly_at_every_frame(mode):
    sim = make(mode=mode)
    at_cube(sim)
    assert sim.close_gripper(ROBOT) == pp.CUBE
    g0 = sim.frames - 1
    (rec,) = sim.grasps
    assert rec.kind == "grasp"
    assert rec.frame == g0
    assert rec.part == pp.CUBE
    sim.move_straight_line(ROBOT, UP @ tool_down(pp.grasp_position()))
    sim.move_joints_relative(ROBOT, np.radians([30, -10, 15, 20, -25, 40]))
    if mode == "playback":
        sim.play()
    m = sim.model
    g = m.body(sim.compiled.gripper_bodies[ROBOT]).id
    c = m.body(pp.CUBE).id
    # the relative pose captured at the grasp, from the grasp frame itself
    _, d = next(replay(sim, g0))
    rel = np.linalg.inv(body_pose(m, d, g)) @ body_pose(m, d, c)
    # the cube's centroid sat at the tool-centre point
    tcp = d.site_xpos[m.site(sim.compiled.tool_sites[ROBOT]).id]
    centroid = body_pose(m, d, c) @ np.append(np.full(3, pp.CUBE_SIZE / 2), 1.0)
    assert np.abs(centroid[:3] - tcp).max() < 1e-9
    worst = 0.0
    for _, d in replay(sim, g0):
        worst = max(worst, np.abs(body_pose(m, d, g) @ rel - body_pose(m, d, c)).max())
    assert worst < 1e-9
    # the weld is active with the captured pose (for physics and the exported model)
    e = m.equality(sim.compiled.welds[(ROBOT, pp.CUBE)]).id
    assert sim.data.eq_active[e] == 1
    assert np.allclose(m.eq_data[e, 3:6], rel[:3, 3], atol=1e-12)


def test_released_part_stays_where_it_was_released():
    sim = make()
    at_cube(sim)
    sim.close_gripper(ROBOT)
    sim.move_straight_line(ROBOT, UP @ tool_down(pp.grasp_position()))
    assert sim.open_gripper(ROBOT) == pp.CUBE
    release = sim.frames - 1
    held_at = sim.part_pose(pp.CUBE)
    sim.move_joints_relative(ROBOT, np.radians([20, 0, 0, 0, 0, 0]))
    assert sim.held(ROBOT) is None
    c = sim.model.body(pp.CUBE).id
    for _, d in replay(sim, release):
        assert np.array_equal(body_pose(sim.model, d, c), held_at)
    assert sim.open_gripper(ROBOT) is None  # nothing held: fingers open, no release event
    assert sim.events[-1].kind == "open"


def test_failed_grasps_name_the_test_and_change_nothing():
    sim = make()
    before = snapshot(sim)
    with pytest.raises(GraspError, match="'cube' fails the distance test"):
        sim.close_gripper(ROBOT)
    assert unchanged(before, snapshot(sim))
    at_cube(sim, tool_down(pp.grasp_position()) @ rot_y(math.radians(25)))
    before = snapshot(sim)
    with pytest.raises(GraspError, match="fails the angle test: tool z axis is 25 deg"):
        sim.close_gripper(ROBOT)
    sim.close_gripper(ROBOT, max_angle=math.radians(30))  # the same pose passes a looser test
    with pytest.raises(GraspError, match="already holds"):
        sim.close_gripper(ROBOT, max_angle=math.radians(30))
    with pytest.raises(ProgramError, match="max_distance"):
        sim.close_gripper(ROBOT, max_distance=-1)


def test_width_test_on_a_narrow_gripper():
    cell = pp.build()
    cell.remove(ROBOT)
    cell.add_robot(ROBOT, "puma260", gripper={"max_opening": 0.03}, base=translation(0, 0, 0.4))
    sim = Simulator(cell, dt=0.005)
    at_cube(sim)
    with pytest.raises(
        GraspError, match="width across the grasp is 40 mm, wider than the gripper's 30 mm"
    ):
        sim.close_gripper(ROBOT)


def test_gripperless_robot_is_refused():
    cell = Workcell("bare")
    cell.add_robot("r", "puma260")
    sim = Simulator(cell)
    with pytest.raises(ProgramError, match="no gripper"):
        sim.close_gripper("r")


def test_handoff_and_the_double_hold_rule():
    sim = make("ho")
    ho.program(sim)
    kinds = [(r.robot, r.kind) for r in sim.grasps]
    assert kinds == [
        (ho.GIVER, "grasp"),
        (ho.RECEIVER, "grasp"),
        (ho.GIVER, "release"),
        (ho.RECEIVER, "release"),
    ]
    # the sphere ends where puma_2 set it down: on table 2, centre one radius above the top
    assert np.abs(sim.part_pose(ho.SPHERE)[:3, 3] - ho.PLACE).max() < 1e-9
    assert sim.summary()["collisions"] == 0
    # while both hold it, neither may move
    sim2 = make("ho")
    cmds = []
    orig = ho.program

    class StopError(Exception):
        pass

    def spy(name):
        real = getattr(sim2, name)

        def call(*a, **k):
            out = real(*a, **k)
            cmds.append(name)
            if name == "close_gripper" and a[0] == ho.RECEIVER:
                raise StopError
            return out

        return call

    sim2.close_gripper = spy("close_gripper")
    with pytest.raises(StopError):
        orig(sim2)
    assert sim2.held(ho.GIVER) == sim2.held(ho.RECEIVER) == ho.SPHERE
    before = snapshot(sim2)
    for robot in (ho.GIVER, ho.RECEIVER):
        with pytest.raises(ProgramError, match="also held by"):
            sim2.move_joints_relative(robot, np.radians([5, 0, 0, 0, 0, 0]))
    assert unchanged(before, snapshot(sim2))


def crash_cell() -> Workcell:
    cell = Workcell("crash")
    solids.box(cell.model, "post", size=(0.1, 0.1, 0.6))
    solids.cube(cell.model, "blk", size=0.05)
    cell.add_static("post", "post", translation(0.25, -0.05, 0.0))
    cell.add_movable("block", "blk", translation(-0.3, 0.0, 0.1), density=1000.0)
    cell.add_robot("r", "puma260", gripper=True)
    return cell


def test_collisions_become_events_and_can_stop_the_program():
    cell = crash_cell()
    cc = compile_cell(cell)
    sim = Simulator(cell, compiled=cc, dt=0.005)
    assert sim.clearance("block", "ground") == pytest.approx(0.1, abs=1e-6)
    assert sim.clearance("block", "post") == pytest.approx(0.55 - 0.05, abs=1e-6)
    assert sim.clearance("r", "post") > 0
    with pytest.raises(ProgramError, match="known:"):
        sim.clearance("r", "nothing")
    sweep = np.radians([60, 0, 0, 0, 0, 0])
    sim.move_joints_relative("r", sweep)  # the forearm and gripper sweep through the post
    hits = [e for e in sim.events if e.kind == "collision"]
    assert hits
    assert all(e.robot == "r" for e in hits)
    assert any("post" in e.detail for e in hits)
    depth = float(hits[0].detail.split("depth ")[1].split(" mm")[0])
    assert depth > 0.1  # deeper than the contact tolerance (mm)
    assert sim.summary()["collisions"] == len(hits)
    stopper = Simulator(cell, compiled=cc, dt=0.005, stop_on_collision=True)
    before = snapshot(stopper)
    with pytest.raises(CollisionError, match=r"collision at t = .*post"):
        stopper.move_joints_relative("r", sweep)
    assert unchanged(before, snapshot(stopper))
    quiet = Simulator(cell, compiled=cc, dt=0.005, check_collisions=False)
    quiet.move_joints_relative("r", sweep)
    assert quiet.summary()["collisions"] == 0


def test_a_held_part_does_not_collide_with_its_gripper_but_with_the_rest():
    sim = make()
    at_cube(sim)
    sim.close_gripper(ROBOT)
    # pushing the held cube 30 mm into the table is a collision (cube with table)
    sim.move_straight_line(ROBOT, translation(0, 0, -0.03) @ tool_down(pp.grasp_position()))
    hits = [e.detail for e in sim.events if e.kind == "collision"]
    assert any("cube with table" in h or "table with cube" in h for h in hits)
    assert not any("gripper" in h and "cube" in h for h in hits)


def _overlap(sim: Simulator, frame: int, a: str, b: str) -> float:
    """The deepest overlap (m, > 0) between things ``a`` and ``b`` (a part: its geoms
    ``a.*``; a link: the geoms of body ``a``) in timeline ``frame``, from MuJoCo's contacts
    on a fresh MjData."""
    m, d = sim.model, mujoco.MjData(sim.model)
    d.qpos[:] = sim.timeline.frame(frame)[2]
    mujoco.mj_kinematics(m, d)
    mujoco.mj_collision(m, d)

    def of(geom: int, thing: str) -> bool:
        return (
            m.geom(geom).name.startswith(thing + ".") or m.body(m.geom_bodyid[geom]).name == thing
        )

    depths = [
        -c.dist
        for c in d.contact[: d.ncon]
        if (of(c.geom1, a) and of(c.geom2, b)) or (of(c.geom1, b) and of(c.geom2, a))
    ]
    return max(depths, default=0.0)


def test_a_collision_event_carries_the_colliding_frame():
    """render_frame(sim, event.frame) must show the collision: the pair overlaps in that
    frame, and did not in the frame before; the frame's time is the event's."""
    cell = crash_cell()
    sim = Simulator(cell, dt=0.005)
    sim.move_joints_relative("r", np.radians([60, 0, 0, 0, 0, 0]))
    hits = [e for e in sim.events if e.kind == "collision" and "post" in e.detail]
    assert hits
    tol = 1e-4  # the contact tolerance (m)
    for e in hits:
        a, b = e.detail.split(":")[0].split(" with ")
        assert 0 < e.frame < sim.frames
        assert sim.timeline.frame(e.frame)[0] == pytest.approx(e.t, abs=1e-12)
        assert _overlap(sim, e.frame, a, b) > tol, e
        assert _overlap(sim, e.frame - 1, a, b) <= tol, e
    move = next(e for e in sim.events if e.kind == "move")
    assert hits[0].frame < move.frame  # during the move, not at its start or end
