"""Robots with link solids and grippers in MuJoCo: kinematics, mass properties, export, loading.

References: ``Robot.fk`` (already checked against the thesis's formulation), trimesh's
volumes and inertias of the modeller's meshes, the modeller's own ``properties``, and
plain MuJoCo / dm_control loading the written files in a fresh process from another
working directory.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import mujoco
import numpy as np
import pytest
import trimesh
from scipy.spatial import Delaunay

from workcell import solids, spatial
from workcell.errors import ModelError
from workcell.meshgeoms import convex_pieces
from workcell.modeller.model import Model
from workcell.robots import Joint, LinkGeometry, Robot, puma260, puma560
from workcell.robots.gripper import attach_gripper, parallel_gripper
from workcell.robots.mjcf import (
    ARM_DENSITY,
    body_name,
    export_robot,
    finger_joint_names,
    gripper_body_name,
    robot_spec,
)

PREFIX = "puma_1."
ROBOTS = {
    "puma560": puma560(),
    "puma260": puma260(),
    "puma560+gripper": attach_gripper(puma560(), parallel_gripper()),
    "puma260+gripper": attach_gripper(puma260(), parallel_gripper(max_opening=0.05)),
}


def site_pose(M, D, name):
    i = mujoco.mj_name2id(M, mujoco.mjtObj.mjOBJ_SITE, name)
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = D.site_xmat[i].reshape(3, 3), D.site_xpos[i]
    return T


def body_id(M, name):
    i = mujoco.mj_name2id(M, mujoco.mjtObj.mjOBJ_BODY, name)
    assert i >= 0, name
    return i


def arm_qpos(M, robot, prefix, q):
    D = mujoco.MjData(M)
    for k, j in enumerate(robot.joints):
        D.joint(f"{prefix}{j.name}").qpos[0] = q[k]
    mujoco.mj_kinematics(M, D)
    return D


def trimesh_of(robot, block):
    m = robot.model.world_mesh(("block", block))
    return trimesh.Trimesh(np.array(m.vertices), np.array(m.faces), process=False)


def solids_of_body(robot, link):
    """LinkGeometry entries that MuJoCo puts in link ``link``'s body (gripper parts aside)."""
    skip = {p.block for p in robot.gripper.geometry} if robot.gripper else set()
    return [g for g in robot.geometry if g.link == link and g.block not in skip]


@pytest.mark.parametrize("name", ROBOTS)
@pytest.mark.parametrize("prefix", ["", PREFIX])
def test_tool_site_follows_fk(name, prefix):
    robot = ROBOTS[name]
    M = robot_spec(robot, prefix=prefix).compile()
    rng = np.random.default_rng(17)
    for _ in range(40):
        q = rng.uniform(robot.lower, robot.upper)
        D = arm_qpos(M, robot, prefix, q)
        np.testing.assert_allclose(site_pose(M, D, f"{prefix}tool"), robot.fk(q), atol=1e-9)


def test_tool_site_follows_fk_with_a_base_transform():
    base = spatial.euler((0.1, -0.2, 0.7), translation=(1.0, -0.5, 0.2))
    robot = ROBOTS["puma260+gripper"].with_(base=base)
    M = robot_spec(robot, prefix=PREFIX).compile()
    q = robot.pose("home")
    D = arm_qpos(M, robot, PREFIX, q)
    np.testing.assert_allclose(site_pose(M, D, f"{PREFIX}tool"), robot.fk(q), atol=1e-9)


@pytest.mark.parametrize("name", ROBOTS)
def test_body_masses_are_density_times_exact_volume(name):
    robot = ROBOTS[name]
    M = robot_spec(robot, prefix=PREFIX).compile()
    for link in range(robot.dof + 1):
        mine = solids_of_body(robot, link)
        vol_trimesh = sum(trimesh_of(robot, g.block).volume for g in mine)
        vol_props = sum(robot.model.properties(("block", g.block)).volume for g in mine)
        mass = M.body_mass[body_id(M, body_name(PREFIX, link))]
        assert mass == pytest.approx(ARM_DENSITY * vol_trimesh, rel=1e-6)
        assert mass == pytest.approx(ARM_DENSITY * vol_props, rel=1e-6)
    if robot.gripper is not None:
        g = gripper_body_name(robot, PREFIX)
        for role, body in (("palm", g), ("left", f"{g}.left"), ("right", f"{g}.right")):
            vol = trimesh_of(robot, robot.gripper.part(role).block).volume
            assert M.body_mass[body_id(M, body)] == pytest.approx(ARM_DENSITY * vol, rel=1e-6)


