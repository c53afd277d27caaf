"""URDF import, checked against two independent readers of the same files: yourdfpy (a
URDF library) and MuJoCo's own URDF compiler, on files the tests write and on the real
ROS-Industrial files of the test-only rtb-data package; plus every error path."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh
import yourdfpy
from hypothesis import given, settings
from hypothesis import strategies as st
from robot_files import (
    RTB,
    RTB_FILES,
    arm_urdf,
    gripper_urdf,
    l_shape,
    random_q,
    write,
    write_meshes,
)

from workcell import Workcell, limits, solids, spatial
from workcell.cell import compile_cell
from workcell.errors import KinematicsError, LimitError, ModelError
from workcell.robots import from_urdf
from workcell.robots.urdf import CONTINUOUS_LIMIT

needs_rtb = pytest.mark.skipif(RTB is None, reason="rtb-data (a test dependency) is missing")


def quiet(path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return from_urdf(path, **kw)


@pytest.fixture(scope="module")
def arm_file(tmp_path_factory):
    d = tmp_path_factory.mktemp("urdf")
    write_meshes(d)
    return write(d, "arm.urdf", arm_urdf())


@pytest.fixture(scope="module")
def arm(arm_file):
    return quiet(arm_file)


def mujoco_frames(path: Path, names: list[str], q: np.ndarray, bodies: tuple[str, str]):
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    for n, v in zip(names, q, strict=True):
        d.qpos[m.joint(n).qposadr[0]] = v
    mujoco.mj_kinematics(m, d)
    out = []
    for b in bodies:
        T = np.eye(4)
        T[:3, :3] = d.xmat[m.body(b).id].reshape(3, 3)
        T[:3, 3] = d.xpos[m.body(b).id]
        out.append(T)
    return np.linalg.inv(out[0]) @ out[1]


# ---------------------------------------------------------------------- the test arm
def test_the_chain_joints_limits_and_defaults(arm):
    assert [j.name for j in arm.joints] == ["j1", "j2", "j3", "j4", "j5"]
    assert [j.kind for j in arm.joints] == ["revolute"] * 2 + ["prismatic"] + ["revolute"] * 2
    assert arm.joints[0].limits == (-3.0, 3.0)
    assert arm.joints[1].limits == (-CONTINUOUS_LIMIT, CONTINUOUS_LIMIT)  # continuous
    assert arm.joints[2].limits == (0.0, 0.2)
    np.testing.assert_allclose(arm.max_speeds, [2.0, 1.0, 0.1, 3.0, 3.0])  # j2: the default
    # accelerations and jerks: the library's rule (full speed in 0.25 s, full acc. in 0.05 s)
    np.testing.assert_allclose(arm.max_accelerations, arm.max_speeds / 0.25)
    np.testing.assert_allclose(arm.max_jerks, arm.max_accelerations / 0.05)
    assert arm.name == "test_arm"
    assert arm.file.format == "urdf"
    assert len(arm.file.sha256) == 64


def test_a_branch_off_the_chain_is_left_out_with_a_warning(arm_file):
    with pytest.warns(UserWarning, match="side_joint"):
        from_urdf(arm_file)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0.0, 1.0), min_size=5, max_size=5))
def test_fk_equals_yourdfpy(arm_file, arm, u):
    q = arm.lower + np.array(u) * (arm.upper - arm.lower)
    ref = yourdfpy.URDF.load(
        str(arm_file), load_meshes=False, build_scene_graph=True, load_collision_meshes=False
    )
    ref.update_cfg(dict(zip([j.name for j in arm.joints], q, strict=True)))
    np.testing.assert_allclose(arm.fk(q), ref.get_transform("tool0", "base_link"), atol=1e-9)


def test_fk_equals_mujocos_own_compile_of_the_file(arm_file, arm):
    names = [j.name for j in arm.joints]
    worst = 0.0
    for q in random_q(arm, 200, seed=1):
        T = mujoco_frames(arm_file, names, q, ("base_link", "tool0"))
        worst = max(worst, float(np.abs(T - arm.fk(q)).max()))
    assert worst < 1e-9


def test_geometry_visuals_collisions_scale_and_colours(arm):
    g = arm.geometry
    by_link = {k: [e for e in g if e.link == k] for k in range(arm.dof + 1)}
    base = by_link[0]
    assert base[0].colour == (1.0, 0.5, 0.0, 1.0)  # the named material
    assert base[0].collides
    assert len(base[0].collision) == 1
    assert base[0].mesh.extents == pytest.approx([0.3, 0.3, 0.1])
    link1 = by_link[1][0]
    assert link1.colour == (0.0, 0.0, 1.0, 1.0)  # inline colour
    assert link1.mesh.extents == pytest.approx([0.15, 0.06, 0.1])  # scale 0.5 1 2 of a box
    # link 2 (after j2): its OBJ cylinder with its sphere collision, and the fixed sensor box
    assert len(by_link[2]) == 2
    assert by_link[2][1].mesh.extents == pytest.approx([0.02, 0.02, 0.02])
    assert not by_link[2][1].collides  # a visual without collision geometry does not collide
    # link 1's transform: the visual origin (rpy about z) in link frame 1
    np.testing.assert_allclose(
        link1.transform, spatial.translation(0.1, 0, 0) @ spatial.rot_z(0.1), atol=1e-15
    )


def test_geometry_false_reads_no_mesh(tmp_path):
    p = write(tmp_path, "arm.urdf", arm_urdf("nowhere"))
    r = quiet(p, geometry=False)
    assert r.dof == 5
    assert not r.geometry


def test_a_cell_compiles_an_imported_arm_with_exact_kinematics(arm):
    cell = Workcell("urdf_cell")
    base = spatial.translation(0.2, -0.1, 0.05) @ spatial.rot_z(0.4)
    q0 = np.array([0.3, -0.5, 0.1, 0.4, 0.2])
    cell.add_robot("r1", arm, base=base, q=q0)
    cc = compile_cell(cell)
    m, d = cc.model, mujoco.MjData(cc.model)
    mujoco.mj_kinematics(m, d)
    site = m.site(cc.tool_sites["r1"]).id
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = d.site_xmat[site].reshape(3, 3), d.site_xpos[site]
    np.testing.assert_allclose(T, base @ arm.fk(q0), atol=1e-9)
    assert m.nmesh > 0
    assert (m.geom_group == 3).any()


# ---------------------------------------------------------------------- meshes and files
@pytest.mark.filterwarnings("ignore:.*are left out")
def test_package_paths_resolve_by_map_then_search_then_beside(tmp_path, arm):
    pkg = tmp_path / "my_pkg"
    write_meshes(pkg)
    text = arm_urdf("package://my_support/meshes")
    f = write(tmp_path / "elsewhere", "arm.urdf", text)
    with pytest.warns(UserWarning, match="my_support") as rec:  # visual meshes fall back
        from_urdf(f)
    tried = " ".join(str(w.message) for w in rec)
    assert str(tmp_path / "elsewhere" / "meshes" / "arm.stl") in tried  # beside the URDF
    assert str(tmp_path / "meshes" / "arm.stl") in tried  # beside its folder
    by_map = quiet(f, packages={"my_support": pkg})
    by_search = quiet(f, search=[tmp_path / "nothing", pkg])
    for r in (by_map, by_search):
        np.testing.assert_allclose(r.fk(np.full(5, 0.1)), arm.fk(np.full(5, 0.1)))
        assert len(r.geometry) == len(arm.geometry)
    # the ROS layout: the package folder holds urdf/ and meshes/
    g = write(pkg / "urdf", "arm.urdf", text)
    assert len(quiet(g).geometry) == len(arm.geometry)


@pytest.mark.filterwarnings("ignore:.*are left out")
def test_root_confines_every_file_read(tmp_path):
    inside, outside = tmp_path / "root", tmp_path / "outside"
    write_meshes(outside)
    f = write(inside, "arm.urdf", arm_urdf("package://p/meshes"))
    with pytest.warns(UserWarning, match="outside the root folder: not tried"):
        from_urdf(f, search=[outside], root=inside)
    write_meshes(inside / "copy")
    os.unlink(inside / "copy" / "meshes" / "arm.stl")
    os.link(outside / "meshes" / "arm.stl", inside / "copy" / "meshes" / "arm.stl")
    with pytest.warns(UserWarning, match="2 hard links, which may lead outside the root"):
        from_urdf(f, search=[inside / "copy"], root=inside)
    assert quiet(f, search=[outside]).geometry  # without a root it is found


@pytest.mark.filterwarnings("ignore:.*are left out")
def test_a_missing_visual_falls_back_to_the_collision_mesh(tmp_path):
    write_meshes(tmp_path)
    text = arm_urdf().replace("meshes/arm.obj", "meshes/missing.dae")
    f = write(tmp_path, "arm.urdf", text)
    with pytest.warns(UserWarning, match=r"missing\.dae.*drawn with its collision geometry"):
        r = from_urdf(f)
    link2 = [g for g in r.geometry if g.link == 2]
    sphere = [g for g in link2 if g.mesh.extents == pytest.approx([0.1, 0.1, 0.1], rel=0.02)]
    assert sphere  # the collision sphere is drawn instead


def test_a_missing_collision_mesh_lists_every_place_tried_when_strict(tmp_path):
    text = arm_urdf().replace('<sphere radius="0.05"/>', '<mesh filename="package://x/c.stl"/>')
    f = write(tmp_path / "robot" / "urdf", "arm.urdf", text)
    write_meshes(f.parent)
    with pytest.raises(ModelError, match=r"link 'link2'.*'package://x/c\.stl'") as err:
        quiet(f, packages={"x": tmp_path / "px"}, search=[tmp_path / "s1"], strict=True)
    msg = str(err.value)
    for place in ("px/c.stl", "s1/c.stl", "urdf/c.stl", "robot/c.stl", "robot/x/c.stl"):
        assert place in msg


def test_dae_meshes_with_units_scale_and_colours(tmp_path):
    box = trimesh.creation.box(extents=(100.0, 20.0, 10.0))  # millimetres
    box.visual.face_colors = [200, 100, 50, 255]
    dae = box.export(file_type="dae")
    dae = dae.replace(b"<up_axis>", b'<unit meter="0.001" name="millimeter"/><up_axis>', 1)
    (tmp_path / "link.dae").write_bytes(dae)
    text = arm_urdf(mujoco=False).replace(
        '<box size="0.3 0.3 0.1"/></geometry><material name="orange"/>',
        '<mesh filename="link.dae" scale="2 1 1"/></geometry>',
    )
    write_meshes(tmp_path)
    r = quiet(write(tmp_path, "arm.urdf", text))
    base = next(g for g in r.geometry if g.link == 0)
    assert base.mesh.extents == pytest.approx([0.2, 0.02, 0.01])  # mm -> m, then x2 in x
    assert base.colour == pytest.approx((200 / 255, 100 / 255, 50 / 255, 1.0))  # the file's own
    (tmp_path / "evil.dae").write_bytes(b'<?xml version="1.0"?><!DOCTYPE c [<!ENTITY a "b">]><c/>')
    with pytest.raises(ModelError, match="COLLADA file with a DOCTYPE"):
        quiet(write(tmp_path, "evil.urdf", text.replace("link.dae", "evil.dae")))


def test_non_convex_collision_meshes_are_decomposed(tmp_path):
    l_shape().export(tmp_path / "ell.stl")
    text = arm_urdf().replace('<sphere radius="0.05"/>', '<mesh filename="ell.stl"/>')
    write_meshes(tmp_path)
    f = write(tmp_path, "arm.urdf", text)
    decomposed = next(g for g in quiet(f).geometry if g.link == 2 and g.collides)
    hulled = next(g for g in quiet(f, concavity=None).geometry if g.link == 2 and g.collides)
    assert len(decomposed.collision) >= 2  # CoACD's pieces: the L's notch stays open
    vol = sum(p.volume for p in decomposed.collision)
    assert vol == pytest.approx(l_shape().volume, rel=0.1)
    assert hulled.collision[-1].volume == pytest.approx(l_shape().convex_hull.volume)


def test_mesh_facets_are_bounded_by_the_work_limits(arm_file):
    with limits.using(max_facets=10), pytest.raises(LimitError, match="max_facets"):
        quiet(arm_file)


# ---------------------------------------------------------------------- the gripper
def test_a_parallel_gripper_of_the_file_is_kept(tmp_path):
    r = quiet(write(tmp_path, "g.urdf", gripper_urdf()))
    assert [j.name for j in r.joints] == ["q1", "q2"]  # the fingers are not arm joints
    g = r.gripper
    assert g is not None
    assert g.finger_travel == pytest.approx(0.04)
    assert g.max_opening == pytest.approx(0.08)
    # the fingers slide along the palm's x axis; the gripper frame turns them onto +-y
    palm_in_b = spatial.translation(0.3, 0, 0) @ spatial.rot_y(np.pi / 2)
    y_in_b = g.mount[:3, 1]
    assert abs(abs(y_in_b @ palm_in_b[:3, 0]) - 1) < 1e-12
    np.testing.assert_allclose(g.mount[:3, 3], palm_in_b[:3, 3], atol=1e-12)
    # no tool0 and no tip_link: the tool is the kept gripper's TCP
    np.testing.assert_allclose(r.tool, g.mount @ g.tcp)
    assert {p.role for p in g.geometry} == {"palm", "left", "right"}
    # the fingers are stored open: each 0.04 m out from closed along its opening direction
    left = next(p for p in g.geometry if p.role == "left")
    right = next(p for p in g.geometry if p.role == "right")
    gap = left.vertices(g.model)[:, 1].min() - right.vertices(g.model)[:, 1].max()
    assert gap == pytest.approx(0.08, abs=1e-9)  # closed the inner faces touch
    kept = quiet(write(tmp_path, "g.urdf", gripper_urdf()), gripper=False)
    assert kept.gripper is None


def test_fingers_sliding_along_the_approach_axis_are_no_parallel_gripper(tmp_path):
    text = gripper_urdf().replace('<axis xyz="1 0 0"/>', '<axis xyz="0 0 1"/>')
    text = text.replace('<axis xyz="-1 0 0"/>', '<axis xyz="0 0 -1"/>')
    with pytest.warns(UserWarning, match="slide along the palm's z axis; it is left out"):
        r = from_urdf(write(tmp_path, "g.urdf", text))
    assert r.gripper is None
    assert any(g.mesh.extents == pytest.approx([0.1, 0.03, 0.02]) for g in r.geometry)  # palm


def test_a_file_gripper_grasps_in_the_simulator(tmp_path):
    from workcell.sim import Simulator

    r = quiet(write(tmp_path, "g.urdf", gripper_urdf()))
    cell = Workcell("grip")
    solids.box(cell.model, "cube", size=(0.03, 0.03, 0.03))
    q = np.array([0.0, 0.3])
    tcp = r.fk(q)
    part = spatial.translation(*(tcp[:3, 3] - 0.015))
    cell.add_movable("cube", "cube", part, density=1000.0)
    cell.add_robot("g", r, q=q)
    sim = Simulator(cell, mode="path", dt=0.01)
    assert sim.close_gripper("g", max_distance=0.01, max_angle=np.radians(90)) == "cube"
    sim.move_joints_absolute("g", [0.5, 0.2])
    centre = sim.part_pose("cube") @ [0.015, 0.015, 0.015, 1.0]
    np.testing.assert_allclose(centre[:3], sim.tool_pose("g")[:3, 3], atol=1e-9)


# ---------------------------------------------------------------------- errors
BAD = {
    "xml": ("<robot><link name='a'></robot>", "not well-formed XML: line 1"),
    "entity": (
        '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaa"><!ENTITY b "&a;&a;">]>'
        "<robot><link name='&b;'/></robot>",
        "entity declarations",
    ),
    "external": (
        '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]>'
        "<robot><link name='&x;'/></robot>",
        "entity declarations",
    ),
    "top": ("<sdf/>", "not <robot>"),
    "nolinks": ("<robot/>", "no <link>"),
    "missing_link": (
        "<robot><link name='a'/><joint name='j' type='fixed'><parent link='a'/>"
        "<child link='b'/></joint></robot>",
        r"joint 'j' \(line 1\): child link 'b' does not exist",
    ),
    "two_parents": (
        "<robot><link name='a'/><link name='b'/><link name='c'/>"
        "<joint name='j1' type='fixed'><parent link='a'/><child link='c'/></joint>"
        "<joint name='j2' type='fixed'><parent link='b'/><child link='c'/></joint></robot>",
        "already the child of joint 'j1'",
    ),
    "loop": (
        "<robot><link name='a'/><link name='b'/>"
        "<joint name='j1' type='fixed'><parent link='a'/><child link='b'/></joint>"
        "<joint name='j2' type='fixed'><parent link='b'/><child link='a'/></joint></robot>",
        "form a loop",
    ),
    "type": (
        "<robot><link name='a'/><link name='b'/><joint name='j' type='hinge'>"
        "<parent link='a'/><child link='b'/></joint></robot>",
        "joint 'j'.*unknown joint type 'hinge'",
    ),
    "planar": (
        "<robot><link name='a'/><link name='b'/><joint name='j' type='planar'>"
        "<parent link='a'/><child link='b'/></joint></robot>",
        "joint 'j'.*planar joint cannot be in a robot's chain",
    ),
    "floating": (
        "<robot><link name='a'/><link name='b'/><joint name='j' type='floating'>"
        "<parent link='a'/><child link='b'/></joint></robot>",
        "floating joint cannot be in",
    ),
    "number": (
        "<robot><link name='a'/><link name='b'/><joint name='j' type='revolute'>"
        "<parent link='a'/><child link='b'/><origin xyz='0 zero 0'/>"
        "<limit lower='-1' upper='1'/></joint></robot>",
        "joint 'j'.*xyz='0 zero 0' must be 3 finite",
    ),
    "limit": (
        "<robot><link name='a'/><link name='b'/><joint name='j' type='revolute'>"
        "<parent link='a'/><child link='b'/></joint></robot>",
        "joint 'j'.*needs <limit",
    ),
    "axis": (
        "<robot><link name='a'/><link name='b'/><joint name='j' type='revolute'>"
        "<parent link='a'/><child link='b'/><axis xyz='0 0 0'/>"
        "<limit lower='-1' upper='1'/></joint></robot>",
        "joint 'j'.*axis must be a non-zero",
    ),
    "roots": ("<robot><link name='a'/><link name='b'/></robot>", "have no parent"),
    "shape": (
        "<robot><link name='a'><visual><geometry><cone/></geometry></visual></link></robot>",
        r"link 'a' \(line 1\) visual 1: unknown geometry <cone>",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_files_raise_model_errors_naming_the_element(tmp_path, case):
    text, pattern = BAD[case]
    with pytest.raises(ModelError, match=pattern):
        quiet(write(tmp_path, f"{case}.urdf", text))


def test_bad_arguments(arm_file, tmp_path):
    with pytest.raises(ModelError, match="tip_link 'nope' is not a link"):
        quiet(arm_file, tip_link="nope")
    with pytest.raises(ModelError, match="'base_link' is not below 'link3'"):
        quiet(arm_file, base_link="link3", tip_link="base_link")
    with pytest.raises(ModelError, match="no movable joint"):
        quiet(arm_file, base_link="link5", tip_link="tool0")
    with pytest.raises(ModelError, match="cannot read URDF file"):
        from_urdf(tmp_path / "none.urdf")
    with limits.using(max_file_bytes=100), pytest.raises(LimitError, match="max_file_bytes"):
        quiet(arm_file)


def test_base_and_tip_choose_a_sub_chain(arm_file, arm):
    sub = quiet(arm_file, base_link="link1b", tip_link="link4")
    assert [j.name for j in sub.joints] == ["j2", "j3", "j4"]
    q = np.array([0.2, 0.3, 0.1, -0.4, 0.5])
    F = arm.link_frames(q)
    mount = spatial.translation(0.05, 0, 0.1) @ spatial.rot_z(0.4) @ spatial.rot_y(-0.1)
    mount = mount @ spatial.rot_x(0.2)  # the fixed joint 'mount': link1 -> link1b
    np.testing.assert_allclose(sub.fk(q[1:4]), np.linalg.inv(F[1] @ mount) @ F[4], atol=1e-12)


# ---------------------------------------------------------------------- rtb-data files
@needs_rtb
@pytest.mark.parametrize("which", sorted(RTB_FILES))
def test_ros_industrial_files_match_yourdfpy_and_their_family(which):
    path = RTB / RTB_FILES[which]
    robot = quiet(path, geometry=False)
    assert robot.dof == 6
    ref = yourdfpy.URDF.load(
        str(path), load_meshes=False, build_scene_graph=True, load_collision_meshes=False
    )
    worst = 0.0
    for q in random_q(robot, 100, seed=2):
        ref.update_cfg(dict(zip([j.name for j in robot.joints], q, strict=True)))
        worst = max(
            worst, float(np.abs(ref.get_transform("tool0", "base_link") - robot.fk(q)).max())
        )
    assert worst < 1e-9
    # the KUKA files are OPW arms; this IRB 140 file's axis 6 misses axis 5 by 20 mm
    assert robot.ik_family == (None if which == "irb140" else "opw")


@needs_rtb
def test_the_irb140_file_falls_back_to_numerical_ik():
    robot = quiet(RTB / RTB_FILES["irb140"], geometry=False)
    with pytest.raises(KinematicsError, match="closed-form"):
        robot.ik_closed_form(robot.fk(np.zeros(6)))
    for q in random_q(robot, 5, seed=3) * 0.5:
        T = robot.fk(q)
        sol = robot.ik(T, q + 0.05)
        assert sol.success, sol.reason
        np.testing.assert_allclose(robot.fk(sol.q), T, atol=1e-5)


@needs_rtb
def test_kuka_closed_form_solutions_contain_the_generating_q():
    robot = quiet(RTB / RTB_FILES["kr16"], geometry=False)
    for q in random_q(robot, 200, seed=4) * 0.9:
        sols = robot.ik_closed_form(robot.fk(q))
        assert min(np.abs(np.angle(np.exp(1j * (s.q - q)))).max() for s in sols) < 1e-7
        for s in sols:
            np.testing.assert_allclose(robot.fk(s.q), robot.fk(q), atol=1e-9)


@needs_rtb
@pytest.mark.slow
@pytest.mark.parametrize("which", sorted(RTB_FILES))
def test_ros_industrial_files_place_in_a_cell(which):
    robot = quiet(RTB / RTB_FILES[which], concavity=None)
    assert robot.geometry
    cell = Workcell(f"rtb_{which}")
    cell.add_robot("r", robot, gripper=True)
    cc = compile_cell(cell)
    assert cc.model.ngeom > 2 * robot.dof
    assert "r.gripper" in [cc.model.body(i).name for i in range(cc.model.nbody)]
    if which == "kr16":  # KUKA orange from the DAE files' materials
        colours = [g.colour for g in robot.geometry if g.colour is not None]
        assert any(c[0] > 0.4 and c[2] < 0.2 for c in colours)
