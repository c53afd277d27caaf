"""Issue 14, item 9: Ctrl-C (SIGINT) and SIGTERM in the middle of a CLI command.

A real ``workcell run --save`` process is interrupted at two moments it announces
itself: while simulating (after the script saved a marker file) and while writing the
recording (once its temp file exists). Ctrl-C must print one line, not a traceback, and
leave no file under the final name and no temp file; SIGTERM must leave no temp file."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

SCRIPT = """\
cell new thesis_joints
add robot puma puma260 q 0 0 -90 0 90 0
cell save started.json
simulate path dt {dt}
speed puma 0.3 rad/s
move joints relative puma -70 -10 10 30 -20 -10
move joints absolute puma -60 0 -70 0 90 30
move joints absolute puma 0 0 -90 0 90 0
"""


def start(tmp_path: Path, dt: float) -> subprocess.Popen:
    (tmp_path / "prog.wcl").write_text(SCRIPT.format(dt=dt))
    return subprocess.Popen(
        [sys.executable, "-m", "workcell.cli", "run", "prog.wcl", "--save", "run.rrd"],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")},
    )


def wait_for(p: subprocess.Popen, found, what: str, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while not found():
        if p.poll() is not None:
            raise AssertionError(f"the command ended before {what}: {p.communicate()}")
        if time.monotonic() > deadline:
            p.kill()
            raise AssertionError(f"no {what} within {timeout} s")
        time.sleep(0.005)


def loaded(pid: int, library: str) -> bool:
    """Whether process ``pid`` has mapped a shared library whose path names ``library``."""
    try:
        return f"/{library}/" in Path(f"/proc/{pid}/maps").read_text()
    except OSError:
        return False


def temp_files(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def writing(folder: Path) -> bool:
    """The recording's temp file exists (the writing has begun)."""
    return any(n.startswith(".run.rrd.") and n.endswith(".tmp") for n in temp_files(folder))


def test_ctrl_c_while_simulating_prints_one_line_and_writes_nothing(tmp_path):
    p = start(tmp_path, dt=2e-5)  # ~500,000 frames: seconds of work
    wait_for(p, (tmp_path / "started.json").exists, "start of the simulation")
    time.sleep(0.3)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert err == "workcell: interrupted\n"  # one line, no traceback
    assert not (tmp_path / "run.rrd").exists()
    assert temp_files(tmp_path) == []


def test_ctrl_c_while_writing_the_recording_leaves_no_partial_file(tmp_path):
    p = start(tmp_path, dt=1e-4)

    wait_for(p, lambda: writing(tmp_path), "the recording's temp file")
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    if p.returncode == 0:  # the write finished before the signal landed: a whole file
        assert (tmp_path / "run.rrd").stat().st_size > 0
    else:
        assert p.returncode == 130, err
        assert err == "workcell: interrupted\n"  # one line, no traceback
        assert not (tmp_path / "run.rrd").exists()
    assert temp_files(tmp_path) == []


def test_sigterm_while_writing_the_recording_leaves_no_temp_file(tmp_path):
    p = start(tmp_path, dt=1e-4)
    wait_for(p, lambda: writing(tmp_path), "the recording's temp file")
    p.send_signal(signal.SIGTERM)
    p.communicate(timeout=60)
    assert p.returncode in (-signal.SIGTERM, 0)
    assert temp_files(tmp_path) == []
    if p.returncode != 0:
        assert not (tmp_path / "run.rrd").exists()


def test_ctrl_c_while_the_command_is_still_starting_prints_one_line(tmp_path):
    # `workcell robots` imports the simulator stack (MuJoCo, trimesh, ...) for about a
    # second before it prints anything: Ctrl-C once numpy is loaded lands in those
    # imports (a fixed delay after start did not: on a loaded machine Python could still
    # be starting up, before the command line's own handling)
    p = subprocess.Popen(
        [sys.executable, "-m", "workcell.cli", "robots"],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # as from a terminal: Ctrl-C not ignored (a background job of a script inherits
        # SIGINT ignored, and Python then keeps ignoring it)
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    wait_for(p, lambda: loaded(p.pid, "numpy"), "the heavy imports")
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=60)
    assert (p.returncode, out, err) == (130, "", "workcell: interrupted\n")
