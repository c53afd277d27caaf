"""MJCF import, checked against MuJoCo's own compile of the same files (written by the
tests: an arm with mesh and primitive geoms, default classes, degrees, a joint ref,
keyframes, a site and a parallel gripper), and every error path. A MuJoCo Menagerie
checkout is tried too when ``WORKCELL_MENAGERIE`` names one (nothing of it is kept)."""

from __future__ import annotations

import os
from pathlib import Path

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from robot_files import arm_mjcf, random_q, write, write_meshes

from workcell import Workcell, limits, solids, spatial
from workcell.cell import compile_cell
from workcell.errors import LimitError, ModelError
from workcell.robots import from_mjcf
from workcell.robots.urdf import CONTINUOUS_LIMIT


@pytest.fixture(scope="module")
def arm_file(tmp_path_factory):
    d = tmp_path_factory.mktemp("mjcf")
    write_meshes(d)
    return write(d, "arm.xml", arm_mjcf())


@pytest.fixture(scope="module")
def arm(arm_file):
    return from_mjcf(arm_file, tool_site="flange")


def mujoco_pose(path: Path, robot, q: np.ndarray, base: str, *, site=None, body=None):
    """The site's (or body's) pose in the base body's frame, by MuJoCo at qpos q."""
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    for j, v in zip(robot.joints, q, strict=True):
        d.qpos[m.joint(j.name).qposadr[0]] = v
    mujoco.mj_kinematics(m, d)

    def pose(pos, mat):
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = mat.reshape(3, 3), pos
        return T

    b = m.body(base).id
    B = pose(d.xpos[b], d.xmat[b])
    if site is not None:
        s = m.site(site).id
        E = pose(d.site_xpos[s], d.site_xmat[s])
    else:
        e = m.body(body).id
        E = pose(d.xpos[e], d.xmat[e])
    return np.linalg.inv(B) @ E


def test_the_chain_limits_poses_and_defaults(arm):
    assert [j.name for j in arm.joints] == ["j1", "j2", "j3", "j4", "j5"]
    assert [j.kind for j in arm.joints] == ["revolute"] * 2 + ["prismatic"] + ["revolute"] * 2
    np.testing.assert_allclose(arm.joints[0].limits, np.radians([-170, 170]))  # class default
    np.testing.assert_allclose(arm.joints[4].limits, np.radians([-90, 120]))  # degrees
    assert arm.joints[3].limits == (-CONTINUOUS_LIMIT, CONTINUOUS_LIMIT)  # unlimited hinge
    assert arm.joints[2].limits == (0.0, 0.15)
    np.testing.assert_allclose(arm.max_speeds, [1, 1, 0.25, 1, 1])  # MJCF gives none
    np.testing.assert_allclose(arm.max_jerks, arm.max_speeds / 0.25 / 0.05)
    np.testing.assert_allclose(arm.pose("home"), [0.1, 0.2, 0.05, 0.3, 0.4])  # keyframes
    np.testing.assert_allclose(arm.pose("key1"), [0, 0.5, 0.02, 0, 0])
    assert arm.name == "mjcf_arm"
    assert "chain base -> l5" in arm.source


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(0.0, 1.0), min_size=5, max_size=5))
def test_fk_equals_mujoco_at_the_site(arm_file, arm, u):
    q = arm.lower + np.array(u) * (arm.upper - arm.lower)
    T = mujoco_pose(arm_file, arm, q, "base", site="flange")
    np.testing.assert_allclose(arm.fk(q), T, atol=1e-9)


@pytest.mark.filterwarnings("ignore:.*are left out")
def test_tip_body_and_base_body(arm_file):
    sub = from_mjcf(arm_file, base_body="l1", tip_body="l4")
    assert [j.name for j in sub.joints] == ["j2", "j3", "j4"]
    full = from_mjcf(arm_file, tip_body="l5", gripper=False)
    for q in random_q(full, 20, seed=5):
        np.testing.assert_allclose(
            full.fk(q), mujoco_pose(arm_file, full, q, "base", body="l5"), atol=1e-9
        )
        T = mujoco_pose(arm_file, full, q, "l1", body="l4")
        np.testing.assert_allclose(sub.fk(q[1:4]), T, atol=1e-9)