@pytest.mark.parametrize("name", ["puma560", "puma260"])
def test_single_solid_links_have_the_mesh_centre_of_mass_and_inertia(name):
    """Links 2..6 carry one solid: MuJoCo's inertia equals trimesh's for that mesh at density."""
    robot = ROBOTS[name]
    M = robot_spec(robot).compile()
    q = robot.pose("home")
    D = arm_qpos(M, robot, "", q)
    F = robot.link_frames(q)
    for link in range(2, 7):
        (g,) = solids_of_body(robot, link)
        mesh = trimesh_of(robot, g.block)
        mesh.apply_transform(F[link] @ g.transform)
        mesh.density = ARM_DENSITY
        b = body_id(M, body_name("", link))
        np.testing.assert_allclose(D.xipos[b], mesh.center_mass, atol=1e-7)
        np.testing.assert_allclose(
            np.sort(M.body_inertia[b]), np.sort(mesh.principal_inertia_components), rtol=1e-5
        )


@pytest.mark.parametrize("name", ROBOTS)
def test_no_slash_in_names_and_exclude_pairs_for_links_up_to_two_apart(name):
    robot = ROBOTS[name]
    M = robot_spec(robot, prefix=PREFIX).compile()
    names = [n.decode() for n in M.names.split(b"\x00") if n]
    assert names
    assert not [n for n in names if "/" in n]
    link_of = {body_name(PREFIX, k): k for k in range(robot.dof + 1)}
    if robot.gripper is not None:
        g = gripper_body_name(robot, PREFIX)
        link_of.update({g: robot.dof, f"{g}.left": robot.dof, f"{g}.right": robot.dof})
    ids = {body_id(M, n): k for n, k in link_of.items()}
    want = {frozenset((a, b)) for a in ids for b in ids if a != b and abs(ids[a] - ids[b]) <= 2}
    sig = M.exclude_signature
    got = {frozenset((int(s >> 16), int(s & 0xFFFF))) for s in sig}
    assert got == want
    for k in range(robot.dof):  # adjacent and two-apart links among them
        assert (
            frozenset((body_id(M, body_name(PREFIX, k)), body_id(M, body_name(PREFIX, k + 1))))
            in got
        )


@pytest.mark.parametrize("name", ROBOTS)
def test_visual_geoms_carry_mass_and_collision_geoms_collide(name):
    robot = ROBOTS[name]
    M = robot_spec(robot).compile()
    vis = M.geom_group == 2
    col = M.geom_group == 3
    assert vis.sum() + col.sum() == M.ngeom
    assert vis.sum() == len(robot.geometry)
    assert not M.geom_contype[vis].any()
    assert not M.geom_conaffinity[vis].any()
    assert M.geom_contype[col].all()
    assert M.geom_conaffinity[col].all()
    assert (M.geom_type == mujoco.mjtGeom.mjGEOM_MESH).all()


@pytest.mark.parametrize("name", ROBOTS)
def test_no_self_contacts_in_the_named_poses(name):
    robot = ROBOTS[name]
    M = robot_spec(robot).compile()
    for pose in robot.poses:
        D = arm_qpos(M, robot, "", robot.pose(pose))
        mujoco.mj_collision(M, D)
        assert D.ncon == 0, pose


def test_fingers_slide_from_open_to_closed():
    robot = ROBOTS["puma260+gripper"]
    g = robot.gripper
    M = robot_spec(robot, prefix=PREFIX).compile()
    left, right = finger_joint_names(robot, PREFIX)
    for jn in (left, right):
        j = M.joint(jn)
        assert j.type[0] == mujoco.mjtJoint.mjJNT_SLIDE
        np.testing.assert_allclose(j.range, [0.0, g.finger_travel])
        assert M.qpos0[j.qposadr[0]] == pytest.approx(g.finger_travel)  # starts open
    q = robot.pose("home")
    D = arm_qpos(M, robot, PREFIX, q)
    gname = gripper_body_name(robot, PREFIX)
    frame = robot.link_frames(q)[6] @ g.mount
    np.testing.assert_allclose(D.body(gname).xpos, frame[:3, 3], atol=1e-12)
    # open: the finger bodies are the gripper frame (solids drawn open)
    for side in ("left", "right"):
        np.testing.assert_allclose(D.body(f"{gname}.{side}").xpos, frame[:3, 3], atol=1e-12)
    D.joint(left).qpos[0] = D.joint(right).qpos[0] = 0.0
    mujoco.mj_kinematics(M, D)
    y = frame[:3, 1]
    for side, sign in (("left", -1), ("right", 1)):
        shift = D.body(f"{gname}.{side}").xpos - frame[:3, 3]
        np.testing.assert_allclose(shift, sign * g.finger_travel * y, atol=1e-12)
    # closed jaws meet at the TCP plane: the TCP sits between the inner faces, now touching
    tcp = site_pose(M, D, f"{PREFIX}tool")[:3, 3]
    np.testing.assert_allclose((tcp - frame[:3, 3]) @ y, 0.0, atol=1e-12)


