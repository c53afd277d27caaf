"""The command vocabulary: building commands from plain arguments, running them on a session."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from program_helpers import EXAMPLE1_SIM_TIME, snapshot

from workcell import JointLimitError, ModelError, ProgramError, WorkcellError, spatial
from workcell.examples import thesis_joints
from workcell.program import COMMANDS, Command, Session, from_wire
from workcell.program import cellcommands as cellc
from workcell.program import commands as cmd
from workcell.program import simcommands as simc
from workcell.program import solidcommands as sol


def run(session: Session, wire: str, *args, **kwargs):
    return session.execute(from_wire(wire, list(args) if args else kwargs))


def test_every_command_is_a_frozen_documented_dataclass_with_a_wire_name():
    assert len(COMMANDS) >= 50
    for name, cls in COMMANDS.items():
        assert cls.wire == name
        assert dataclasses.is_dataclass(cls), name
        assert cls.__dataclass_params__.frozen, name
        assert issubclass(cls, Command), name
        assert cls.execute is not Command.execute, name
        assert (cls.__doc__ or "").strip(), name
        for f in dataclasses.fields(cls):  # every argument is checked by a converter
            assert callable(f.metadata.get("convert")), (name, f.name)


def test_the_simulator_api_names_are_commands():
    api = [
        "set_speed", "move_joints_absolute", "move_joints_relative", "wait", "joints",
        "tool_pose", "play", "summary", "robots", "frames", "sim_time", "events",
        "move_end_effector", "move_straight_line", "close_gripper", "open_gripper",
        "set_mode", "held", "clearance",
    ]  # fmt: skip
    assert set(api) <= set(COMMANDS)


def test_arguments_by_position_and_by_name_give_the_same_command():
    a = from_wire("create_cylinder", ["c", 0.5, 2.0, 24])
    b = from_wire("create_cylinder", {"name": "c", "radius": 0.5, "height": 2, "n": 24})
    assert a == b
    assert a.height == 2.0
    assert isinstance(a.height, float)


@pytest.mark.parametrize(
    ("wire", "args", "words"),
    [
        (
            "create_cube",
            {"name": "c", "sise": 1},
            ["unknown argument", "sise", "valid: name, size"],
        ),
        ("create_cylinder", {"name": "c", "radius": 1}, ["missing", "height"]),
        ("create_cube", {"name": "c", "size": "big"}, ["size", "finite number", "'big'"]),
        ("create_cube", {"name": "c", "size": True}, ["finite number"]),
        ("move_joints_absolute", {"robot": "p", "q": [1, "x"]}, ["q", "list of numbers"]),
        ("set_transform", {"owner": "b", "relation": "r", "transform": [[1, 2]]}, ["4x4"]),
        ("create", {"level": "surface", "name": "s"}, ["level", "block, object, scene"]),
        ("remove", {"ref": ["nolevel", "x"]}, ["level in surface, block"]),
        ("create_cube", [1, 2, 3, 4], ["at most 3 arguments"]),
        ("create_surface", {"name": "s", "points": [[0, 0], [1, 0]]}, ["at least 3"]),
        ("create_sphere", {"name": "s", "radius": 1, "m": 2.5}, ["whole number"]),
        ("create_sphere", {"name": "s", "radius": 1, "m": 10**5}, ["in 0 .. 10000"]),
        ("set_colour", {"ref": "x", "colour": [2, 0, 0]}, ["[0, 1]"]),
    ],
)
def test_bad_arguments_raise_program_error_naming_the_argument(wire, args, words):
    with pytest.raises(ProgramError) as e:
        from_wire(wire, args)
    for w in words:
        assert w in str(e.value)


def test_unknown_command_suggests_and_lists():
    with pytest.raises(ProgramError, match=r"did you mean move_joints_absolute"):
        from_wire("move_joint_absolute", {})


def test_to_args_round_trips():
    c = cmd.Attach("cube1", "square1", spatial.srt(rotation=(0.3, 0, 0)).tolist(), "f1")
    again = from_wire("attach", c.to_args())
    assert again == c


def test_the_thesis_cube_through_the_vocabulary_has_unit_volume(session):
    run(session, "create_surface", name="square1", points=[[0, 0], [1, 0], [1, 1], [0, 1]])
    run(session, "create", level="block", name="cube1")
    d = math.pi / 2
    rows = [((d, 0, 0), (0, 0, 0)), ((d, 0, 0), (0, 1, 0)), ((0, -d, 0), (0, 0, 0)),
            ((0, -d, 0), (1, 0, 0)), ((0, 0, 0), (0, 0, 0)), ((0, 0, 0), (0, 0, 1))]  # fmt: skip
    for r, t in rows:
        run(session, "attach", owner="cube1", target="square1", transform=spatial.srt(1, r, t))
    p = run(session, "properties", "cube1")
    assert p["volume"] == pytest.approx(1.0, abs=1e-12)
    assert np.allclose(p["centroid"], [0.5, 0.5, 0.5])
    assert session.model.pointed_by("square1") == 6
    run(session, "copy", ref="cube1", new_name="para", transform=spatial.scaling(2, 3, 1.5))
    assert run(session, "properties", "para")["volume"] == pytest.approx(2 * 3 * 1.5)


@pytest.mark.parametrize(
    ("command", "volume"),
    [
        (sol.CreateCube("c", 0.5), 0.125),
        (sol.CreateBox("b", (0.1, 0.2, 0.3)), 0.006),
        # an n-gon prism: n/2 r^2 sin(2 pi/n) h
        (sol.CreateCylinder("y", 0.5, 2.0, 24), 12 * 0.25 * math.sin(2 * math.pi / 24) * 2),
        (sol.CreateCone("k", 0.5, 1.0, 24), 12 * 0.25 * math.sin(2 * math.pi / 24) / 3),
    ],
)
def test_primitives_have_their_analytic_volumes(session, command, volume):
    session.execute(command)
    assert session.model.properties(command.name).volume == pytest.approx(volume, rel=1e-9)


def test_sphere_and_torus_volumes(session):
    session.execute(sol.CreateSphere("s", 1.0, 64, 32))
    assert session.model.properties("s").volume == pytest.approx(4 / 3 * math.pi, rel=3e-3)
    session.execute(sol.CreateTorus("t", 1.0, 0.25, 64, 32))
    # an n-gon section (area n/2 r^2 sin(2 pi/n)) revolved in m planar steps about an axis at
    # distance R: V = m sin(2 pi/m) R A (Pappus on the inscribed polyhedron)
    section = 32 / 2 * 0.25**2 * math.sin(2 * math.pi / 32)
    exact = 64 * math.sin(2 * math.pi / 64) * 1.0 * section
    assert session.model.properties("t").volume == pytest.approx(exact, rel=1e-9)


def test_modify_copy_show_list_detach_remove(session):
    session.execute(sol.CreateCube("c", 1.0))
    run(session, "rename", ref="c", new_name="d")
    assert session.model.exists("d")
    assert not session.model.exists(("block", "c"))
    run(session, "set_colour", ref="d", colour=[1, 0, 0])
    assert session.model.info("d").colour == (1.0, 0.0, 0.0, 1.0)
    run(session, "set_movable", ref="d", movable=True)
    assert session.model.info("d").movable
    rel = session.model.relations("d")[0].name
    run(session, "rename_relation", owner="d", relation=rel, new_name="bottom")
    run(
        session,
        "set_transform",
        owner="d",
        relation="bottom",
        transform=spatial.translation(0, 0, 5),
    )
    assert session.model.relation("d", "bottom").transform[2, 3] == 5
    assert "block d" in run(session, "show", ref="d")
    assert "bottom" in run(session, "show", "d", True)
    assert run(session, "list", level="block") == ["d"]
    run(session, "detach", owner="d", relation="bottom")
    assert len(session.model.relations("d")) == 5
    run(session, "create", level="object", name="o")
    run(session, "attach", owner="o", target="d")
    with pytest.raises(ModelError, match="pointed to"):
        run(session, "remove", ref="d")
    assert run(session, "remove", ref="o") == ["o"]
    removed = run(session, "remove", ref="d", recursive=True)
    assert removed == ["d", "c.square"]  # its own square, named when it was "c"


def test_save_load_and_mesh_export_write_files(session, tmp_path):
    session.execute(sol.CreateCube("c", 0.5))
    path = run(session, "save", path="m.json")
    assert path == str(tmp_path / "m.json")
    other = Session(base_dir=tmp_path)
    other.execute(cmd.LoadModel("m.json"))
    assert other.model == session.model
    mesh = run(session, "world_mesh", ref="c", path="c.stl")
    assert mesh["watertight"]
    assert mesh["volume"] == pytest.approx(0.125)
    assert np.allclose(mesh["bounds"], [[0, 0, 0], [0.5, 0.5, 0.5]])
    assert (tmp_path / "c.stl").stat().st_size == 84 + 50 * mesh["faces"]  # binary STL size


@pytest.mark.parametrize(
    "command",
    [
        cmd.CreateEntity("block", "c"),  # the name is taken
        cmd.CreateEntity("block", "bad name"),
        cmd.CreateSurface("s", ((0, 0), (1, 1), (2, 2))),  # zero area
        sol.CreateCube("c", 1.0),  # taken
        sol.CreateCube("new", -1.0),
        sol.CreateCylinder("cyl", 1.0, 1.0, 2),
        sol.CreateTorus("t", 0.2, 0.5),
        cmd.Remove("c.square"),  # pointed to
        cmd.Remove("nothing"),
        cmd.Rename("c", "o c"),
        cmd.Attach("c", "c"),  # a cycle / wrong level
        cmd.Attach("o", "c", ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 0, 0), (0, 0, 0, 1))),
        cmd.Detach("c", "nope"),
        cmd.SetTransform("c", "ts1", ((0,) * 4,) * 4),
        cmd.Copy("c", "c"),
        cmd.LoadModel("missing.json"),
        cmd.SaveModel("no/such/dir/m.json"),
        cmd.WorldMesh("c", "c.txt"),
    ],
)
def test_a_failed_datamodel_command_changes_nothing(session, command):
    session.execute(sol.CreateCube("c", 1.0))
    session.execute(cmd.CreateEntity("object", "o"))
    before = snapshot(session)
    with pytest.raises(WorkcellError):
        session.execute(command)
    assert snapshot(session) == before


def test_cell_commands_build_a_cell_on_the_sessions_model(session, tmp_path):
    session.execute(sol.CreateBox("table", (0.6, 0.6, 0.4)))
    session.execute(sol.CreateCube("cube", 0.04))
    session.execute(cellc.NewCell("c1"))
    assert session.cell.model is session.model
    session.execute(
        cellc.AddStatic("table_1", "table", spatial.translation(-0.3, -0.3, 0).tolist())
    )
    session.execute(
        cellc.AddMovable("part", "cube", 2700.0, spatial.translation(0.3, 0, 0.4).tolist())
    )
    session.execute(
        cellc.AddRobot("puma", "puma260", True, spatial.translation(0, 0, 0.4).tolist())
    )
    assert session.cell.mass("part") == pytest.approx(2700 * 0.04**3)
    text = session.execute(cellc.ShowCell())
    assert "robot puma" in text
    assert "movable part" in text
    assert "static table_1" in text
    session.execute(cellc.SaveCell("c.json"))
    other = Session(base_dir=tmp_path)
    assert other.execute(cellc.LoadCell("c.json")) == "c1"
    assert other.cell == session.cell
    # parts' entities are protected while the cell uses them
    before = snapshot(session)
    for bad in (cmd.Remove("cube"), cmd.Rename("table", "t2"), cmd.Remove("cube.square")):
        with pytest.raises(ModelError, match="part '"):
            session.execute(bad)
    assert snapshot(session) == before


def test_cell_edits_are_refused_while_simulating_and_model_load_while_a_cell_is_loaded(session):
    session.execute(cellc.ExampleCell("joints"))
    session.execute(simc.Simulate())
    before = snapshot(session)
    for bad in (
        cellc.AddRobot("r2"),
        cellc.RemoveFromCell("puma"),
        cellc.NewCell("x"),
        cmd.LoadModel("m.json"),
        cellc.RemoveFromCell("nobody"),
    ):
        with pytest.raises(WorkcellError):
            session.execute(bad)
    assert snapshot(session) == before
    session.execute(simc.StopSimulation())
    session.execute(cellc.AddRobot("r2", base=spatial.translation(1, 0, 0).tolist()))
    assert set(session.cell.robots) == {"puma", "r2"}


def test_example_1_through_the_vocabulary_takes_the_hand_formula_time(session):
    session.execute(cellc.ExampleCell("joints"))
    session.execute(simc.Simulate("path", 0.01))
    session.execute(simc.SetSpeed("puma", 0.3))
    session.execute(simc.MoveJointsRelative("puma", tuple(np.radians(thesis_joints.RELATIVE_DEG))))
    session.execute(simc.MoveJointsAbsolute("puma", tuple(np.radians(thesis_joints.ABSOLUTE_DEG))))
    session.execute(simc.MoveJointsAbsolute("puma", tuple(np.radians(thesis_joints.START_DEG))))
    assert session.execute(simc.SimTime()) == pytest.approx(EXAMPLE1_SIM_TIME, abs=1e-9)
    assert np.allclose(session.execute(simc.Joints("puma")), np.radians(thesis_joints.START_DEG))
    events = session.execute(simc.Events())
    assert [e["kind"] for e in events] == ["speed", "move", "move", "move"]
    assert session.execute(simc.Robots()) == ("puma",)
    # frames: 1 + sum over moves of ceil(T / dt) (remainders are not zero here)
    T = np.radians([70, 40, 60]) / 0.3
    assert session.execute(simc.Frames()) == 1 + int(np.sum(np.ceil(T / 0.01)))


def test_failed_simulation_commands_change_nothing(session):
    session.execute(cellc.ExampleCell("joints"))
    session.execute(simc.Simulate("path", 0.01))
    session.execute(simc.MoveJointsRelative("puma", (0.1, 0, 0, 0, 0, 0)))
    before = snapshot(session)
    bad = [
        (simc.MoveJointsAbsolute("puma", (math.radians(170), 0, 0, 0, 0, 0)), JointLimitError),
        (simc.MoveJointsAbsolute("puma", (0, 0, 0)), ProgramError),
        (simc.MoveJointsRelative("nobody", (0,) * 6), ProgramError),
        (simc.SetSpeed("puma", -1.0), ProgramError),
        (simc.SetSpeed("puma", 1e6), ProgramError),
        (simc.Wait(-1.0), ProgramError),
        (simc.Joints("x"), ProgramError),
        (simc.Simulate("path", -0.01), ProgramError),
    ]
    for command, error in bad:
        with pytest.raises(error):
            session.execute(command)
        assert snapshot(session) == before, command


def test_simulation_commands_without_a_simulation_say_how_to_start_one(session):
    with pytest.raises(ProgramError, match="no cell yet"):
        session.execute(simc.Simulate())
    session.execute(cellc.ExampleCell("joints"))
    with pytest.raises(ProgramError, match="simulate"):
        session.execute(simc.SimTime())


def test_a_session_handed_a_simulator_drives_it(session):
    sim = thesis_joints.run("path", 0.01)
    s = Session(sim=sim)
    assert s.model is sim.cell.model
    assert s.cell is sim.cell
    assert s.execute(simc.SimTime()) == pytest.approx(EXAMPLE1_SIM_TIME)
    with pytest.raises(ProgramError):
        Session(sim=sim, cell=thesis_joints.build())


def test_cell_save_during_a_simulation_saves_the_cell_as_set_up_and_says_so(tmp_path):
    # the user's steps: a cell, a simulation that moves the robot, `cell save`
    from workcell import Workcell
    from workcell.program.interpreter import Interpreter

    said: list[str] = []
    interp = Interpreter(Session(base_dir=tmp_path), out=said.append)
    for line in (
        "cell example joints",
        "simulate path dt 0.01",
        "cell save before.json",  # nothing has moved yet: the path alone
        "move joints relative puma 10 0 0 0 0 0",
        "cell save during.json",
    ):
        interp.run_line(line)
    assert said[-2] == str(tmp_path / "before.json")  # (a move prints nothing)
    assert said[-1] == (
        f"{tmp_path / 'during.json'}: the cell as set up (the state programs start from); "
        "the simulation's state at t = 0.581776 s is not in it"
    )  # 10 deg at the thesis's 0.3 rad/s: 0.5818 s
    initial = np.radians([0, 0, -90, 0, 90, 0])  # example 1's robot as set up
    for name in ("before.json", "during.json"):
        saved = Workcell.load(tmp_path / name)
        np.testing.assert_allclose(saved.robots["puma"].q, initial, atol=1e-12)
    assert not np.allclose(interp.session.sim.joints("puma"), initial)
