"""Compiling a workcell to MuJoCo and exporting it as MJCF + meshes."""

from __future__ import annotations

import json
import subprocess
import sys

import mujoco
import numpy as np
import pytest
from cell_helpers import two_puma_cell

from workcell.cell import compile_cell, export_cell
from workcell.cli import main
from workcell.spatial import pose_from_pos_quat


@pytest.fixture(scope="module")
def compiled():
    cell = two_puma_cell()
    return cell, compile_cell(cell)


def _body_pose(d, bid):
    return pose_from_pos_quat(d.xpos[bid], d.xquat[bid])


def test_tool_site_matches_fk_for_random_q(compiled):
    cell, cc = compiled
    m = cc.model
    d = mujoco.MjData(m)
    rng = np.random.default_rng(7)
    for name, r in cell.robots.items():
        adr = [m.joint(j).qposadr[0] for j in cc.joint_names[name]]
        sid = m.site(cc.tool_sites[name]).id
        for _ in range(20):
            q = rng.uniform(r.robot.lower, r.robot.upper)
            d.qpos[adr] = q
            mujoco.mj_kinematics(m, d)
            T = np.eye(4)
            T[:3, :3] = d.site_xmat[sid].reshape(3, 3)
            T[:3, 3] = d.site_xpos[sid]
            np.testing.assert_allclose(T, r.base @ r.robot.fk(q), atol=1e-9)


def test_initial_q_is_qpos0(compiled):
    cell, cc = compiled
    m = cc.model
    for name, r in cell.robots.items():
        adr = [m.joint(j).qposadr[0] for j in cc.joint_names[name]]
        np.testing.assert_array_equal(m.qpos0[adr], r.q)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    for name, r in cell.robots.items():
        sid = m.site(cc.tool_sites[name]).id
        np.testing.assert_allclose(d.site_xpos[sid], r.tool_pose()[:3, 3], atol=1e-9)


def test_movable_mass_and_centre_of_mass(compiled):
    cell, cc = compiled
    m = cc.model
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    for name, p in cell.movable_parts.items():
        mesh = cell.model.world_mesh(p.entity)  # trimesh: the independent value
        bid = m.body(cc.part_bodies[name]).id
        assert m.body_mass[bid] == pytest.approx(p.density * mesh.volume, rel=1e-6)
        world_com = (p.pose @ np.append(mesh.center_mass, 1.0))[:3]
        np.testing.assert_allclose(d.xipos[bid], world_com, atol=1e-9)
        np.testing.assert_allclose(_body_pose(d, bid), p.pose, atol=1e-12)


def test_free_joints_only_for_movable_parts(compiled):
    cell, cc = compiled
    m = cc.model
    free = {m.joint(i).name for i in range(m.njnt) if m.jnt_type[i] == mujoco.mjtJoint.mjJNT_FREE}
    assert free == {f"{n}.free" for n in cell.movable_parts}
    for n in cell.movable_parts:
        assert m.body(m.joint(f"{n}.free").bodyid[0]).name == n


def test_weld_per_gripper_robot_and_part_inactive(compiled):
    cell, cc = compiled
    m = cc.model
    pairs = {(r, p) for r in cell.robots for p in cell.movable_parts}
    assert set(cc.welds) == pairs
    for (r, p), ename in cc.welds.items():
        e = m.equality(ename)
        assert ename == f"grasp.{r}.{p}"
        assert e.type[0] == mujoco.mjtEq.mjEQ_WELD
        assert not m.eq_active0[e.id]
        assert m.body(e.obj1id[0]).name == cc.gripper_bodies[r]
        assert m.body(e.obj2id[0]).name == p
        np.testing.assert_array_equal(m.eq_data[e.id, :3], 0)  # anchor set, not (0, 1, 0)
        np.testing.assert_array_equal(m.eq_data[e.id, 6:10], [1, 0, 0, 0])
    assert m.neq == len(pairs)


def test_no_slash_in_any_name(compiled):
    _, cc = compiled
    m = cc.model
    names = m.names.split(b"\x00")
    assert names
    assert not any(b"/" in n for n in names)


def test_cameras_look_at_their_target(compiled):
    cell, cc = compiled
    m = cc.model
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)  # camera poses come from mj_camlight
    for name, c in cell.cameras.items():
        cid = m.camera(cc.cameras[name]).id
        R = d.cam_xmat[cid].reshape(3, 3)
        np.testing.assert_allclose(d.cam_xpos[cid], c.position, atol=1e-12)
        to_target = (c.target - c.position) / np.linalg.norm(c.target - c.position)
        np.testing.assert_allclose(-R[:, 2], to_target, atol=1e-9)
        assert m.cam_fovy[cid] == pytest.approx(c.fovy)


