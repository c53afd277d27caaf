"""Robot files without (some of) their meshes still give the robot: the kinematics are
all in the file. Checked against MuJoCo's own compile of the same files (with their
meshes), the capsule stand-ins against their sizing rule, the warnings and ``strict``
errors against the places MuJoCo and ROS look; plus pybullet's ``package://meshes/...``."""

from __future__ import annotations

import math
import shutil
import warnings
from pathlib import Path

import mujoco
import numpy as np
import pytest
from robot_files import PYBULLET, arm_urdf, menagerie_like, random_q, write, write_meshes

from workcell import Workcell
from workcell.cell import compile_cell
from workcell.errors import ModelError
from workcell.robots import from_mjcf, from_urdf


def loud(load, *args, **kw):
    """(robot, the warnings' texts) of one import."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = load(*args, **kw)
    return robot, [str(w.message) for w in caught]


def extents_along(mesh, axis) -> tuple[float, float]:
    """(length along the unit ``axis``, width across it) of a mesh's vertices."""
    v = mesh.vertices
    along = v @ axis
    across = np.linalg.norm(v - np.outer(along, axis), axis=1)
    return float(along.max() - along.min()), float(2 * across.max())


# ---------------------------------------------------------------------- URDF
def test_a_missing_urdf_collision_mesh_is_a_capsule_between_the_joints(tmp_path):
    write_meshes(tmp_path)
    text = arm_urdf().replace('<sphere radius="0.05"/>', '<mesh filename="package://x/c.stl"/>')
    f = write(tmp_path, "arm.urdf", text)
    robot, said = loud(from_urdf, f)
    [w] = [s for s in said if "not found" in s]
    assert "'package://x/c.stl' (link 'link2' (line" in w  # the name as the file wrote it
    assert "collision 1: a capsule between its joints stands in" in w
    assert str(tmp_path / "x" / "c.stl") in w  # every place tried
    assert "strict=True" in w
    # link2's joint origin to the farthest joint it carries (j3 at 0.3 m along x); the
    # file states no inertia: radius 10 % of the longer of 0.3 m and its parent's 0.1 m
    [stand] = [g for g in robot.geometry if g.link == 2 and g.collides]
    hull = stand.collision[-1]
    length, width = extents_along(hull, np.array([1.0, 0.0, 0.0]))
    assert length == pytest.approx(0.3 + 2 * 0.03, abs=1e-3)
    assert width == pytest.approx(2 * 0.03, abs=1e-3)
    ref = from_urdf(f, geometry=False)
    Q = random_q(robot, 20)
    np.testing.assert_array_equal(robot.fk_batch(Q), ref.fk_batch(Q))


def test_a_stand_in_takes_its_radius_from_the_files_inertia(tmp_path):
    write_meshes(tmp_path)
    inertial = (
        '<inertial><origin xyz="0.15 0 0"/><mass value="2"/>'
        '<inertia ixx="0.0025" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>'
    )
    text = arm_urdf().replace('<sphere radius="0.05"/>', '<mesh filename="gone.stl"/>')
    text = text.replace('<link name="link2">', '<link name="link2">' + inertial)
    robot, _ = loud(from_urdf, write(tmp_path, "arm.urdf", text))
    [stand] = [g for g in robot.geometry if g.link == 2 and g.collides]
    # a solid cylinder of 2 kg whose moment about its axis is 0.0025 kg m^2: r = 0.05 m
    r = math.sqrt(2 * 0.0025 / 2)
    length, width = extents_along(stand.collision[-1], np.array([1.0, 0.0, 0.0]))
    assert width == pytest.approx(2 * r, abs=1e-3)
    assert length == pytest.approx(0.3 + 2 * r, abs=1e-3)


def test_strict_makes_a_missing_mesh_an_error(tmp_path):
    write_meshes(tmp_path)
    text = arm_urdf().replace("meshes/arm.obj", "meshes/gone.obj")
    with pytest.raises(ModelError, match=r"link 'link2' .*visual 1: mesh file 'meshes/gone\.obj'"):
        from_urdf(write(tmp_path, "arm.urdf", text), strict=True)


def test_a_urdf_copied_without_its_meshes_keeps_its_kinematics(tmp_path):
    write_meshes(tmp_path)
    f = write(tmp_path, "arm.urdf", arm_urdf())
    full, _ = loud(from_urdf, f)
    shutil.rmtree(tmp_path / "meshes")
    bare, said = loud(from_urdf, f)
    Q = random_q(full, 20)
    np.testing.assert_array_equal(bare.fk_batch(Q), full.fk_batch(Q))
    assert any("2 mesh file(s) not found" in s for s in said)
    # link1 is drawn with its collision box instead of its mesh; link2 with its sphere
    assert {g.link for g in bare.geometry} == {g.link for g in full.geometry}
    cell = Workcell("bare")
    cell.add_robot("r", bare)
    compile_cell(cell)


