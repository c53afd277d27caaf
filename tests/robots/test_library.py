"""The robot library: names, published numbers, geometry, cells, the command line, programs.

References from outside the code: the manufacturers' reach figures against the arm
lengths read off each robot's own axes (OPW: a1 + c2 + sqrt(c3^2 + a2^2) is where KUKA,
ABB and FANUC measure their reach, to the wrist centre), MuJoCo's compile of the cells,
and programs run through the ``workcell`` command.
"""

from __future__ import annotations

import json
import math

import mujoco
import numpy as np
import pytest

from workcell import Workcell, solids
from workcell.cell import compile_cell
from workcell.cli import main
from workcell.errors import ModelError
from workcell.robots import attach_gripper, get, library, parallel_gripper
from workcell.robots.ik_closed import family_model
from workcell.robots.library import entries
from workcell.robots.mjcf import robot_spec
from workcell.spatial import rot_z, translation

NAMES = library()
REACH = {e.name: e.reach for e in entries()}


def test_library_names_and_unknown_names():
    assert sorted(NAMES) == NAMES
    need = {"puma260", "puma560", "ur3e", "ur5e", "ur10e", "kuka_kr6_r700", "abb_irb140"}
    assert need <= set(NAMES)
    assert {"abb_irb120", "abb_irb2400", "fanuc_lrmate200id", "kuka_kr16"} <= set(NAMES)
    with pytest.raises(ModelError, match=r"puma260.*ur5e"):
        get("ur6")
    with pytest.raises(ModelError, match="the library has"):
        get(None)  # type: ignore[arg-type]


@pytest.mark.parametrize("name", NAMES)
def test_every_robot_has_finite_documented_limits(name):
    robot = get(name, geometry=False)
    assert robot.source
    assert len(robot.source) > 20
    for values in (robot.max_speeds, robot.max_accelerations, robot.max_jerks):
        assert np.all(np.isfinite(values))
        assert np.all(values > 0)
    assert np.all(np.isfinite(robot.lower))
    assert np.all(robot.upper > robot.lower)
    # accelerations reach the top speed in 0.25 s, jerks the top acceleration in 0.05 s
    np.testing.assert_allclose(robot.max_accelerations, robot.max_speeds / 0.25)
    np.testing.assert_allclose(robot.max_jerks, robot.max_accelerations / 0.05)
    assert robot.within_limits(robot.pose("home"))


@pytest.mark.parametrize("name", [n for n in NAMES if not n.startswith(("ur", "puma"))])
def test_published_reach_is_the_wrist_centre_reach_of_the_axes(name):
    p = family_model(get(name, geometry=False)).parameters()
    wrist = p["a1"] + p["c2"] + math.hypot(p["c3"], p["a2"])
    assert wrist == pytest.approx(REACH[name], rel=0.015)


def test_published_speeds_are_the_data_sheet_figures():
    deg = np.degrees
    np.testing.assert_allclose(deg(get("kuka_kr6_r700").max_speeds), [360, 300, 360, 381, 388, 615])
    np.testing.assert_allclose(deg(get("ur10e").max_speeds), [120, 120, 180, 180, 180, 180])
    np.testing.assert_allclose(deg(get("puma260").max_speeds), [119, 119, 164, 577, 431, 397])


@pytest.mark.parametrize("name", NAMES)
def test_geometry_compiles_follows_fk_and_does_not_touch_itself_at_home(name):
    robot = attach_gripper(get(name), parallel_gripper())
    assert robot.geometry
    assert robot.model is not None
    M = robot_spec(robot, prefix="r.").compile()
    D = mujoco.MjData(M)
    vis = M.geom_group == 2
    assert vis.sum() >= 8
    assert (M.body_mass[1:] > 0).all()
    assert (M.geom_contype[M.geom_group == 3] == 1).all()  # and colliding
    rng = np.random.default_rng(1)
    for q in [robot.pose("home"), *rng.uniform(robot.lower, robot.upper, (10, robot.dof))]:
        for k, j in enumerate(robot.joints):
            D.joint(f"r.{j.name}").qpos[0] = q[k]
        mujoco.mj_kinematics(M, D)
        s = D.site("r.tool")
        np.testing.assert_allclose(s.xpos, robot.fk(q)[:3, 3], atol=1e-9)
        np.testing.assert_allclose(s.xmat.reshape(3, 3), robot.fk(q)[:3, :3], atol=1e-9)
    for k, j in enumerate(robot.joints):
        D.joint(f"r.{j.name}").qpos[0] = robot.pose("home")[k]
    mujoco.mj_kinematics(M, D)
    mujoco.mj_collision(M, D)
    assert D.ncon == 0


def test_every_library_robot_goes_into_a_cell_and_back_from_json(tmp_path):
    cell = Workcell("all")
    for i, name in enumerate(NAMES):
        cell.add_robot(f"r{i}", name, gripper=True, base=translation(2.0 * i, 0, 0))
    path = tmp_path / "all.json"
    cell.save(path)
    data = json.loads(path.read_text())
    assert [r["builtin"] for r in data["robots"]] == NAMES
    back = Workcell.load(path)
    cc = compile_cell(back)
    d = mujoco.MjData(cc.model)
    mujoco.mj_kinematics(cc.model, d)
    for i, name in enumerate(NAMES):
        placed = back.robots[f"r{i}"]
        assert placed.builtin == name
        np.testing.assert_allclose(placed.q, get(name).pose("home"))
        site = d.site(cc.tool_sites[f"r{i}"])
        np.testing.assert_allclose(site.xpos, placed.tool_pose()[:3, 3], atol=1e-9)


