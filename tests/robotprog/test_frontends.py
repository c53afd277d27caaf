"""Robot programs from every front end: the command line (export-program, run
--robot-program), the language (export program, run program) and the server through the
client (export_program, run_robot_program, file names kept inside the server's root).
Each runs the same program and reads back the same cycle time."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from workcell.cli import main
from workcell.client import Client
from workcell.errors import ProgramError
from workcell.program.interpreter import run_script
from workcell.program.server import Server
from workcell.program.session import Session

SCRIPT = """profile jerk
move joints absolute puma 10 -20 30 0 40 0
move linear puma offset 0 0 0.05 speed 100 mm/s zone 5 mm
move joints absolute puma home
"""


def _cycle(out: str) -> float:
    lines = [x for x in out.splitlines() if x.startswith("simulated cycle time")]
    return float(lines[-1].split()[3])


def test_command_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "pick.wcl").write_text(SCRIPT)
    cell = tmp_path / "pp.json"
    assert main(["export-cell", "pick-place", "--out", str(cell)]) == 0
    args = ["export-program", str(cell), "--program", str(tmp_path / "pick.wcl"), "--robot",
            "puma", "--language", "krl", "--out", str(tmp_path / "out"), "--signal", "gripper=4"]  # fmt: skip
    assert main(args) == 0
    wrote = _cycle(capsys.readouterr().out)
    assert (tmp_path / "out" / "pick.src").is_file()
    assert (tmp_path / "out" / "pick.dat").is_file()
    program = f"puma={tmp_path / 'out' / 'pick.src'}"
    assert main(["run", str(cell), "--robot-program", program, "--cycle-time"]) == 0
    out = capsys.readouterr().out
    assert _cycle(out) == pytest.approx(wrote, rel=1e-6)
    assert "move_linear" in out  # the cycle-time table
    # an unknown robot: status 2 and one line
    assert (
        main(["run", str(cell), "--robot-program", f"nobody={tmp_path / 'out' / 'pick.src'}"]) == 2
    )


def test_the_language(tmp_path: Path) -> None:
    (tmp_path / "t.wcl").write_text(
        "cell example pick-place\nsimulate path\n" + SCRIPT
        + "export program puma t.ls\nexport program puma t.txt language rapid\n"
        + "time\nsimulate stop\nsimulate path\nrun program puma t.ls\ntime\n"
    )  # fmt: skip
    printed: list[str] = []
    session = run_script(tmp_path / "t.wcl", out=printed.append)
    assert (tmp_path / "t.ls").is_file()
    assert "MODULE t" in (tmp_path / "t.txt").read_text()
    times = [float(x.split()[0]) for x in printed if re.fullmatch(r"[\d.]+ s", x)]
    assert times[-1] == pytest.approx(times[0], rel=1e-6)
    assert isinstance(session, Session)


def test_the_server_and_the_client(tmp_path: Path) -> None:
    server = Server(port=0, root=tmp_path)
    server.serve_in_thread()
    try:
        with Client(port=server.port, timeout=60) as remote:
            remote.example_cell("pick-place")
            remote.simulate("path", dt=0.01)
            remote.set_profile("jerk")
            remote.move_joints_absolute("puma", [0.1745, -0.349, 0.5236, 0.0, 0.698, 0.0])
            remote.move_linear("puma", {"offset": [0, 0, 0.05]}, speed=0.1)
            files = remote.export_program("puma", "prog/p.src", signals={"gripper": 2})
            assert [Path(f).name for f in files] == ["p.src", "p.dat"]
            t = remote.sim_time
            with pytest.raises(ProgramError, match=r"outside|inside|refused"):
                remote.export_program("puma", "../escape.src")
            remote.simulate("path", dt=0.01)
            done = remote.run_robot_program("puma", "prog/p.src")
            assert done["sim_time_s"] == pytest.approx(t, rel=1e-6)
        assert (tmp_path / "prog" / "p.dat").is_file()
        assert not (tmp_path.parent / "escape.src").exists()
    finally:
        server.stop()
