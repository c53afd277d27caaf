"""Physics mode: the thesis's examples 2 and 3 replayed with mj_step.

Checked against numbers from outside the physics code: the kinematic run's result (the
plan and where it left the parts), analytic resting heights (the stage's top; the
sphere's facet distances computed here from its mesh), forward kinematics of the
robots (``RobotPlacement.tool_pose``) and MuJoCo kinematics on a scratch MjData.
Default cases sample the plan at 20 ms (the physics steps at 2 ms either way); the
1 ms runs are marked slow.
"""

from __future__ import annotations

import copy
import functools
import json
import math

import mujoco
import numpy as np
import pytest

from workcell.errors import ProgramError
from workcell.examples import thesis_handoff as ho
from workcell.examples import thesis_pick_place as pp
from workcell.sim.physics import PhysicsResult, run_physics
from workcell.sim.physics_support import GripContacts, Plan, plan_of
from workcell.spatial import invert, pose_from_pos_quat

DT = 0.02  # s: the kinematic sampling of the default cases
PLACE_TOLERANCE = 5e-3  # m: the bound on a placed part vs the kinematic result
JOINT_MAX = 0.01  # rad: stated bound on any arm joint's tracking error
JOINT_RMS = 0.002  # rad
TOOL_MAX = 3e-3  # m: stated bound on the tool point's tracking error
CARRY = 1e-3  # m: a carried part stays this close to its pose in the gripper
CARRY_ANGLE = math.radians(1.0)
REST_HEIGHT = 5e-5  # m: a resting part sinks at most this far into its support


@functools.cache
def kinematic(example: str, dt: float = DT):
    return {"pp": pp, "ho": ho}[example].run("path", dt)


@functools.cache
def physics(example: str, dt: float = DT, **options: object) -> PhysicsResult:
    return run_physics(kinematic(example, dt), settle=0.5, **options)


def free_pose(result_or_sim, part: str, qpos: np.ndarray) -> np.ndarray:
    """World pose (4x4) of a part from a qpos row (its free joint)."""
    m = result_or_sim.model
    adr = m.jnt_qposadr[m.joint(f"{part}.free").id]
    return pose_from_pos_quat(qpos[adr : adr + 3], qpos[adr + 3 : adr + 7])


def final_pose(result: PhysicsResult, part: str) -> np.ndarray:
    return free_pose(result, part, result.timeline.frame(-1)[2])


def kinematic_pose(example: str, part: str) -> np.ndarray:
    sim = kinematic(example)
    return free_pose(sim, part, sim.timeline.frame(-1)[2])


def lowest_point(result: PhysicsResult, part: str, block: str) -> float:
    """World z (m) of the lowest vertex of a part's mesh at the end."""
    V = result.cell.model.world_mesh(("block", block)).vertices
    P = final_pose(result, part)
    return float((V @ P[:3, :3].T + P[:3, 3])[:, 2].min())


def at_rest(result: PhysicsResult, part: str) -> float:
    """Speed (m/s) of the part between the last two frames."""
    (t0, _, q0), (t1, _, q1) = result.timeline.frame(-2), result.timeline.frame(-1)
    p0, p1 = free_pose(result, part, q0)[:3, 3], free_pose(result, part, q1)[:3, 3]
    return float(np.linalg.norm(p1 - p0) / (t1 - t0))


# ---------------------------------------------------------------------- example 2
def test_cube_ends_resting_on_stage_1_near_the_kinematic_result():
    r = physics("pp")
    P, K = final_pose(r, pp.CUBE), kinematic_pose("pp", pp.CUBE)
    assert np.linalg.norm(P[:3, 3] - K[:3, 3]) < PLACE_TOLERANCE
    # lying flat on the stage: its z axis vertical, its bottom face at the stage's top
    assert P[2, 2] > math.cos(math.radians(0.5))
    assert P[2, 3] == pytest.approx(pp.STAGE_1_TOP, abs=REST_HEIGHT)
    assert lowest_point(r, pp.CUBE, "cube_block") == pytest.approx(pp.STAGE_1_TOP, abs=REST_HEIGHT)
    centre = P[:3, :3] @ np.full(3, pp.CUBE_SIZE / 2) + P[:3, 3]
    assert np.abs(centre[:2] - pp.STAGE_1_CENTRE).max() < PLACE_TOLERANCE
    assert r.part_positions()[pp.CUBE] == pytest.approx(centre.tolist(), abs=1e-12)  # centroids
    assert at_rest(r, pp.CUBE) < 1e-3
    s = r.parts[pp.CUBE]
    assert s.resting
    assert s.distance == pytest.approx(np.linalg.norm(P[:3, 3] - K[:3, 3]), abs=1e-12)


