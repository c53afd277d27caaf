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