def test_prefix_with_a_slash_is_refused():
    with pytest.raises(ModelError, match="'/'"):
        robot_spec(ROBOTS["puma560"], prefix="puma/1")


# ---------------------------------------------------------------------- non-convex and scaled solids
def two_link_robot():
    """A planar two-link arm with a torus (non-convex), a union, a scaled and a mirrored cube."""
    m = Model()
    solids.torus(m, "ring", major_radius=0.1, minor_radius=0.03, m=24, n=12)
    solids.box(m, "a", size=(0.3, 0.04, 0.04))
    solids.box(m, "b", size=(0.04, 0.2, 0.04))
    solids.union(m, "tee", "a", "b", transforms=[None, spatial.translation(0.26, -0.08, 0)])
    solids.cube(m, "cube", size=0.05)
    geo = (
        LinkGeometry(1, "ring", spatial.translation(-0.3, 0, 0)),
        LinkGeometry(1, "tee", spatial.translation(-0.3, -0.02, -0.02)),
        LinkGeometry(2, "cube", spatial.translation(-0.1, 0, 0) @ spatial.scaling(2.0, 1.0, 0.5)),
        LinkGeometry(2, "cube", spatial.translation(0.1, 0, 0) @ spatial.scaling(-1.0, 1.0, 1.0)),
    )
    return Robot(
        "two", (Joint.from_dh("a", a=0.3), Joint.from_dh("b", a=0.2)), model=m, geometry=geo
    )


def test_convex_pieces_rule():
    robot = two_link_robot()
    pieces, convex = convex_pieces(robot.model, "ring")
    assert not convex  # CoACD's pieces: the hole stays open
    ring = trimesh_of(robot, "ring")
    assert len(pieces) > 4
    assert (
        ring.volume <= sum(p.volume for p in pieces) < 1.1 * ring.volume < ring.convex_hull.volume
    )
    centre = np.zeros((1, 3))  # the torus's centre, in the hole: in no piece
    assert all(Delaunay(p.vertices).find_simplex(centre)[0] < 0 for p in pieces)
    pieces, convex = convex_pieces(robot.model, "tee")
    assert not convex  # the union's two boxes
    assert len(pieces) == 2
    assert sum(p.volume for p in pieces) == pytest.approx(0.3 * 0.04**2 + 0.2 * 0.04**2, rel=1e-12)
    pieces, convex = convex_pieces(robot.model, "cube")
    assert convex
    assert len(pieces) == 1


def test_non_convex_and_scaled_solids_keep_exact_mass():
    robot = two_link_robot()
    M = robot_spec(robot, density=1000.0).compile()
    ring = trimesh_of(robot, "ring").volume
    tee = 0.3 * 0.04**2 + 0.2 * 0.04**2 - 0.04 * 0.04 * 0.04  # boxes overlap in a 4 cm cube
    assert M.body_mass[body_id(M, "link1")] == pytest.approx(1000 * (ring + tee), rel=1e-6)
    # scaled by det 1 and mirrored (det -1, turned inside out unless re-wound): 2 cubes
    assert M.body_mass[body_id(M, "link2")] == pytest.approx(1000 * 2 * 0.05**3, rel=1e-6)
    # the tee collides as its two boxes, the torus as CoACD's pieces, each placed cube as itself
    col_bodies = M.geom_bodyid[M.geom_group == 3].tolist()
    link1, link2 = body_id(M, "link1"), body_id(M, "link2")
    ring_pieces = len(convex_pieces(robot.model, "ring")[0])
    assert (col_bodies.count(link1), col_bodies.count(link2)) == (2 + ring_pieces, 2)
    rng = np.random.default_rng(2)
    for _ in range(10):
        q = rng.uniform(robot.lower, robot.upper)
        D = arm_qpos(M, robot, "", q)
        np.testing.assert_allclose(site_pose(M, D, "tool"), robot.fk(q), atol=1e-12)