def test_tracking_errors_within_bounds_and_consistent_with_the_frames():
    for example in ("pp", "ho"):
        r, sim = physics(example), kinematic(example)
        t_plan, Q_plan = sim.timeline.sim_times(), sim.timeline.qpos()
        t = r.timeline.sim_times()
        inside = t <= r.program_time
        Q = r.timeline.qpos()[inside]
        for robot, placement in r.cell.robots.items():
            tr = r.tracking[robot]
            assert tr.joint_max < JOINT_MAX, (example, robot, tr)
            assert tr.joint_rms < JOINT_RMS, (example, robot, tr)
            assert tr.tool_max < TOOL_MAX, (example, robot, tr)
            adr = [r.model.jnt_qposadr[r.model.joint(j).id] for j in r.compiled.joint_names[robot]]
            plan = np.column_stack([np.interp(t[inside], t_plan, Q_plan[:, a]) for a in adr])
            err = np.abs(Q[:, adr] - plan)
            # the frames are a subset of the physics steps the statistics cover
            assert err.max() <= tr.joint_max + 1e-12
            assert err.max() > 0.3 * tr.joint_max
            tool = np.array([placement.tool_pose(q)[:3, 3] for q in Q[::5, adr]])
            want = np.array([placement.tool_pose(q)[:3, 3] for q in plan[::5]])
            assert np.linalg.norm(tool - want, axis=1).max() <= tr.tool_max + 1e-12


def test_gravity_compensation_matters():
    on, off = physics("pp"), physics("pp", gravcomp=False)
    assert off.tracking[pp.ROBOT].tool_rms > 3 * on.tracking[pp.ROBOT].tool_rms
    assert off.tracking[pp.ROBOT].joint_rms > 3 * on.tracking[pp.ROBOT].joint_rms


def test_results_independent_of_the_kinematic_dt():
    coarse, fine = physics("pp"), physics("pp", 0.005)
    assert fine.frames > 3 * coarse.frames
    a, b = final_pose(coarse, pp.CUBE), final_pose(fine, pp.CUBE)
    assert np.linalg.norm(a[:3, 3] - b[:3, 3]) < 5e-5
    ta, tb = coarse.tracking[pp.ROBOT], fine.tracking[pp.ROBOT]
    assert tb.tool_max == pytest.approx(ta.tool_max, rel=0.05)
    assert tb.joint_rms == pytest.approx(ta.joint_rms, rel=0.05)


def test_a_robot_hitting_the_table_is_a_collision():
    # joint by joint (each joint in its own time), the return home dips a finger into the
    # table; physics reports it when the kinematic run does, though the stiff contact
    # barely lets the finger in
    sim = pp.run("joint-by-joint", DT, joint_by_joint_clock="sequential")
    want = [e for e in sim.events if e.kind == "collision"]
    assert [e.detail.split(":")[0] for e in want] == ["puma.gripper.right with table"]
    r = run_physics(sim, settle=0.1)
    got = [e for e in r.events if e.kind == "collision" and "with table" in e.detail]
    assert len(got) == 1
    assert got[0].robot == pp.ROBOT
    assert got[0].detail.startswith("puma.gripper.right with table")
    assert got[0].t == pytest.approx(want[0].t, abs=DT + r.timestep)
    assert r.tracking[pp.ROBOT].joint_max > 0.05  # the table holds the arm back


# ---------------------------------------------------------------------- example 3
def sphere_facet_distances() -> np.ndarray:
    """Distances (m) from the sphere's centre to the planes of its mesh's faces."""
    mesh = ho.build().model.world_mesh(("block", "sphere_block"))
    return np.abs(np.einsum("ij,ij->i", mesh.face_normals, mesh.triangles[:, 0]))


def test_sphere_ends_resting_on_a_facet_on_table_2():
    r = physics("ho")
    P, K = final_pose(r, ho.SPHERE), kinematic_pose("ho", ho.SPHERE)
    assert np.linalg.norm(P[:3, 3] - K[:3, 3]) < PLACE_TOLERANCE
    assert np.abs(P[:2, 3] - np.array(ho.BASE_2)).max() < 0.3  # on table 2 (0.6 m square)
    # a faceted sphere lies on a face: the centre is one facet distance above the table
    # (the kinematic run puts it a radius above, on a vertex)
    height = P[2, 3] - ho.TABLE_TOP
    assert np.abs(sphere_facet_distances() - height).min() < REST_HEIGHT
    assert height < ho.RADIUS - 1e-4
    assert lowest_point(r, ho.SPHERE, "sphere_block") == pytest.approx(
        ho.TABLE_TOP, abs=REST_HEIGHT
    )
    assert at_rest(r, ho.SPHERE) < 1e-3
    assert r.parts[ho.SPHERE].resting