def test_geoms_become_link_geometry(arm):
    by_link = {k: [g for g in arm.geometry if g.link == k] for k in range(arm.dof + 1)}
    base = by_link[0]  # the floor plane of the world is not part of the robot
    assert len(base) == 1
    assert base[0].colour == pytest.approx((0.9, 0.4, 0.1, 1.0))  # its material
    assert base[0].mesh.extents == pytest.approx([0.2, 0.2, 0.1], rel=1e-3)
    # link 1: a visual capsule that does not collide, which hosts the hidden collision one
    (l1,) = by_link[1]
    assert l1.colour == (0.0, 0.0, 1.0, 1.0)
    assert l1.collides
    assert len(l1.collision) == 1
    assert l1.collision[0].extents == pytest.approx([0.1, 0.1, 0.4], rel=1e-3)
    # link 2: the scaled mesh (visual only) and the bracket's sphere (fixed body, collides)
    mesh, sphere = by_link[2]
    placed = mesh.mesh.copy().apply_transform(mesh.transform)  # MuJoCo turns meshes to their
    assert placed.extents == pytest.approx([0.3, 0.06, 0.1], rel=1e-6)  # axes; scale 1 1 2
    assert not mesh.collides
    assert sphere.collides


def test_the_parallel_gripper_of_the_file_is_kept(arm_file, arm):
    g = arm.gripper
    assert g is not None
    assert g.finger_travel == pytest.approx(0.03)
    assert g.max_opening == pytest.approx(0.06)
    np.testing.assert_allclose(arm.tool, g.mount @ g.tcp, atol=1e-15)  # the site stays the tool
    default = from_mjcf(arm_file)  # no site, no tip: the gripper's TCP is the tool
    tips = [p.vertices(g.model)[:, 2].max() for p in default.gripper.geometry if p.role != "palm"]
    np.testing.assert_allclose(default.gripper.tcp[:3, 3], [0, 0, max(tips) - 0.04 / 4], atol=1e-12)
    # the hand is turned 30 deg about z: the gripper frame is the palm's
    np.testing.assert_allclose(
        default.gripper.mount[:3, :3], spatial.rot_z(np.radians(30))[:3, :3], atol=1e-12
    )
    assert from_mjcf(arm_file, gripper=False).gripper is None


def test_an_imported_arm_runs_a_pick_in_a_cell(arm):
    from workcell.sim import Simulator

    cell = Workcell("mjcf_cell")
    solids.box(cell.model, "cube", size=(0.02, 0.02, 0.02))
    q = arm.pose("home")
    centre = arm.fk(q)[:3, 3]
    cell.add_movable("cube", "cube", spatial.translation(*(centre - 0.01)), density=1000.0)
    cell.add_robot("m", arm, q=q)
    cc = compile_cell(cell)
    assert cc.finger_joints["m"] == ("m.gripper.left_slide", "m.gripper.right_slide")
    sim = Simulator(cell, mode="path", dt=0.01)
    assert sim.close_gripper("m", max_distance=0.005, max_angle=np.radians(90)) == "cube"
    sim.move_joints_absolute("m", q + 0.1)
    centroid = sim.part_pose("cube") @ [0.01, 0.01, 0.01, 1.0]
    np.testing.assert_allclose(centroid[:3], sim.tool_pose("m")[:3, 3], atol=1e-9)


def test_include_files_and_geometry_false(tmp_path):
    write_meshes(tmp_path)
    write(
        tmp_path,
        "more.xml",
        '<mujoco><worldbody><body name="x" pos="1 0 0">'
        '<joint name="jx"/><geom size="0.1"/></body></worldbody></mujoco>',
    )
    f = write(
        tmp_path, "arm.xml", arm_mjcf().replace("</mujoco>", '<include file="more.xml"/></mujoco>')
    )
    r = from_mjcf(f, base_body="base", geometry=False)
    assert r.dof == 5
    assert not r.geometry


# ---------------------------------------------------------------------- errors
def _bad(tmp_path, text: str) -> Path:
    write_meshes(tmp_path)
    return write(tmp_path, "bad.xml", text)