_LOADER = """
import json, sys, mujoco, numpy as np
from dm_control import mjcf
path = sys.argv[1]
m = mujoco.MjModel.from_xml_path(path)
phys = mjcf.Physics.from_mjcf_model(mjcf.from_path(path))
phys.forward()
print(json.dumps({"nbody": m.nbody, "njnt": m.njnt, "neq": m.neq, "ngeom": m.ngeom,
                  "dm_nbody": int(phys.model.nbody), "qpos0": m.qpos0.tolist(),
                  "mass": m.body_mass.tolist()}))
"""


def test_exported_folder_loads_elsewhere(compiled, tmp_path):
    cell, cc = compiled
    path = export_cell(cell, tmp_path / "out")
    assert path.is_absolute()
    assert path.exists()
    assert "<frame" not in path.read_text()  # dm_control 1.0.50's schema has no <frame>
    assert (path.parent / "meshes" / "cube.mesh.stl").exists()
    res = subprocess.run(
        [sys.executable, "-c", _LOADER, str(path)],
        cwd="/",
        capture_output=True,
        text=True,
        timeout=120,
        env={"MUJOCO_GL": "egl", "PATH": "/usr/bin:/bin"},
    )
    assert res.returncode == 0, res.stderr
    got = json.loads(res.stdout.strip().splitlines()[-1])
    m = cc.model
    assert (got["nbody"], got["njnt"], got["neq"], got["ngeom"]) == (
        m.nbody,
        m.njnt,
        m.neq,
        m.ngeom,
    )
    assert got["dm_nbody"] == m.nbody
    np.testing.assert_allclose(got["qpos0"], m.qpos0, atol=1e-12)
    np.testing.assert_allclose(got["mass"], m.body_mass, rtol=1e-6)


def test_cli_export(tmp_path, capsys):
    cell = two_puma_cell()
    cell.save(tmp_path / "cell.json")
    assert main(["export", str(tmp_path / "cell.json"), "--out", str(tmp_path / "x")]) == 0
    assert (tmp_path / "x" / "two_pumas.xml").exists()
    assert "two_pumas.xml" in capsys.readouterr().out
    (tmp_path / "bad.json").write_text("{}")
    assert main(["export", str(tmp_path / "bad.json"), "--out", str(tmp_path / "y")]) == 2
    assert capsys.readouterr().err.startswith("workcell: ModelError: ")


def test_non_convex_object_part_gets_convex_pieces():
    from workcell import solids
    from workcell.cell import Workcell
    from workcell.spatial import translation

    cell = Workcell("l_cell")
    m = cell.model
    solids.box(m, "bar", size=(0.1, 0.02, 0.02))
    m.create("object", "ell")
    m.attach("ell", "bar")
    m.attach(
        "ell",
        "bar",
        translation(0.02, 0.03, 0)
        @ np.array([[0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=float),
    )
    cell.add_movable("ell_part", "ell", translation(0, 0, 0.1), density=1000.0)
    cc = compile_cell(cell)
    mm = cc.model
    cols = [mm.geom(i).name for i in range(mm.ngeom) if mm.geom(i).name.startswith("ell_part.col")]
    assert len(cols) == 2
    vol = cell.model.world_mesh(("object", "ell")).volume
    assert mm.body_mass[mm.body("ell_part").id] == pytest.approx(1000.0 * vol, rel=1e-6)


def test_object_of_overlapping_blocks_compiles_with_one_visual_per_block():
    from workcell import solids
    from workcell.cell import Workcell
    from workcell.spatial import translation

    cell = Workcell("cross_cell")
    m = cell.model
    solids.box(m, "bar", size=(0.1, 0.02, 0.02))
    m.create("object", "cross")
    m.attach("cross", "bar", translation(-0.05, -0.01, 0))
    m.attach(
        "cross",
        "bar",
        translation(0.01, -0.05, 0)
        @ np.array([[0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=float),
    )  # the two bars cross at the origin: their meshes overlap
    cell.add_movable("cross_part", "cross", translation(0, 0, 0.1), density=1000.0)
    mm = compile_cell(cell).model
    visuals = [mm.geom(i).name for i in range(mm.ngeom) if ".visual" in mm.geom(i).name]
    assert sorted(visuals) == ["cross_part.visual0", "cross_part.visual1"]
    # each bar 0.1 x 0.02 x 0.02 m at 1000 kg/m^3: the overlap is counted in both
    # meshes travel as STL (float32 vertices): 1e-6 relative
    assert mm.body_mass[mm.body("cross_part").id] == pytest.approx(
        2 * 1000.0 * 0.1 * 0.02 * 0.02, rel=1e-6
    )
    assert cell.mass("cross_part") == pytest.approx(2 * 1000.0 * 0.1 * 0.02 * 0.02, rel=1e-12)
