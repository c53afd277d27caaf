"""``workcell shell`` and ``workcell run``: lines from a pipe, the prompt_toolkit prompt,
completion, history, and the subcommands' registration."""

from __future__ import annotations

import argparse
import io
import math
import subprocess
import sys
from pathlib import Path

import pytest
from program_helpers import EXAMPLE1_SIM_TIME

from workcell.program import Session
from workcell.program.cli import register
from workcell.program.shell import PROMPT, run_shell

ASSETS = Path(__file__).resolve().parents[2] / "assets"


def shell(text: str, session: Session | None = None, **kw) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    rc = run_shell(session, stdin=io.StringIO(text), stdout=out, stderr=err, **kw)
    return rc, out.getvalue(), err.getvalue()


def test_lines_from_a_pipe_run_in_order_and_print_results():
    rc, out, err = shell("create cube c size 2\nproperties c\nmesh c\n")
    assert rc == 0
    assert err == ""
    assert "volume 8 m^3" in out
    assert "12 faces" in out


def test_an_error_is_reported_and_the_shell_goes_on_with_exit_status_1():
    s = Session()
    rc, _out, err = shell("create cube c size 1\nremove nothing\ncreate cube d size 1\n", s)
    assert rc == 1
    assert err.startswith("CommandSyntaxError: column 8: unknown entity 'nothing'")
    assert s.model.exists("d")  # the line after the error ran


def test_quit_ends_the_shell_and_echo_makes_a_transcript():
    s = Session()
    rc, out, _ = shell("create cube a size 1\nquit\ncreate cube b size 1\n", s, echo=True)
    assert rc == 0
    assert s.model.exists("a")
    assert not s.model.exists("b")
    assert out.splitlines()[:2] == [f"{PROMPT}create cube a size 1", f"{PROMPT}quit"]


def test_help_in_the_shell_says_the_units():
    _, out, _ = shell("help wait\n")
    assert "wait T [s|ms]" in out
    assert "degrees" in out
    assert "metres" in out


def test_the_prompt_toolkit_shell_runs_typed_lines_and_keeps_history(tmp_path):
    from prompt_toolkit.application import create_app_session
    from prompt_toolkit.input import create_pipe_input
    from prompt_toolkit.output import DummyOutput

    s = Session()
    out, err = io.StringIO(), io.StringIO()
    history = tmp_path / "history"
    with create_pipe_input() as inp:
        inp.send_text("create cube c size 0.5\nproperties c\nfrob\n")
        inp.close()
        with create_app_session(input=inp, output=DummyOutput()):
            rc = run_shell(s, stdout=out, stderr=err, history=history, interactive=True)
    assert rc == 1
    assert "volume 0.125 m^3" in out.getvalue()
    assert "unexpected 'frob'" in err.getvalue()
    assert "+properties c" in history.read_text()


def test_the_completer_offers_keywords_and_names():
    from prompt_toolkit.completion import CompleteEvent
    from prompt_toolkit.document import Document

    from workcell.program.completion import WorkcellCompleter
    from workcell.program.solidcommands import CreateCube

    s = Session()
    s.execute(CreateCube("gear", 1.0))
    c = WorkcellCompleter(s)
    got = list(c.get_completions(Document("properties g"), CompleteEvent()))
    assert sorted((x.text, x.start_position) for x in got) == [("gear", -1), ("gear.square", -1)]
    got = list(c.get_completions(Document("mov"), CompleteEvent()))
    assert [x.text for x in got] == ["move"]


def test_register_adds_shell_run_and_serve():
    p = argparse.ArgumentParser(prog="workcell")
    register(p.add_subparsers(dest="command", required=True))
    a = p.parse_args(["run", "x.wcl", "--echo"])
    assert a.script == "x.wcl"
    assert a.echo
    assert callable(a.func)
    a = p.parse_args(["serve", "--port", "0", "--example", "joints", "--mode", "path"])
    assert (a.host, a.port, a.example, a.mode, a.token) == ("127.0.0.1", 0, "joints", "path", None)
    a = p.parse_args(["shell", "--cell", "c.json", "--history", "h"])
    assert a.cell == "c.json"
    assert callable(a.func)
    with pytest.raises(SystemExit):
        p.parse_args(["serve", "--cell", "c.json", "--example", "joints"])


def cli(*args: str, stdin: str = "") -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "workcell.program.cli", *args],
        input=stdin,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_workcell_run_prints_results_and_the_summary():
    r = cli("run", str(ASSETS / "thesis_example1.wcl"), "--summary")
    assert r.returncode == 0, r.stderr
    import json

    summary = json.loads(r.stdout.splitlines()[-1])
    assert summary["sim_time_s"] == pytest.approx(EXAMPLE1_SIM_TIME, abs=1e-9)


