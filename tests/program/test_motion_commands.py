"""The motion commands from every front end: the language (units), sessions, the server
and its Python client, and ``workcell run --cycle-time``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from workcell.client import Client
from workcell.errors import ProgramError
from workcell.examples import thesis_pick_place as pp
from workcell.program import Session
from workcell.program import simcommands as simc
from workcell.program.keytree import CommandSyntaxError
from workcell.program.language import parse_line
from workcell.program.server import Server
from workcell.sim import Simulator
from workcell.sim.grasp import tool_down
from workcell.spatial import translation

PROGRAM = [
    "cell example pick-place",
    "simulate path dt 0.01",
    "move end_effector puma at cube offset 0 0 0.1 down config ru",
    "move linear puma at cube down speed 100 mm/s",
    "override puma 50 %",
    "move linear puma offset 0 0 0.1 speed 250 mm/s acceleration 800 mm/s^2 zone 20 mm",
    "move circular puma via 0.36 0.03 0.56 on stage_1 offset 0 0 0.1 down speed 0.25",
]


def python_program(sim) -> None:
    """PROGRAM through the Simulator's (or the client's) own methods, SI units."""
    cube = pp.grasp_position()
    sim.move_end_effector("puma", translation(0, 0, 0.1) @ tool_down(cube), config="ru")
    sim.move_linear("puma", tool_down(cube), speed=0.1)
    sim.set_override("puma", 0.5)
    sim.move_linear(
        "puma", translation(0, 0, 0.1) @ tool_down(cube), speed=0.25, acceleration=0.8, zone=0.02
    )
    top = np.array([0.24, 0.22, pp.STAGE_1_TOP])  # the centre of stage 1's top
    sim.move_circular(
        "puma", [0.36, 0.03, 0.56], tool_down(top + np.array([0, 0, 0.1])), speed=0.25
    )


def test_the_language_reads_tool_speeds_accelerations_zones_and_percentages():
    (m,) = list(parse_line(PROGRAM[5]))
    assert isinstance(m, simc.MoveLinear)
    assert (m.speed, m.acceleration, m.zone) == pytest.approx((0.25, 0.8, 0.02))
    (c,) = list(parse_line(PROGRAM[6]))
    assert c.via.position == (0.36, 0.03, 0.56)
    assert (c.speed, c.acceleration, c.zone) == (0.25, None, 0.0)
    assert next(iter(parse_line("override puma 25"))).override == pytest.approx(0.25)
    assert next(iter(parse_line("profile trapezoid acceleration 90 deg/s^2"))).acceleration == (
        pytest.approx(math.pi / 2)
    )
    assert next(iter(parse_line("profile jerk"))).profile == "jerk"
    assert next(iter(parse_line("move joints relative puma 10 0 0 0 0 0 zone 5 mm"))).zone == 0.005
    assert isinstance(next(iter(parse_line("time detail"))), simc.CycleTime)
    assert isinstance(next(iter(parse_line("time"))), simc.SimTime)


@pytest.mark.parametrize(
    ("line", "error", "match"),
    [
        ("override puma 50 deg", CommandSyntaxError, "does not fit here; valid here: %"),
        ("move linear puma offset 0 0.1 0", ProgramError, "give the tool speed"),
        ("move linear puma offset 0 0.1 0 speed 2 deg/s", CommandSyntaxError, "m/s, mm/s"),
        ("profile smooth", CommandSyntaxError, "linear, trapezoid, quintic, jerk"),
        ("move circular puma to 0.3 0 0.5 speed 0.1", CommandSyntaxError, "via"),
    ],
)
def test_language_mistakes_say_what_is_valid(line, error, match):
    with pytest.raises(error, match=match):
        list(parse_line(line))


def test_a_session_runs_the_program_as_python_does():
    session = Session()
    for line in PROGRAM:
        for command in parse_line(line, session):
            session.execute(command)
    sim = Simulator(pp.build())
    python_program(sim)
    assert session.sim.sim_time == pytest.approx(sim.sim_time, rel=1e-9)
    ours = [(r["command"], r["limited_by"], r["zone_m"]) for r in sim.cycle_time()["commands"]]
    theirs = session.execute(simc.CycleTime())["commands"]
    assert ours == [(r["command"], r["limited_by"], r["zone_m"]) for r in theirs]
    # at half override: 0.125 m/s reached after 0.625 s at 0.2 m/s^2 (39 mm), then 41 mm
    # of cruise (0.33 s) to the zone: the acceleration set most of its time
    assert ours[-2] == ("move_linear", "tool acceleration", 0.02)


def test_the_client_drives_the_motion_commands_like_the_simulator():
    srv = Server(port=0)
    srv.serve_in_thread()
    try:
        with Client(port=srv.port, timeout=120) as c:
            c.example_cell("pick-place")
            c.simulate("path", dt=0.01)
            python_program(c)
            report = c.cycle_time()
            with pytest.raises(ProgramError, match=r"\(0, 1\]"):
                c.set_override("puma", 2.0)
            c.set_profile("trapezoid", acceleration=2.0)
            assert c.summary()["commands"] == report["commands"]
    finally:
        srv.stop()
    sim = Simulator(pp.build())
    python_program(sim)
    assert report["total_s"] == pytest.approx(sim.sim_time, rel=1e-9)
    assert len(report["commands"]) == 4


def test_run_prints_the_cycle_time_table(tmp_path, capsys):
    from workcell.cli import main

    script = tmp_path / "p.wcl"
    script.write_text("\n".join(PROGRAM) + "\n")
    assert main(["run", str(script), "--cycle-time"]) == 0
    out = capsys.readouterr().out
    assert "limited by" in out
    assert "move_circular" in out
    assert "total " in out


def test_demo_json_carries_the_cycle_time_records(capsys):
    import json

    from workcell.cli import main

    assert main(["demo", "joints", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    recs = out["commands"]
    assert [r["command"] for r in recs] == [
        "move_joints_relative",
        "move_joints_absolute",
        "move_joints_absolute",
    ]
    # eq. 4.27 per command: the largest joint motion (70, 40, 60 deg) over 0.3 rad/s
    expected = [math.radians(d) / 0.3 for d in (70, 40, 60)]
    assert [r["duration_s"] for r in recs] == pytest.approx(expected, rel=1e-12)
    assert {r["limited_by"] for r in recs} == {"robot speed"}
    assert sum(r["duration_s"] for r in recs) == pytest.approx(out["sim_time_s"], rel=1e-12)