def carried_relative_poses(r: PhysicsResult, robot: str, t0: float, t1: float) -> np.ndarray:
    """The part's pose in the gripper's frame (N, 4, 4) at the frames in [t0, t1]."""
    m, d = r.model, mujoco.MjData(r.model)
    g = m.body(r.compiled.gripper_bodies[robot]).id
    t = r.timeline.sim_times()
    rows = r.timeline.qpos()[(t >= t0) & (t <= t1)]
    out = []
    for q in rows:
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        G = pose_from_pos_quat(d.xpos[g], d.xquat[g])
        out.append(invert(G) @ free_pose(r, ho.SPHERE, q))
    return np.array(out)


def pose_deviation(A: np.ndarray, B: np.ndarray) -> tuple[float, float]:
    """Largest position (m) and rotation (rad) differences between poses A (N) and B."""
    dp = np.linalg.norm(A[:, :3, 3] - B[:3, 3], axis=1).max()
    c = (np.einsum("nij,ij->n", A[:, :3, :3], B[:3, :3]) - 1) / 2
    return float(dp), float(np.arccos(np.clip(c, -1, 1)).max())


def test_carried_part_follows_its_gripper():
    r, sim = physics("ho"), kinematic("ho")
    grasps = [g for g in sim.grasps if g.kind == "grasp"]
    releases = {g.robot: g.t for g in sim.grasps if g.kind == "release"}
    assert [g.robot for g in grasps] == [ho.GIVER, ho.RECEIVER]
    for g in grasps:
        rel = carried_relative_poses(r, g.robot, g.t + r.timestep, releases[g.robot])
        assert len(rel) > 100
        dp, da = pose_deviation(rel, rel[0])
        assert dp < CARRY, (g.robot, dp)
        assert da < CARRY_ANGLE, (g.robot, da)
        # the grip is where the fingers met the part: near the plan's weld pose
        dp, _ = pose_deviation(rel[:1], pose_from_pos_quat(g.pos, g.quat))
        assert dp < 3e-3
    assert r.parts[ho.SPHERE].carry_error < CARRY


def test_planned_weld_pose_pulls_the_part_to_the_plans_grip():
    r, sim = physics("ho", weld_pose="planned"), kinematic("ho")
    g = next(g for g in sim.grasps if g.kind == "grasp")
    release = next(x.t for x in sim.grasps if x.kind == "release" and x.robot == g.robot)
    rel = carried_relative_poses(r, g.robot, g.t + 0.1, release)
    dp, da = pose_deviation(rel, pose_from_pos_quat(g.pos, g.quat))
    assert dp < CARRY
    assert da < CARRY_ANGLE
    P, K = final_pose(r, ho.SPHERE), kinematic_pose("ho", ho.SPHERE)
    assert np.linalg.norm(P[:3, 3] - K[:3, 3]) < PLACE_TOLERANCE


# ---------------------------------------------------------------------- building blocks
def test_plan_is_linear_between_frames_and_jumps_at_shared_times():
    t = np.array([0.0, 1.0, 2.0, 2.0, 3.0, 4.0, 5.0])
    P = np.array([[0.0], [1.0], [2.0], [5.0], [5.0], [4.0], [3.0]])
    ref, vel = Plan(t, P).at(np.array([-1.0, 0.5, 1.999, 2.0, 2.5, 4.5, 6.0]))
    assert ref[:, 0] == pytest.approx([0.0, 0.5, 1.999, 5.0, 5.0, 3.5, 3.0])
    assert vel[:, 0] == pytest.approx([0.0, 1.0, 1.0, 0.0, 0.0, -1.0, 0.0])
    # plan_of keeps only the bends of a simulator's plan, and it interpolates the same
    sim = kinematic("pp")
    cols = np.array([sim.model.jnt_qposadr[sim.model.joint("puma.j2").id]])
    full, small = Plan(sim.timeline.sim_times(), sim.timeline.qpos()[:, cols]), plan_of(sim, cols)
    assert len(small.t) < len(full.t) / 10
    ts = np.linspace(0.0, full.t[-1], 20_001)
    assert np.abs(small.at(ts)[0] - full.at(ts)[0]).max() < 1e-12


