"""The ``workcell`` command itself: --version, and subcommands that write only what is asked."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

import workcell
from workcell.cli import main


def test_version_is_the_package_version(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"workcell {workcell.__version__}"
    from importlib.metadata import version

    assert workcell.__version__ == version("workcell")  # pyproject and the package agree


def test_demo_solids_writes_nothing_unasked(tmp_path):
    """Without --save it neither writes /tmp/thesis_solids.json nor anything in the cwd."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = {**os.environ, "TMPDIR": str(tmp)}
    run = subprocess.run(
        [sys.executable, "-m", "workcell.cli", "demo", "solids", "--json"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    data = json.loads(run.stdout)
    assert data["round_trip_exact"] is True
    assert data["model_file"] is None
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tmp"]
    assert list(tmp.iterdir()) == []
    assert not (Path(tempfile.gettempdir()) / "thesis_solids.json").exists()


def test_joint_by_joint_demo_prints_both_clocks(capsys):
    """The thesis's clock (eq. 4.27: 170 deg at 0.3 rad/s) beside frames x dt, each named."""
    import math
    import re

    assert main(["demo", "joints", "--mode", "joint-by-joint", "--json"]) == 0
    frames = json.loads(capsys.readouterr().out)["frames"]
    assert main(["demo", "joints", "--mode", "joint-by-joint"]) == 0
    text = capsys.readouterr().out
    thesis = re.search(r"sim time \(thesis clock\)\s+([\d.]+) s", text)
    steps = re.search(r"frames x dt\s+([\d.]+) s", text)
    assert thesis, text
    assert steps, text
    assert float(thesis.group(1)) == pytest.approx(math.radians(170) / 0.3, abs=1e-3)
    assert float(steps.group(1)) == pytest.approx((frames - 1) * 0.01, abs=1e-3)
    assert float(steps.group(1)) > float(thesis.group(1))  # one joint at a time takes longer


def test_help_explains_the_joint_by_joint_clock(capsys):
    with pytest.raises(SystemExit):
        main(["demo", "--help"])
    assert "thesis's clock" in " ".join(capsys.readouterr().out.split())
    from workcell.program.language import help_text

    assert "thesis's clock" in " ".join(help_text(("simulate",)).split())


def test_recordings_keep_60_frames_per_simulated_second_unless_asked(tmp_path, capsys):
    """A 1 kHz run: --save keeps about 60 frames a second (and every event's frame);
    --record-fps 0 keeps them all."""
    import math

    argv = ["demo", "joints", "--dt", "0.001", "--json", "--save"]
    assert main([*argv, str(tmp_path / "slim.rrd")]) == 0
    slim = json.loads(capsys.readouterr().out)
    assert main([*argv, str(tmp_path / "full.rrd"), "--record-fps", "0"]) == 0
    full = json.loads(capsys.readouterr().out)
    assert full["rrd_frames"] == full["frames"] > 9000
    T = slim["sim_time_s"]
    assert (
        math.floor(T * 60) + 1 <= slim["rrd_frames"] <= math.floor(T * 60) + 2 + len(slim["events"])
    )
    assert slim["rrd_bytes"] < full["rrd_bytes"] / 8