def test_workcell_run_stops_at_an_error_with_status_2(tmp_path):
    p = tmp_path / "bad.wcl"
    p.write_text("create cube a size 1\ncreate cube a size 1\n")
    r = cli("run", str(p))
    assert r.returncode == 2
    assert r.stderr.startswith(f"workcell: ModelError: {p}:2: ")


def test_workcell_shell_reads_a_pipe():
    r = cli("shell", "--example", "joints", "--mode", "path", stdin="speed puma 0.3 rad/s\n"
            "move joints relative puma -70 -10 10 30 -20 -10\ntime\n")  # fmt: skip
    assert r.returncode == 0, r.stderr
    # one move: joint 1 moves most, 70 deg at 0.3 rad/s (eq. 4.27); printed to 6 digits
    assert float(r.stdout.split()[0]) == pytest.approx(math.radians(70) / 0.3, rel=1e-5)


def test_read_back_is_in_degrees_and_metres_and_can_be_typed_in_again():
    import numpy as np

    from workcell import spatial
    from workcell.examples import thesis_joints

    _, out, err = shell("cell example joints\nsimulate\njoints puma\npose puma\n")
    assert err == ""
    lines = out.splitlines()
    assert lines[2] == "(0, 0, -90, 0, 90, 0) deg"
    pos, rpy = (
        [float(x) for x in part.split("(")[1].split(")")[0].split(",")]
        for part in lines[3].split(" m, rpy ")
    )
    T = thesis_joints.build().robots["puma"].tool_pose()  # forward kinematics
    assert np.allclose(pos, T[:3, 3], atol=1e-6)
    R = spatial.srt(rotation=np.radians(rpy))[:3, :3]  # the language's rpy
    assert np.allclose(R, T[:3, :3], atol=1e-5)


def test_exit_leaves_like_quit():
    s = Session()
    rc, _, err = shell("create cube a size 1\nexit\ncreate cube b size 1\n", s)
    assert (rc, err) == (0, "")
    assert s.model.exists("a")
    assert not s.model.exists("b")


def test_clear_is_its_own_command_not_a_prefix_of_clearance(tmp_path):
    """'clear' clears a terminal's screen (and nothing in a pipe); 'clea' is ambiguous."""
    from prompt_toolkit.application import create_app_session
    from prompt_toolkit.data_structures import Size
    from prompt_toolkit.input import create_pipe_input
    from prompt_toolkit.output.vt100 import Vt100_Output

    rc, out, err = shell("clear\n")
    assert (rc, out, err) == (0, "", "")
    rc, _, err = shell("clea\n")
    assert rc == 1
    assert "'clea' is ambiguous" in err
    assert "clear" in err
    assert "clearance" in err
    screen = io.StringIO()
    terminal = Vt100_Output(screen, lambda: Size(rows=24, columns=80), term="xterm")
    with create_pipe_input() as inp:
        inp.send_text("clear\nexit\n")
        inp.close()
        with create_app_session(input=inp, output=terminal):
            rc = run_shell(
                Session(),
                stdout=io.StringIO(),
                stderr=io.StringIO(),
                history=tmp_path / "h",
                interactive=True,
            )
    assert rc == 0
    assert "\x1b[2J" in screen.getvalue()  # the VT100 erase-screen sequence


def test_names_made_earlier_on_a_line_are_known_to_the_commands_after_them():
    s = Session()
    rc, out, err = shell("create cube c1 size 40 mm; properties c1\n", s)
    assert (rc, err) == (0, "")
    assert "volume 6.4e-05 m^3" in out


def test_errors_quote_values_in_the_units_people_type():
    """The shell's user types degrees and millimetres: a refused value comes back in them."""
    s = Session()
    lines = [
        "cell example pick-place",
        "simulate",
        "speed puma 600",  # deg/s, over the fastest joint's 577 deg/s
        "close gripper puma angle -5",
        "move straight puma offset 0 0 -0.05 step -2 mm",
        "move joints absolute puma 0 0 -90 0 90",
        "simulate stop",
        "add robot r2 puma260 q 90 0",
    ]
    rc, _, err = shell("\n".join(lines) + "\n", s)
    assert rc == 1
    errors = err.splitlines()
    assert len(errors) == 5, err
    assert "got 600 deg/s" in errors[0]
    assert "577 deg/s" in errors[0]
    assert "got -5 deg" in errors[1]
    assert "got -2 mm" in errors[2]
    assert "rad" not in errors[3]
    assert "1.57" not in errors[4]  # not the 90 deg typed, in radians
    assert "got 2 value(s)" in errors[4]
    for e in errors:  # never a bare radian value
        assert "rad" not in e or "deg" in e, e
