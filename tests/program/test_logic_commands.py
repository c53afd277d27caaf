"""Cell logic in every front end: the command language and the server give what the
Python API gives (a cell built in the language equals the one built in Python, a beam
breaks at the same time, programs run together the same), and bad input is refused with
a clear error and changes nothing, in each of them."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import snapshot

from workcell import GeometryError, ModelError, ProgramError, SignalTimeout, solids
from workcell.cell import Workcell
from workcell.client import Client
from workcell.program import Session
from workcell.program.interpreter import Interpreter
from workcell.program.keytree import CommandSyntaxError
from workcell.program.server import Server
from workcell.sim import Simulator
from workcell.spatial import translation

CELL_LINES = [
    "cell new flow",
    "create box crate size 0.1 0.1 0.1",
    "add movable box crate density 500 translate 0 2 0",
    "add robot puma puma260 translate 0 -1.2 0",
    "add signal run true",
    "add signal done false",
    "add conveyor belt from 0 0 0.5 to 3 0 0.5 width 0.3 speed 500 mm/s run run",
    "add source feeder box translate 0.1 -0.05 0.5 every 1 count 3",
    "add sensor beam beam from 1 -0.3 0.55 to 1 0.3 0.55",
    "add sensor gap proximity at 1.5 0 1 direction 0 0 -1 range 1 threshold 0.45",
    "add sink out center 2 0 0.55 size 0.2 0.4 0.4",
]
ROBOT_WCL = "signal wait beam\nmove joints relative puma 20 0 0 0 0 0\nsignal set done true\n"
CONTROLLER_WCL = "signal wait done\nsignal set run false\nwait 1\nsignal show\n"


def python_cell() -> Workcell:
    cell = Workcell("flow")
    solids.box(cell.model, "crate", size=(0.1, 0.1, 0.1))
    cell.add_movable("box", "crate", translation(0, 2, 0), density=500.0)
    cell.add_robot("puma", "puma260", base=translation(0, -1.2, 0))
    cell.add_signal("run", True)
    cell.add_signal("done", False)
    cell.add_conveyor(
        "belt", start=(0, 0, 0.5), end=(3, 0, 0.5), width=0.3, speed=0.5, run_signal="run"
    )
    cell.add_source("feeder", "box", at=(0.1, -0.05, 0.5), every=1.0, count=3)
    cell.add_sensor("beam", "beam", start=(1, -0.3, 0.55), end=(1, 0.3, 0.55))
    cell.add_sensor(
        "gap", "proximity", origin=(1.5, 0, 1), direction=(0, 0, -1), range=1.0, threshold=0.45
    )
    cell.add_sink("out", center=(2, 0, 0.55), size=(0.2, 0.4, 0.4))
    return cell


@pytest.fixture
def lang(tmp_path):
    session = Session(base_dir=tmp_path)
    out: list[str] = []
    interp = Interpreter(session, out.append)
    for line in CELL_LINES:
        interp.run_line(line)
    (tmp_path / "robot.wcl").write_text(ROBOT_WCL)
    (tmp_path / "controller.wcl").write_text(CONTROLLER_WCL)
    return session, interp, out


def test_a_cell_built_in_the_language_is_the_python_one(lang):
    session, _interp, _out = lang
    assert session.cell.to_dict() == python_cell().to_dict()


def test_signals_and_programs_in_the_language_run_as_in_python(lang, tmp_path):
    session, interp, out = lang
    interp.run_line("simulate path dt 0.01")
    interp.run_line("program puma robot.wcl; program controller controller.wcl")
    interp.run_line("programs")
    assert out[-1] == "puma: robot.wcl\ncontroller: controller.wcl"
    interp.run_line("run programs")
    assert "program puma: done" in out[-1]
    assert "done = true" in out[-1]
    ref = Simulator(python_cell(), dt=0.01)
    ref.run_programs({"puma": tmp_path / "robot.wcl", "controller": tmp_path / "controller.wcl"})
    sim = session.sim
    assert [(e.t, e.kind, e.detail) for e in sim.events] == [
        (e.t, e.kind, e.detail) for e in ref.events
    ]
    interp.run_line("signal show beam; distance gap; throughput")
    assert out[-3] == f"beam = {'true' if ref.signal('beam') else 'false'}"
    assert out[-2] == f"{ref.distance('gap'):.6g} m"
    assert "robot puma: moving" in out[-1]
    interp.run_line(f"gantt {tmp_path / 'g.png'}")
    assert (tmp_path / "g.png").stat().st_size > 1000


def test_a_wait_in_the_language_breaks_the_beam_when_python_does(lang):
    session, interp, _out = lang
    interp.run_line("simulate; signal wait beam true timeout 10")
    ref = Simulator(python_cell(), dt=0.01)
    ref.wait_signal("beam", True, timeout=10)
    assert session.sim.sim_time == ref.sim_time
    with pytest.raises(SignalTimeout, match=r"'done' did not become true within 0\.5 s"):
        interp.run_line("signal wait done timeout 500 ms")
    assert session.sim.sim_time == pytest.approx(ref.sim_time + 0.5)
    interp.run_line("signal set done 1")  # 1 is true for a bool signal
    assert session.sim.signal("done") is True


@pytest.mark.parametrize(
    ("line", "error", "words"),
    [
        ("add signal go maybe", CommandSyntaxError, "true, false or a number"),
        ("add signal run false", ModelError, "taken"),
        ("add conveyor c from 0 0 .5 to 1 0 .6 width .3 speed 1", GeometryError, "one height"),
        (
            "add conveyor c from 0 0 .5 to 1 0 .5 width .3 speed 1 run nope",
            ModelError,
            "no signal 'nope'",
        ),
        ("add sensor s beam from 0 0 0 to 0 0 0", GeometryError, "apart"),
        ("add sensor s presence center 0 0 0 size 1 0 1", GeometryError, "> 0"),
        (
            "add source s nothing translate 0 0 0 every 1",
            CommandSyntaxError,
            "unknown movable part",
        ),
        ("add source s box translate 0 0 0", ModelError, "pattern of source 'feeder'"),
        ("add sink k center 0 0 0 size 0.1 0.1", CommandSyntaxError, "edge lengths"),
        ("signal set run true", ProgramError, "no simulation running"),
        ("run programs", ProgramError, "no simulation running"),
        ("program puma robot.txt", ProgramError, "no .wcl file"),
        ("program puma missing.wcl", ProgramError, "missing.wcl"),
    ],
)
def test_bad_logic_lines_are_refused_and_change_nothing(lang, line, error, words):
    session, interp, _ = lang
    before = snapshot(session)
    with pytest.raises(error, match=words):
        interp.run_line(line)
    assert snapshot(session) == before
    assert session.programs == {}


@pytest.mark.parametrize(
    ("line", "error", "words"),
    [
        ("signal set nope true", CommandSyntaxError, "unknown signal 'nope'"),
        ("signal set done 2.5", ProgramError, "bool signal takes true or false"),
        ("signal wait done timeout -1", ProgramError, "timeout"),
        ("distance beam", ProgramError, "proximity sensors: gap"),
        ("run programs", ProgramError, "no programs"),
        ("run programs until -3", ProgramError, "until must be"),
        ("add signal x 1", ProgramError, "being simulated"),
    ],
)
def test_bad_logic_lines_while_simulating_change_nothing(lang, line, error, words):
    session, interp, _ = lang
    interp.run_line("simulate")
    before = (snapshot(session), session.sim.signals())
    with pytest.raises(error, match=words):
        interp.run_line(line)
    assert (snapshot(session), session.sim.signals()) == before


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    root = tmp_path_factory.mktemp("root")
    (root / "robot.wcl").write_text(ROBOT_WCL)
    (root / "controller.wcl").write_text(CONTROLLER_WCL)
    srv = Server(port=0, root=root)
    srv.serve_in_thread()
    yield srv
    srv.stop()


def _remote_cell(c: Client) -> None:
    c.new_cell(name="flow")
    c.create_box(name="crate", size=[0.1, 0.1, 0.1])
    c.add_movable(name="box", entity="crate", density=500.0, pose=translation(0, 2, 0).tolist())
    c.add_robot(name="puma", robot="puma260", base=translation(0, -1.2, 0).tolist())
    c.add_signal(name="run", initial=True)
    c.add_signal(name="done", initial=False)
    c.add_conveyor(
        name="belt", start=[0, 0, 0.5], end=[3, 0, 0.5], width=0.3, speed=0.5, run_signal="run"
    )
    c.add_source(name="feeder", part="box", at=[0.1, -0.05, 0.5], every=1.0, count=3)
    c.add_sensor(name="beam", kind="beam", start=[1, -0.3, 0.55], end=[1, 0.3, 0.55])
    c.add_sensor(
        name="gap",
        kind="proximity",
        origin=[1.5, 0, 1],
        direction=[0, 0, -1],
        range=1.0,
        threshold=0.45,
    )
    c.add_sink(name="out", center=[2, 0, 0.55], size=[0.2, 0.4, 0.4])


def test_the_server_runs_the_same_cell_and_programs(server):
    with Client(port=server.port, timeout=60) as c:
        _remote_cell(c)
        assert c.cell.to_dict() == python_cell().to_dict()
        c.simulate("path", dt=0.01)
        out = c.run_programs({"puma": "robot.wcl", "controller": "controller.wcl"})
        assert out["puma"]["state"] == "done"
        ref = Simulator(python_cell(), dt=0.01)
        root = server.root
        ref.run_programs({"puma": root / "robot.wcl", "controller": root / "controller.wcl"})
        assert c.sim_time == ref.sim_time
        assert c.signals() == ref.signals()
        assert c.signal("run") is False
        assert c.distance("gap") == pytest.approx(ref.distance("gap"))
        assert c.throughput() == ref.throughput()
        c.set_signal("run", True)
        c.wait_signal("beam", True, timeout=5.0)
        with pytest.raises(SignalTimeout):
            c.wait_signal("done", False, timeout=0.25)


@pytest.mark.parametrize(
    ("call", "error", "words"),
    [
        (lambda c: c.add_signal(name="x", initial="yes"), ProgramError, "true, false or a number"),
        (lambda c: c.set_signal("nope", True), ProgramError, "signals: run"),
        (lambda c: c.set_signal("done", 3), ProgramError, "bool signal"),
        (lambda c: c.wait_signal("done", True, timeout=-1), ProgramError, "timeout"),
        (lambda c: c.distance("beam"), ProgramError, "proximity sensors: gap"),
        (
            lambda c: c.run_programs({"puma": lambda s: None}),
            ProgramError,
            "Python functions run in-process",
        ),
        (lambda c: c.run_programs({"puma": "/etc/passwd.wcl"}), ProgramError, "refused"),
        (
            lambda c: c.run_programs({"puma": "robot.wcl"}, until=-1.0),
            ProgramError,
            "until must be",
        ),
        (lambda c: c.call("program", name="x", path="../robot.wcl"), ProgramError, "refused"),
        (lambda c: c.call("gantt", path="../g.png"), ProgramError, "refused"),
        (lambda c: c.call("add_sensor", name="s", kind="laser"), ProgramError, "beam"),
    ],
)
def test_bad_logic_requests_to_the_server_change_nothing(server, call, error, words):
    with Client(port=server.port, timeout=60) as c:
        _remote_cell(c)
        c.simulate("path", dt=0.01)
        before = (c.frames, c.signals(), c.cell.to_dict())
        with pytest.raises(error, match=words):
            call(c)
        assert (c.frames, c.signals(), c.cell.to_dict()) == before


def test_the_conveyor_programs_in_the_language_stack_two_boxes(tmp_path):
    from pathlib import Path

    from workcell.program.interpreter import run_script

    assets = Path(__file__).resolve().parents[2] / "assets"
    lines: list[str] = []
    session = run_script(assets / "conveyor_programs.wcl", out=lines.append)
    sim = session.sim
    end = sim.part_positions()
    # where the robot's program sets them down: the stack places written in the file
    assert np.allclose(end["box_1"], [0.355, -0.395, 0.325], atol=1e-6)
    assert np.allclose(end["box_2"], [0.445, -0.395, 0.325], atol=1e-6)
    assert sim.throughput()["signals"]["placed"]["rising"] == 2
    assert sim.summary()["collisions"] == 0
    assert "program controller: done" in "\n".join(lines)
