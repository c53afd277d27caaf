"""Every kind of robot in a saved cell: library names, robots built from DH rows or joints
(saved inline), robots read from URDF and MJCF files (saved as their file, its sha256
and the import options), checked by the FK of the rebuilt robots (bit for bit), MuJoCo's
compile of the reloaded cell, and a pick-and-place program through ``workcell run``."""

from __future__ import annotations

import json
import math
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh
from robot_files import RTB, RTB_FILES, arm_mjcf, arm_urdf, random_q, write, write_meshes
from test_library import PROGRAM  # the library robots' pick and place, in the language

from workcell import Workcell, solids, spatial
from workcell.cell import compile_cell
from workcell.cli import main
from workcell.errors import ModelError
from workcell.robots import (
    Joint,
    LinkGeometry,
    Robot,
    attach_gripper,
    chain_geometry,
    from_mjcf,
    from_urdf,
    parallel_gripper,
)
from workcell.robots.chain import joints_from_table


def quiet_urdf(path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return from_urdf(path, **kw)


def reload(cell: Workcell, path: Path, **kw) -> Workcell:
    cell.save(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Workcell.load(path, **kw)


def same_robot(a: Robot, b: Robot, n: int = 50) -> None:
    assert [j.name for j in a.joints] == [j.name for j in b.joints]
    Q = random_q(a, n, seed=7)
    assert np.array_equal(a.fk_batch(Q), b.fk_batch(Q))  # bit for bit
    np.testing.assert_array_equal(a.lower, b.lower)
    np.testing.assert_array_equal(a.max_jerks, b.max_jerks)


def dh_robot() -> Robot:
    """A 4-axis arm from a modified-DH table, with generated link solids and poses."""
    rows = [(0, 0.3, 0, 0), (0.05, 0, -90, -90), (0.35, 0, 0, 0), (0.05, 0.3, -90, 0)]
    joints = joints_from_table(
        rows, [(-170, 170), (-120, 120), (-150, 150), (-180, 180)],
        max_speed_deg=[150, 150, 180, 300], convention="modified",
    )  # fmt: skip
    robot = Robot(
        "dh4", joints, tool=spatial.translation(0, 0, 0.08), poses={"home": [0, 0.2, 0.3, 0]}
    )
    return chain_geometry(robot)


def test_library_dh_and_joint_robots_round_trip(tmp_path):
    cell = Workcell("kinds")
    custom = Robot(
        "custom",
        (Joint("a", spatial.translation(0, 0, 0.2), (0, 0, 1)),
         Joint("b", spatial.rot_x(0.3) @ spatial.translation(0.1, 0, 0.1), (0, 1, 0),
               limits=(-1, 2), max_speed=1.5, axis_point=(0.01, 0, 0)),
         Joint("c", spatial.translation(0.2, 0, 0), (1, 0, 0), "prismatic", limits=(0, 0.3))),
    )  # fmt: skip
    cell.add_robot("lib", "ur5e", gripper={"max_opening": 0.06})
    cell.add_robot("dh", dh_robot(), gripper=True, base=spatial.translation(1, 0, 0))
    cell.add_robot("joints", custom, base=spatial.translation(0, 1, 0), q=[0.1, 0.2, 0.05])
    data = json.loads(json.dumps(cell.to_dict()))
    kinds = {
        r["name"]: next(k for k in ("builtin", "chain", "file") if k in r) for r in data["robots"]
    }
    assert kinds == {"lib": "builtin", "dh": "chain", "joints": "chain"}
    dh = next(r for r in data["robots"] if r["name"] == "dh")
    assert dh["chain"]["joints"][1]["dh"]["convention"] == "modified"  # the DH rows are kept
    assert dh["gripper"] == {}
    back = reload(cell, tmp_path / "kinds.json")
    assert back == cell
    for name in ("dh", "joints"):
        same_robot(cell.robots[name].robot, back.robots[name].robot)
    assert back.robots["dh"].robot.gripper is not None
    assert back.robots["dh"].robot.pose("home").tolist() == [0, 0.2, 0.3, 0]
    a, b = compile_cell(cell).model, compile_cell(back).model
    assert a.nbody == b.nbody
    np.testing.assert_array_equal(a.body_pos, b.body_pos)
    np.testing.assert_allclose(a.body_mass, b.body_mass, rtol=1e-12)


def test_urdf_robots_are_saved_as_their_file(tmp_path):
    folder = tmp_path / "robots" / "arm"
    write_meshes(folder)
    urdf = write(folder, "arm.urdf", arm_urdf())
    robot = quiet_urdf(urdf, base_link="base_link", tip_link="link5", name="my_arm")
    cell = Workcell("urdf_cell")
    cell.add_robot("r", robot, gripper=True, q=[0.1, 0.2, 0.05, 0.3, 0.4])
    cell_file = tmp_path / "cells" / "c.json"
    cell_file.parent.mkdir()
    back = reload(cell, cell_file)
    entry = json.loads(cell_file.read_text())["robots"][0]
    assert entry["file"]["path"] == "../robots/arm/arm.urdf"  # relative to the cell file
    assert entry["file"]["options"]["tip_link"] == "link5"
    assert entry["file"]["options"]["name"] == "my_arm"
    assert len(entry["file"]["sha256"]) == 64
    assert entry["gripper"] == {}
    same_robot(robot, back.robots["r"].bare)
    np.testing.assert_array_equal(back.robots["r"].robot.tool, cell.robots["r"].robot.tool)
    # cell and robot folders moved together: still found
    shutil.move(tmp_path / "robots", tmp_path / "moved" / "robots")
    shutil.move(tmp_path / "cells", tmp_path / "moved" / "cells")
    moved = tmp_path / "moved" / "cells" / "c.json"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert Workcell.load(moved).robots["r"].robot.dof == 5
    # a changed robot file, then a missing one
    moved_urdf = tmp_path / "moved" / "robots" / "arm" / "arm.urdf"
    moved_urdf.write_text(moved_urdf.read_text().replace('velocity="2"', 'velocity="2.5"'))
    with pytest.raises(ModelError, match=r"robots\[0\] \('r'\).*changed since the cell was saved"):
        Workcell.load(moved)
    moved_urdf.unlink()
    with pytest.raises(ModelError, match=r"robots\[0\] \('r'\).*cannot read robot file"):
        Workcell.load(moved)


def test_mjcf_robots_with_their_own_gripper_round_trip(tmp_path):
    write_meshes(tmp_path)
    f = write(tmp_path, "arm.xml", arm_mjcf())
    robot = from_mjcf(f, tool_site="flange")
    cell = Workcell("mjcf_cell")
    cell.add_robot("m", robot)
    back = reload(cell, tmp_path / "m.json")
    r = back.robots["m"].robot
    same_robot(robot, r)
    assert r.gripper is not None
    assert r.gripper.finger_travel == robot.gripper.finger_travel
    np.testing.assert_array_equal(back.robots["m"].q, robot.pose("home"))  # its home keyframe


def test_robots_that_cannot_be_saved_say_why(tmp_path):
    box = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    meshy = Robot("meshy", (Joint("a"),), geometry=(LinkGeometry(1, None, np.eye(4), mesh=box),))
    cell = Workcell("bad")
    cell.add_robot("m", meshy)
    with pytest.raises(ModelError, match=r"robot 'm' cannot be saved.*from_urdf or from_mjcf"):
        cell.save(tmp_path / "bad.json")
    cell = Workcell("bad2")
    cell.add_robot("g", attach_gripper(dh_robot(), parallel_gripper()))
    with pytest.raises(ModelError, match=r"attached outside the cell.*gripper=\.\.\."):
        cell.to_dict()


def test_a_changed_file_robot_is_no_longer_that_file(tmp_path):
    write_meshes(tmp_path)
    robot = quiet_urdf(write(tmp_path, "arm.urdf", arm_urdf()))
    assert robot.with_(name="x", nominal_speed=0.5).file == robot.file  # the same robot
    for change in ({"base": spatial.translation(0, 0, 1)}, {"tool": np.eye(4)}, {"geometry": ()}):
        assert robot.with_(**change).file is None


def test_root_confines_robot_files_of_a_loaded_cell(tmp_path):
    write_meshes(tmp_path / "outside")
    urdf = write(tmp_path / "outside", "arm.urdf", arm_urdf())
    cell = Workcell("c")
    cell.add_robot("r", quiet_urdf(urdf))
    root = tmp_path / "root"
    root.mkdir()
    cell.save(root / "c.json")
    with pytest.raises(ModelError, match=r"outside the server's root folder|refused"):
        Workcell.load(root / "c.json", root=root)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert Workcell.load(root / "c.json").robots["r"].robot.dof == 5


# ---------------------------------------------------------------- KUKA KR 16 from rtb-data


@pytest.mark.slow
@pytest.mark.skipif(RTB is None, reason="rtb-data (a test dependency) is missing")
def test_an_imported_kr16_runs_pick_and_place_from_a_saved_cell(tmp_path, capsys):
    robot = quiet_urdf(RTB / RTB_FILES["kr16"])
    assert robot.ik_family == "opw"
    d, h = 0.55 * 1.611, 0.5
    cell = Workcell("pick_kr16_urdf")
    m = cell.model
    solids.box(m, "table_block", size=(0.6, 0.9, h))
    solids.box(m, "stage_block", size=(0.12, 0.12, 0.1))
    solids.cube(m, "cube_block", size=0.04)
    cell.add_static("table", "table_block", spatial.translation(d - 0.3, -0.45, 0))
    cell.add_static("stage", "stage_block", spatial.translation(d - 0.06, 0.2, h))
    cell.add_movable("cube", "cube_block", spatial.translation(d - 0.02, -0.22, h), density=2700.0)
    cell.add_robot("arm", robot, gripper=True, q=np.radians([0, -90, 90, 0, 45, 0]))
    cell.save(tmp_path / "cell.json")
    entry = json.loads((tmp_path / "cell.json").read_text())["robots"][0]
    assert entry["file"]["format"] == "urdf"
    script = tmp_path / "pick.wcl"
    script.write_text(PROGRAM.format(cell="cell.json"))
    assert main(["run", str(script), "--summary"]) == 0
    out = capsys.readouterr().out
    summary = json.loads(out[out.index("{") :])
    cube = np.array(summary["objects"]["cube"])
    np.testing.assert_allclose(cube, [d, 0.26, h + 0.1 + 0.02], atol=2e-3)  # on the stage
    kinds = [e["kind"] for e in summary["events"]]
    assert "grasp" in kinds
    assert "release" in kinds
    assert summary["collisions"] == 0
    assert math.isfinite(summary["sim_time_s"])


# ---------------------------------------------------------------- the language and the server
def test_the_command_language_imports_robot_files(tmp_path):
    from workcell.errors import ProgramError
    from workcell.program import Session
    from workcell.program.interpreter import Interpreter

    write_meshes(tmp_path)
    write(tmp_path, "arm.urdf", arm_urdf())
    write(tmp_path, "arm.xml", arm_mjcf())
    session = Session(base_dir=tmp_path)
    run = Interpreter(session, out=lambda _: None).run_line
    run("cell new c")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run("add robot r1 urdf arm.urdf tip_link link5 gripper translate 1 0 0")
        run("add robot r2 mjcf arm.xml tool_site flange q 0 10 0.1 20 30")
    r1, r2 = session.cell.robots["r1"], session.cell.robots["r2"]
    np.testing.assert_array_equal(r1.base, spatial.translation(1, 0, 0))
    same_robot(r1.bare, quiet_urdf(tmp_path / "arm.urdf", tip_link="link5"))
    assert r1.robot.gripper is not None
    same_robot(r2.robot, from_mjcf(tmp_path / "arm.xml", tool_site="flange"))
    np.testing.assert_allclose(r2.q, [0, np.radians(10), 0.1, np.radians(20), np.radians(30)])
    for line, pattern in (
        ("add robot r3 ur5e urdf arm.urdf", "give one of a library MODEL"),
        ("add robot r3 urdf arm.urdf tool_site x", "tool_site do.*not apply to a urdf file"),
        ("add robot r3 base_link x", "only for a robot read from urdf or mjcf"),
        ("add robot r3 mjcf none.xml", "cannot read MJCF file"),
    ):
        with pytest.raises((ProgramError, ModelError), match=pattern):
            run(line)
    assert set(session.cell.robots) == {"r1", "r2"}  # a failed command changes nothing
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run("cell save c.json")
        run("cell load c.json")
    same_robot(session.cell.robots["r2"].robot, r2.robot)


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:.*are left out")
def test_the_server_imports_robot_files_inside_its_root(tmp_path):
    from workcell.client import Client
    from workcell.errors import ProgramError
    from workcell.program.server import Server

    write_meshes(tmp_path)
    write(tmp_path, "arm.urdf", arm_urdf())
    robot = quiet_urdf(tmp_path / "arm.urdf")
    srv = Server(port=0, root=tmp_path)
    srv.serve_in_thread()
    try:
        with Client(port=srv.port, timeout=60) as c:
            c.new_cell(name="c")
            c.import_robot(name="r", format="urdf", path="arm.urdf", gripper=True)
            with pytest.raises(ProgramError, match="refused"):
                c.import_robot(name="s", format="urdf", path="arm.urdf", search=["/etc"])
            c.simulate()
            q = np.array([0.3, -0.2, 0.1, 0.5, -0.4])
            c.move_joints_absolute("r", q)
            tool = attach_gripper(robot, parallel_gripper()).fk(q)
            np.testing.assert_allclose(c.tool_pose("r"), tool, atol=1e-9)
            assert c.cell.robots["r"].robot.dof == 5  # the client rebuilds the cell's robot
            # a client on another machine has not got the file: it rebuilds the robot from
            # the kinematics the server sends with it, and says so
            (tmp_path / "arm.urdf").rename(tmp_path / "elsewhere.urdf")
            c.create_cube(name="k", size=0.1)  # a command that may change the cell: refetch
            with pytest.warns(UserWarning, match="rebuilt from the kinematics"):
                far = c.cell.robots["r"].robot
            np.testing.assert_allclose(far.fk(q), tool, atol=1e-12)
            assert [j.limits for j in far.joints] == [j.limits for j in robot.joints]
            np.testing.assert_array_equal(far.max_speeds, robot.max_speeds)
            assert far.file is None
            assert all(g.block.startswith("gripper.") for g in far.geometry)  # no link meshes
    finally:
        srv.stop()


@pytest.mark.slow
@pytest.mark.skipif(RTB is None, reason="rtb-data (a test dependency) is missing")
def test_an_imported_robot_runs_in_physics_records_and_renders(tmp_path):
    """The imported KR 16's pick and place with mj_step (the compiled servos, its DAE link
    masses), a rerun recording and a rendered frame; the MJCF arm's own gripper too."""
    from workcell.record import record, render_frame
    from workcell.sim import Simulator
    from workcell.sim.grasp import tool_down
    from workcell.sim.physics import run_physics

    cell = Workcell("kr16_physics")
    solids.box(cell.model, "table_block", size=(0.6, 0.9, 0.5))
    solids.cube(cell.model, "cube_block", size=0.04)
    cell.add_static("table", "table_block", spatial.translation(0.6, -0.45, 0))
    cell.add_movable("cube", "cube_block", spatial.translation(0.88, -0.22, 0.5), density=2700.0)
    cell.add_robot("arm", quiet_urdf(RTB / RTB_FILES["kr16"]), gripper=True,
                   q=np.radians([0, -90, 90, 0, 45, 0]))  # fmt: skip
    cell.add_camera("cam", (2.5, -2.5, 2.0), (0.8, 0.0, 0.5))
    sim = Simulator(cell, mode="path", dt=0.01)
    cube = cell.movable_parts["cube"].pose[:3, 3] + 0.02
    up = spatial.translation(0, 0, 0.1)
    sim.move_end_effector("arm", up @ tool_down(cube), config="ru")
    sim.move_straight_line("arm", tool_down(cube))
    assert sim.close_gripper("arm") == "cube"
    sim.move_straight_line("arm", up @ tool_down(cube))
    there = cube + np.array([0.0, 0.2, 0.0])  # slid 0.2 m along the table
    sim.move_straight_line("arm", tool_down(there))
    sim.open_gripper("arm")
    sim.move_straight_line("arm", up @ tool_down(there))
    res = run_physics(sim)
    assert res.tracking["arm"].tool_max < 5e-3  # m: the servos follow the plan
    assert res.parts["cube"].distance < 1e-3  # the cube lands where it did kinematically
    assert res.parts["cube"].resting
    record(sim, tmp_path / "run.rrd")
    assert (tmp_path / "run.rrd").stat().st_size > 10_000
    img = render_frame(sim, len(sim.timeline) - 1, camera="cam")
    assert img.shape == (480, 640, 3)
    assert (img.reshape(-1, 3).std(axis=0) > 10).all()  # a picture, not a blank
    # an MJCF arm's own gripper holds a part in physics too
    write_meshes(tmp_path)
    arm = from_mjcf(write(tmp_path, "arm.xml", arm_mjcf()), tool_site="flange")
    cell = Workcell("mjcf_physics")
    solids.box(cell.model, "cube", size=(0.02, 0.02, 0.02))
    q = arm.pose("home")
    cell.add_movable("cube", "cube", spatial.translation(*(arm.fk(q)[:3, 3] - 0.01)), density=500.0)
    cell.add_robot("m", arm, q=q)
    sim = Simulator(cell, mode="path", dt=0.01)
    assert sim.close_gripper("m", max_distance=0.005, max_angle=np.radians(90)) == "cube"
    sim.move_joints_absolute("m", q + 0.1)
    res = run_physics(sim)
    assert res.tracking["m"].tool_max < 5e-3


@pytest.mark.filterwarnings("ignore:.*are left out")
def test_a_cell_with_file_robots_exports_for_mujoco_and_dm_control(tmp_path):
    from dm_control import mjcf

    from workcell.cell import export_cell

    write_meshes(tmp_path)
    cell = Workcell("exported")
    cell.add_robot("u", quiet_urdf(write(tmp_path, "arm.urdf", arm_urdf())), gripper=True)
    cell.add_robot(
        "m", from_mjcf(write(tmp_path, "arm.xml", arm_mjcf())), base=spatial.translation(1, 0, 0)
    )
    xml = export_cell(cell, tmp_path / "out")
    physics = mjcf.Physics.from_mjcf_model(mjcf.from_path(str(xml)))
    physics.step()
    names = {physics.model.body(i).name for i in range(physics.model.nbody)}
    assert {"u.gripper", "m.gripper"} <= names  # ours on the URDF arm, the MJCF arm's own