# ---------------------------------------------------------------------- export and loading
LOADER = r"""
import json, sys
import numpy as np
import mujoco
from dm_control import mjcf

path, prefix, q = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
out = {}
m = mujoco.MjModel.from_xml_path(path)
d = mujoco.MjData(m)
for name, v in q.items():
    d.joint(name).qpos[0] = v
mujoco.mj_kinematics(m, d)
s = d.site(prefix + "tool")
out["mujoco"] = [s.xpos.tolist(), s.xmat.tolist(), m.body_mass.tolist()]
root = mjcf.from_path(path)
physics = mjcf.Physics.from_mjcf_model(root)
for name, v in q.items():
    physics.named.data.qpos[name] = v
physics.forward()
out["dm_control"] = [physics.named.data.site_xpos[prefix + "tool"].tolist(),
                     physics.named.data.site_xmat[prefix + "tool"].tolist()]
physics.step()
out["stepped"] = bool(np.isfinite(physics.data.qpos).all())
print(json.dumps(out))
"""


@pytest.mark.parametrize("name", ["puma560+gripper", "puma260"])
def test_exported_folder_loads_from_any_directory(tmp_path, name):
    robot = ROBOTS[name]
    out = tmp_path / "cell"
    xml = export_robot(robot, out, prefix=PREFIX)
    assert xml.parent == out
    assert xml.exists()
    files = sorted(p.name for p in (out / "meshes").iterdir())
    assert files
    assert all(f.endswith(".stl") for f in files)
    assert not [p for p in out.rglob("*") if p.name.endswith(".tmp")]
    text = xml.read_text()
    assert 'meshdir="meshes"' in text
    assert str(tmp_path) not in text
    q = robot.pose("home") + 0.1
    qd = {f"{PREFIX}{j.name}": float(v) for j, v in zip(robot.joints, q, strict=True)}
    env = {**os.environ, "MUJOCO_GL": "egl"}
    run = subprocess.run(
        [sys.executable, "-c", LOADER, str(xml), PREFIX, json.dumps(qd)],
        cwd="/",
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    res = json.loads(run.stdout.strip().splitlines()[-1])
    T = robot.fk(q)
    for key in ("mujoco", "dm_control"):
        pos, mat = res[key][:2]
        np.testing.assert_allclose(pos, T[:3, 3], atol=1e-9)
        np.testing.assert_allclose(np.reshape(mat, (3, 3)), T[:3, :3], atol=1e-9)
    M = robot_spec(robot, prefix=PREFIX).compile()
    np.testing.assert_allclose(res["mujoco"][2], M.body_mass, rtol=1e-12)
    assert res["stepped"]


def test_mesh_link_geometry_for_robots_described_by_files():
    """LinkGeometry can carry a mesh (as a URDF/MJCF import gives them) instead of a block:
    its exact mass at the density, its collision pieces, and the tool site on FK."""
    box = trimesh.creation.box(extents=(0.3, 0.05, 0.04))
    halves = (
        trimesh.creation.box(extents=(0.15, 0.05, 0.04)).apply_translation((-0.075, 0, 0)),
        trimesh.creation.box(extents=(0.15, 0.05, 0.04)).apply_translation((0.075, 0, 0)),
    )
    geo = (
        LinkGeometry(1, None, spatial.translation(-0.15, 0, 0), mesh=box, collision=halves),
        LinkGeometry(2, None, spatial.translation(-0.1, 0, 0) @ spatial.scaling(0.5), mesh=box),
    )
    robot = Robot("meshy", (Joint.from_dh("a", a=0.3), Joint.from_dh("b", a=0.2)), geometry=geo)
    M = robot_spec(robot, density=1000.0).compile()
    assert M.body_mass[body_id(M, "link1")] == pytest.approx(1000 * 0.3 * 0.05 * 0.04, rel=1e-6)
    assert M.body_mass[body_id(M, "link2")] == pytest.approx(1000 * 0.3 * 0.05 * 0.04 / 8, rel=1e-6)
    col_bodies = M.geom_bodyid[M.geom_group == 3].tolist()
    assert col_bodies.count(body_id(M, "link1")) == 2  # the two given pieces
    assert col_bodies.count(body_id(M, "link2")) == 1  # the hull
    for q in np.random.default_rng(4).uniform(robot.lower, robot.upper, (5, 2)):
        D = arm_qpos(M, robot, "", q)
        np.testing.assert_allclose(site_pose(M, D, "tool"), robot.fk(q), atol=1e-12)
    with pytest.raises(Exception, match="exactly one"):
        LinkGeometry(1, "block", np.eye(4), mesh=box)