def test_grip_contacts_switch_the_held_pair_only():
    sim = kinematic("pp")
    m = copy.deepcopy(sim.compiled.model)
    grip = GripContacts(m, sim.compiled)
    d = mujoco.MjData(m)
    d.qpos[:] = sim.timeline.frame(0)[2]
    mujoco.mj_kinematics(m, d)
    finger = m.geom("puma.gripper.finger_l.col0").id
    adr = m.jnt_qposadr[m.joint("cube.free").id]
    d.qpos[adr : adr + 3] = d.geom_xpos[finger] - pp.CUBE_SIZE / 2  # the cube on the finger
    mujoco.mj_forward(m, d)

    def thing(g: int) -> str:  # a body's name; a static part's for world geoms
        b = m.geom_bodyid[g]
        return m.body(b).name if b else m.geom(g).name.split(".")[0]

    def pairs() -> set[tuple[str, ...]]:
        """The pairs of things in contact that involve the cube."""
        found = {tuple(sorted((thing(c.geom1), thing(c.geom2)))) for c in d.contact[: d.ncon]}
        return {p for p in found if "cube" in p}

    touching = pairs()
    assert ("cube", "puma.gripper.left") in touching
    grip.hold(pp.ROBOT, pp.CUBE, True)
    mujoco.mj_forward(m, d)
    assert pairs() == set()
    start = sim.timeline.frame(0)[2][adr : adr + 3]
    d.qpos[adr : adr + 3] = start - [0.0, 0.0, 1e-3]  # held, 1 mm into the table
    mujoco.mj_forward(m, d)
    assert pairs() == {("cube", "table")}
    grip.hold(pp.ROBOT, pp.CUBE, False)
    d.qpos[adr : adr + 3] = d.geom_xpos[finger] - pp.CUBE_SIZE / 2
    mujoco.mj_forward(m, d)
    assert pairs() == touching


# ---------------------------------------------------------------------- result, errors
def test_summary_timeline_and_events():
    r, sim = physics("ho"), kinematic("ho")
    s = json.loads(json.dumps(r.summary()))
    assert {"sim_time_s", "wall_time_s", "frames", "events", "collisions", "objects"} <= set(s)
    assert s["frames"] == r.frames == len(r.timeline)
    assert s["sim_time_s"] == pytest.approx(sim.sim_time + 0.5, abs=r.timestep)
    assert s["collisions"] == 0
    assert s["objects"][ho.SPHERE] == pytest.approx(final_pose(r, ho.SPHERE)[:3, 3].tolist())
    t = r.timeline.sim_times()
    assert t[0] == 0.0
    assert t[-1] == pytest.approx(s["sim_time_s"])
    gaps = np.diff(t)  # frames every DT (on the physics steps), the last one a remainder
    assert np.allclose(gaps[:-1], DT, atol=r.timestep + 1e-9)
    assert 0 < gaps[-1] <= DT + r.timestep
    assert np.array_equal(r.timeline.frame(0)[2], sim.timeline.frame(0)[2])
    kinds = [(e.robot, e.kind) for e in r.events if e.kind in ("grasp", "release")]
    assert kinds == [(g.robot, g.kind) for g in sim.grasps]
    for e in r.events:  # each event's frame is the last frame at or before its time
        assert t[e.frame] <= e.t + 1e-9
        assert e.frame == len(t) - 1 or t[e.frame + 1] > e.t
    assert [e.kind for e in r.events][-1] == "settle"
    phys = s["physics"]
    assert set(phys["tracking"]) == {ho.GIVER, ho.RECEIVER}
    assert phys["parts"][ho.SPHERE]["distance_m"] < PLACE_TOLERANCE
    assert r.real_time_factor > 1


def test_result_records_like_a_simulator(tmp_path):
    from workcell.record import record

    stats = record(physics("pp"), tmp_path / "physics.rrd")
    assert stats.frames == physics("pp").frames
    assert stats.path.stat().st_size > 0


@pytest.mark.parametrize(
    ("options", "word"),
    [
        ({"timestep": 0.0}, "timestep"),
        ({"timestep": 0.1}, "timestep"),
        ({"timestep": "1 ms"}, "timestep"),
        ({"settle": -1.0}, "settle"),
        ({"weld_pose": "nearest"}, "weld_pose"),
        ({"contact_tolerance": 0.0}, "contact_tolerance"),
    ],
)
def test_bad_arguments_raise_program_error(options, word):
    with pytest.raises(ProgramError, match=word):
        run_physics(kinematic("pp"), **options)


def test_not_a_simulator_raises_program_error():
    with pytest.raises(ProgramError, match="Simulator"):
        run_physics(object())  # type: ignore[arg-type]


# ---------------------------------------------------------------------- 1 ms (slow)
@pytest.mark.slow
@pytest.mark.parametrize(("example", "part"), [("pp", pp.CUBE), ("ho", ho.SPHERE)])
def test_one_millisecond_runs(example, part):
    sim = {"pp": pp, "ho": ho}[example].run("path", 0.001)
    r = run_physics(sim, timestep=0.001, settle=1.0)
    P = final_pose(r, part)
    K = free_pose(sim, part, sim.timeline.frame(-1)[2])
    assert np.linalg.norm(P[:3, 3] - K[:3, 3]) < PLACE_TOLERANCE
    assert r.parts[part].resting
    for tr in r.tracking.values():
        assert tr.joint_max < JOINT_MAX
        assert tr.tool_max < TOOL_MAX
    print(f"{example}: {r!r}; wall {r.wall_time:.3g} s")