@pytest.mark.filterwarnings("ignore:.*are left out")
def test_pybullet_package_paths_resolve_beside_the_file_and_its_parents(tmp_path, arm):
    robot_dir = tmp_path / "my_robot"
    write_meshes(robot_dir)  # my_robot/meshes/arm.stl, as pybullet_data's robots
    text = arm_urdf("package://meshes")
    beside = from_urdf(write(robot_dir, "arm.urdf", text))
    below = from_urdf(write(robot_dir / "urdf" / "deep", "arm.urdf", text))  # two levels up
    for r in (beside, below):
        assert len(r.geometry) == len(arm.geometry)
        q = np.full(5, 0.1)
        np.testing.assert_allclose(r.fk(q), arm.fk(q))


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    d = tmp_path_factory.mktemp("arm")
    write_meshes(d)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return from_urdf(write(d, "arm.urdf", arm_urdf()))


@pytest.mark.skipif(PYBULLET is None, reason="pybullet (a test dependency) is missing")
def test_pybullets_panda_finds_its_meshes():
    _, said = loud(from_urdf, PYBULLET / "franka_panda" / "panda.urdf", concavity=None)
    assert not [s for s in said if "not found" in s]


# ---------------------------------------------------------------------- MJCF
def mujoco_fk(path: Path, robot, q, tip: str) -> np.ndarray:
    """The pose of body ``tip`` in body link0's frame, by MuJoCo's own compile of ``path``."""
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    for j, v in zip(robot.joints, q, strict=True):
        d.qpos[m.joint(j.name).qposadr[0]] = v
    mujoco.mj_kinematics(m, d)
    out = []
    for b in ("link0", tip):
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = d.xmat[m.body(b).id].reshape(3, 3), d.xpos[m.body(b).id]
        out.append(T)
    return np.linalg.inv(out[0]) @ out[1]


def test_a_menagerie_scene_without_assets_imports_with_stand_ins(tmp_path):
    scene = menagerie_like(tmp_path)
    full = from_mjcf(scene, tip_body="hand")
    for q in random_q(full, 10, seed=5):
        np.testing.assert_allclose(full.fk(q), mujoco_fk(scene, full, q, "hand"), atol=1e-9)
    shutil.rmtree(tmp_path / "assets")
    bare, said = loud(from_mjcf, scene, tip_body="hand")
    Q = random_q(full, 20)
    np.testing.assert_array_equal(bare.fk_batch(Q), full.fk_batch(Q))
    assert bare.poses.keys() == full.poses.keys()
    [w] = [s for s in said if "not found" in s]
    assert "4 mesh file(s) not found" in w
    # each name as written, where MuJoCo looks (meshdir 'assets' from the included file)
    for name in ("base.stl", "link1.stl", "upper.obj", "fore.stl"):
        assert f"'{name}'" in w
        assert str(tmp_path / "assets" / name) in w
    # link0 (4 kg, smallest moment 0.02) stands in from its origin to link1's joint 0.333 m up
    r = math.sqrt(2 * 0.02 / 4)
    [base] = [g for g in bare.geometry if g.link == 0]
    length, width = extents_along(base.mesh, np.array([0.0, 0.0, 1.0]))
    assert width == pytest.approx(2 * r, abs=1e-3)
    assert length == pytest.approx(0.333 + 2 * r, abs=1e-3)
    assert base.collides  # its collision geom's mesh was missing too
    upper = [g for g in bare.geometry if g.link == 2]
    assert upper
    assert not any(g.collides for g in upper)  # only a visual geom there
    cell = Workcell("bare_mjcf")
    cell.add_robot("r", bare)
    compile_cell(cell)


def test_geometry_false_reads_no_mesh_file(tmp_path):
    scene = menagerie_like(tmp_path, assets=False)
    robot, said = loud(from_mjcf, scene, geometry=False, tip_body="hand")
    assert robot.dof == 4
    assert robot.geometry == ()
    assert not [s for s in said if "not found" in s]
    for q in random_q(robot, 5, seed=8):
        T = robot.fk(q)
        assert np.isfinite(T).all()


def test_strict_names_the_path_in_the_assets_folder(tmp_path):
    scene = menagerie_like(tmp_path, assets=False)
    with pytest.raises(
        ModelError, match=r"mesh file 'base\.stl' not found; tried: .*assets/base\.stl"
    ):
        from_mjcf(scene, strict=True)