@pytest.mark.parametrize(
    ("edit", "pattern"),
    [
        (
            lambda s: s.replace(
                '<joint name="j2" ref="30" pos="0.01 0 0"/>',
                '<joint name="j2" type="ball" range="0 60"/>',
            ),
            "body 'l2'.*ball joint",
        ),
        (
            lambda s: s.replace(
                '<joint name="j1"/>', '<joint name="j1"/><joint name="j1b" axis="1 0 0"/>'
            ),
            "body 'l1'.*2 joints",
        ),
        (
            lambda s: s.replace('range="0 0.15" ref="0.02"', 'limited="false"'),
            "slide joint 'j3' has no range",
        ),
        (lambda s: s.replace("</mujoco>", "<mujoco>"), "not well-formed XML: line 60"),
        (
            lambda s: s.replace("<mujoco ", "<mujoco x='1' ").replace("<compiler", "<compilr"),
            "MuJoCo cannot read it",
        ),
        (
            lambda s: s.replace('file="meshes/arm.stl"', 'file="meshes/none.stl"'),
            "<mesh file='meshes/none.stl'>: cannot read mesh file .*none.stl': no such file",
        ),
        (
            lambda s: s.replace("<mujoco model", '<!DOCTYPE m [<!ENTITY a "b">]><mujoco model'),
            "entity declarations",
        ),
        (
            lambda s: s.replace("<worldbody>", "<worldbody><body name='base'/>"),
            "repeated name 'base'",
        ),
    ],
)
def test_bad_files(tmp_path, edit, pattern):
    with pytest.raises(ModelError, match=pattern):
        from_mjcf(_bad(tmp_path, edit(arm_mjcf())), tool_site="flange")


def test_bad_arguments(arm_file, tmp_path):
    with pytest.raises(ModelError, match="tool_site 'tcp' is not a site; sites: flange"):
        from_mjcf(arm_file, tool_site="tcp")
    with pytest.raises(ModelError, match="is on body 'l5', not on tip_body 'l4'"):
        from_mjcf(arm_file, tool_site="flange", tip_body="l4")
    with pytest.raises(ModelError, match="base_body 'nope' is not a body"):
        from_mjcf(arm_file, base_body="nope")
    with pytest.raises(ModelError, match="'base' is not below 'l3'"):
        from_mjcf(arm_file, base_body="l3", tip_body="base")
    with pytest.raises(ModelError, match="no body has a joint"):
        from_mjcf(
            write(tmp_path, "s.xml", "<mujoco><worldbody><geom size='1'/></worldbody></mujoco>")
        )
    with pytest.raises(ModelError, match="cannot read MJCF file"):
        from_mjcf(tmp_path / "none.xml")
    with limits.using(max_facets=5), pytest.raises(LimitError, match="max_facets"):
        from_mjcf(arm_file)


def test_root_confines_includes_and_meshes(tmp_path):
    inside = tmp_path / "root"
    write_meshes(tmp_path)  # the meshes lie outside the root
    f = write(inside, "arm.xml", arm_mjcf(mesh="../meshes/arm.stl"))
    assert from_mjcf(f).dof == 5  # fine without a root
    with pytest.raises(ModelError, match="outside the root folder"):
        from_mjcf(f, root=inside)
    g = write(inside, "inc.xml", arm_mjcf(mesh="/etc/passwd"))
    with pytest.raises(ModelError, match="outside the root folder"):
        from_mjcf(g, root=inside)
    h = write(inside, "h.xml", '<mujoco><include file="../secret.xml"/></mujoco>')
    with pytest.raises(ModelError, match="outside the root folder"):
        from_mjcf(h, root=inside)
    (inside / "meshes").mkdir()
    os.link(tmp_path / "meshes" / "arm.stl", inside / "meshes" / "arm.stl")  # a hard link
    k = write(inside, "k.xml", arm_mjcf())
    with pytest.raises(ModelError, match="2 hard links"):
        from_mjcf(k, root=inside)


# ---------------------------------------------------------------------- MuJoCo Menagerie
MENAGERIE = os.environ.get("WORKCELL_MENAGERIE")


@pytest.mark.skipif(not MENAGERIE, reason="set WORKCELL_MENAGERIE to a Menagerie checkout")
@pytest.mark.parametrize(
    ("file", "kw", "family", "tool"),
    [
        (
            "universal_robots_ur5e/ur5e.xml",
            {"tool_site": "attachment_site"},
            "ur",
            ("site", "attachment_site"),
        ),
        ("franka_emika_panda/panda.xml", {"tip_body": "hand"}, None, ("body", "hand")),
    ],
)
def test_menagerie_arms_load_as_shipped(file, kw, family, tool):
    path = Path(MENAGERIE) / file
    robot = from_mjcf(path, **kw)
    assert robot.ik_family == family
    base = robot.source.split("chain ")[1].split(" ->")[0]
    for q in random_q(robot, 20, seed=6):
        T = mujoco_pose(path, robot, q, base, **{tool[0]: tool[1]})
        np.testing.assert_allclose(robot.fk(q), T, atol=1e-9)
    assert "home" in robot.poses
    cell = Workcell("menagerie")
    cell.add_robot("r", robot, gripper=robot.gripper is None)
    compile_cell(cell)