def test_workcell_robots_lists_the_library(capsys):
    assert main(["robots", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in rows] == NAMES
    by = {r["name"]: r for r in rows}
    assert by["ur5e"]["axes"] == 6
    assert by["ur5e"]["ik_family"] == "ur"
    assert by["kuka_kr6_r700"]["reach_m"] == pytest.approx(0.7067)
    assert by["puma560"]["ik_family"] == "opw"
    assert main(["robots"]) == 0
    assert "kuka_kr16" in capsys.readouterr().out


# ---------------------------------------------------------------- a program from a saved cell
PROGRAM = """\
cell load {cell}
simulate path dt 0.01
move end_effector arm at cube offset 0 0 0.1 down config ru
move straight arm at cube down
close gripper arm
move straight arm at cube offset 0 0 0.1 down
move end_effector arm on stage offset 0 0 0.12 down config ru
move straight arm on stage offset 0 0 0.02 down
open gripper arm
move straight arm on stage offset 0 0 0.12 down
positions
"""


def pick_place_cell(name: str) -> tuple[Workcell, np.ndarray]:
    """A table with a 40 mm cube and a stage in front of library robot ``name``; returns
    the cell and the stage's top centre (m)."""
    reach = REACH[name]
    h = 0.3 if reach < 1 else 0.5
    d = 0.55 * reach
    cell = Workcell(f"pick_{name}")
    m = cell.model
    solids.box(m, "table_block", size=(0.6, 0.9, h))
    solids.box(m, "stage_block", size=(0.12, 0.12, 0.1))
    solids.cube(m, "cube_block", size=0.04)
    cell.add_static("table", "table_block", translation(d - 0.3, -0.45, 0))
    cell.add_static("stage", "stage_block", translation(d - 0.06, 0.2, h))
    cell.add_movable("cube", "cube_block", translation(d - 0.02, -0.22, h), density=2700.0)
    base = rot_z(math.pi) if name.startswith("ur") else np.eye(4)  # UR arms face -x at home
    cell.add_robot("arm", name, gripper=True, base=base)
    return cell, np.array([d, 0.26, h + 0.1])


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ur5e", "kuka_kr16"])
def test_pick_and_place_from_a_saved_cell_through_workcell_run(name, tmp_path, capsys):
    cell, stage_top = pick_place_cell(name)
    cell.save(tmp_path / "cell.json")
    script = tmp_path / "pick.wcl"
    script.write_text(PROGRAM.format(cell="cell.json"))
    assert main(["run", str(script), "--summary"]) == 0
    out = capsys.readouterr().out
    summary = json.loads(out[out.index("{") :])
    cube = np.array(summary["objects"]["cube"])  # the cube's centroid, 20 mm above the top
    np.testing.assert_allclose(cube - np.array([0.0, 0.0, 0.02]), stage_top, atol=2e-3)
    kinds = [e["kind"] for e in summary["events"]]
    assert "grasp" in kinds
    assert "release" in kinds
    assert summary["collisions"] == 0


@pytest.mark.slow
def test_a_library_robot_runs_in_physics_records_and_renders(tmp_path):
    """The UR5e's pick and place in the simulator's other modes: physics (mj_step with the
    compiled servos), a rerun recording and a rendered frame."""
    from workcell.record import record, render_frame
    from workcell.sim import Simulator
    from workcell.sim.grasp import tool_down
    from workcell.sim.physics import run_physics

    cell, stage_top = pick_place_cell("ur5e")
    cell.add_camera("cam", (1.2, -1.2, 1.0), (0.45, 0.0, 0.3))
    sim = Simulator(cell, mode="path", dt=0.01)
    cube = cell.movable_parts["cube"].pose[:3, 3] + 0.02
    up = translation(0, 0, 0.1)
    sim.move_end_effector("arm", up @ tool_down(cube), config="ru")
    sim.move_straight_line("arm", tool_down(cube))
    assert sim.close_gripper("arm") == "cube"
    sim.move_straight_line("arm", up @ tool_down(cube))
    top = stage_top + np.array([0.0, 0.0, 0.02])
    sim.move_end_effector("arm", up @ tool_down(top), config="ru")
    sim.move_straight_line("arm", tool_down(top))
    sim.open_gripper("arm")
    sim.move_straight_line("arm", up @ tool_down(top))
    res = run_physics(sim)
    assert res.tracking["arm"].tool_max < 5e-3  # m: the servos follow the plan
    assert res.parts["cube"].distance < 1e-3  # and the cube lands where it did kinematically
    assert res.parts["cube"].resting
    path = tmp_path / "run.rrd"
    record(sim, path)
    assert path.stat().st_size > 10_000
    image = render_frame(sim, -1, camera="cam", width=160, height=120)
    assert image.shape == (120, 160, 3)
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 50  # a scene, not a blank


def test_the_command_language_places_library_robots():
    from workcell.program.interpreter import Interpreter
    from workcell.program.session import Session

    out: list[str] = []
    it = Interpreter(Session(), out=out.append)
    it.run_line("cell new line_cell")
    it.run_line("add robot r1 ur5e gripper translate 1 0 0")
    it.run_line("add robot r2 kuka_kr6 q 0 -90 90 0 45 0")  # an unambiguous prefix
    cell = it.session.require_cell()
    assert cell.robots["r1"].builtin == "ur5e"
    assert cell.robots["r1"].robot.gripper is not None
    np.testing.assert_allclose(cell.robots["r1"].base[:3, 3], [1, 0, 0])
    assert cell.robots["r2"].builtin == "kuka_kr6_r700"
    np.testing.assert_allclose(np.degrees(cell.robots["r2"].q), [0, -90, 90, 0, 45, 0], atol=1e-12)
    with pytest.raises(Exception, match="ur10e"):  # what is valid there is listed
        it.run_line("add robot r3 ur7")
