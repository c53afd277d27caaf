"""Issue 14, item 5: the atomic writer and every writer that uses it, attacked.

Symbolic links, FIFOs and private files at the target; SIGTERM in the middle of a
write; missing folders, files in the way, names too long, read-only places and a full
disk, for every writer (model, cell, export, robot export, mesh, recording, PNG,
contact sheet, MP4): each failure is the writer's WorkcellError naming the path, found
before the expensive work where possible, and never leaves a temp file."""

from __future__ import annotations

import errno
import os
import signal
import socket
import stat
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from workcell import Model, solids
from workcell.cell import Workcell, export_cell
from workcell.errors import ModelError, RecordError, RenderError, WorkcellError
from workcell.examples import thesis_joints
from workcell.files import atomic_path, atomic_write_text
from workcell.program import Session
from workcell.program.commands import WorldMesh
from workcell.robots import puma260
from workcell.robots.mjcf import export_robot
from workcell.sim import Simulator


def leftovers(folder: Path) -> list[str]:
    """Temp files of the atomic writer (hidden names) left in ``folder``."""
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


# ------------------------------------------------------------------ what is at the target
def test_a_symbolic_link_is_written_through_to_its_target(tmp_path):
    target = tmp_path / "real.json"
    target.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    atomic_write_text(link, "new")
    assert link.is_symlink()  # the link stays a link
    assert target.read_text() == "new"  # and its target got the data
    dangling = tmp_path / "dangling.json"
    dangling.symlink_to(tmp_path / "created.json")
    atomic_write_text(dangling, "x")
    assert (tmp_path / "created.json").read_text() == "x"
    assert leftovers(tmp_path) == []


def test_targets_that_are_not_regular_files_are_refused_and_left_alone(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    sock_path = tmp_path / "sock"
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(sock_path))
    folder = tmp_path / "folder"
    folder.mkdir()
    link_to_fifo = tmp_path / "link"
    link_to_fifo.symlink_to(fifo)
    m = Model()
    for path, kind in [
        (fifo, "a FIFO"),
        (sock_path, "a socket"),
        (folder, "a folder"),
        (link_to_fifo, "a FIFO"),
    ]:
        with pytest.raises(ModelError, match=f"it is {kind}, not a regular file"):
            m.save(path)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert stat.S_ISSOCK(os.lstat(sock_path).st_mode)
    assert folder.is_dir()
    sock.close()
    assert leftovers(tmp_path) == []


def test_the_mode_of_the_file_replaced_is_kept(tmp_path):
    m = Model()
    for mode in (0o600, 0o640, 0o444):
        p = tmp_path / f"m{mode:o}.json"
        p.write_text("x")
        p.chmod(mode)
        m.save(p)
        assert stat.S_IMODE(p.stat().st_mode) == mode
        assert p.read_text().startswith("{")
    umask = os.umask(0o022)
    try:
        m.save(tmp_path / "new.json")
    finally:
        os.umask(umask)
    assert stat.S_IMODE((tmp_path / "new.json").stat().st_mode) == 0o644


@pytest.mark.slow
def test_sigterm_in_the_middle_of_a_write_leaves_no_temp_file(tmp_path):
    target = tmp_path / "out.bin"
    target.write_bytes(b"old")
    code = textwrap.dedent(
        f"""
        import time
        from workcell.files import atomic_path
        with atomic_path({str(target)!r}) as tmp:
            open(tmp, "wb").write(b"half" * 1000)
            print("writing", flush=True)
            time.sleep(60)
        """
    )
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline() == "writing\n"
    assert len(leftovers(tmp_path)) == 1  # the temp file exists now
    p.send_signal(signal.SIGTERM)
    assert p.wait(30) == -signal.SIGTERM  # it still dies of SIGTERM
    assert leftovers(tmp_path) == []
    assert target.read_bytes() == b"old"


# ------------------------------------------------------------------ every writer, every failure
@pytest.fixture(scope="module")
def sim():
    s = Simulator(thesis_joints.build(), dt=0.05, check_collisions=False)
    s.move_joints_relative("puma", np.radians([10, 0, 0, 0, 0, 0]))
    return s


def writers(sim):
    """name -> (write(path), its error class, the file ending it takes); folder writers
    take a folder."""
    model = Model()
    solids.cube(model, "c", size=0.1)
    cell = Workcell("w")
    solids.cube(cell.model, "c", size=0.1)
    cell.add_static("c1", "c")
    session = Session(model)
    from workcell.record import contact_sheet, record, save_mp4, save_png

    return {
        "model": (model.save, ModelError, ".json"),
        "cell": (cell.save, ModelError, ".json"),
        "mesh": (lambda p: session.execute(WorldMesh("c", str(p))), ModelError, ".stl"),
        "export": (lambda p: export_cell(cell, p), ModelError, ""),
        "robot export": (lambda p: export_robot(puma260(), p), ModelError, ""),
        "record": (lambda p: record(sim, p), RecordError, ".rrd"),
        "png": (lambda p: save_png(np.zeros((4, 4, 3), np.uint8), p), RenderError, ".png"),
        "contact sheet": (lambda p: contact_sheet(sim, p), RenderError, ".png"),
        "mp4": (lambda p: save_mp4(sim, p), RenderError, ".mp4"),
    }


def bad_places(tmp_path: Path, ending: str) -> dict[str, tuple[Path, str]]:
    (tmp_path / "afile").write_text("x")
    places = {
        "not a folder": (tmp_path / "afile" / f"x{ending}", "not a folder"),
        "name too long": (tmp_path / ("n" * 300 + ending), "too long"),
    }
    if ending:  # folder writers create missing folders
        places["missing folder"] = (tmp_path / "nope" / f"x{ending}", "does not exist")
    if os.path.isdir("/sys") and not os.access("/sys", os.W_OK):
        places["read-only"] = (Path("/sys") / f"workcell-x{ending}", "permission denied")
    elif os.geteuid() != 0:
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o500)
        places["read-only"] = (ro / f"x{ending}", "permission denied")
    return places


@pytest.mark.parametrize(
    "writer",
    ["model", "cell", "mesh", "export", "robot export", "record", "png", "contact sheet", "mp4"],
)
def test_every_writer_turns_file_system_failures_into_its_error(sim, tmp_path, writer):
    write, error, ending = writers(sim)[writer]
    for case, (path, words) in bad_places(tmp_path, ending).items():
        with pytest.raises(error) as info:
            write(path)
        message = str(info.value)
        assert str(path) in message, (case, message)
        assert words in message, (case, message)
    assert leftovers(tmp_path) == []


@pytest.mark.parametrize("writer", ["model", "cell", "mesh", "export", "record", "png"])
def test_a_full_disk_is_an_error_naming_the_path_and_leaves_nothing(
    sim, tmp_path, writer, monkeypatch
):
    write, error, ending = writers(sim)[writer]

    def full(fd: int) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", full)  # the data does not fit: the flush fails
    path = tmp_path / f"out{ending}"
    with pytest.raises(error, match="no space left on device") as info:
        write(path)
    assert str(path) in str(info.value)
    assert not path.exists() or path.is_dir()
    assert leftovers(tmp_path) == []
    if path.is_dir():
        assert all(not p.name.startswith(".") for p in path.rglob("*"))


def test_record_to_an_unwritable_place_fails_before_the_work(sim, tmp_path, monkeypatch):
    from workcell.record import rerun_log

    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("the recording was computed")

    monkeypatch.setattr(rerun_log, "log_timeline", never)
    (tmp_path / "afile").write_text("x")
    with pytest.raises(RecordError, match="not a folder"):
        rerun_log.record(sim, tmp_path / "afile" / "x.rrd")


@pytest.mark.parametrize(
    "option",
    [["--save", "afile/x.rrd"], ["--render", "afile/x.png"], ["--mjcf", "afile/out"]],
)
def test_the_cli_refuses_an_unwritable_output_before_simulating(
    tmp_path, monkeypatch, capsys, option
):
    from workcell import cli

    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("the simulation ran")

    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("x")
    monkeypatch.setattr(thesis_joints, "run", never)
    assert cli.main(["demo", "joints", *option]) == 2
    err = capsys.readouterr().err
    assert err.startswith("workcell: ")
    assert "afile" in err
    assert len(err.splitlines()) == 1


def test_writer_errors_are_workcell_errors_with_the_same_message_shape(tmp_path):
    """The shared writer gives every caller the same wording (the study stream reuses it)."""
    with (
        pytest.raises(WorkcellError, match=r"cannot write '.*nope/x': folder '.*nope' does not"),
        atomic_path(tmp_path / "nope" / "x"),
    ):
        pass


def test_leaves_root_refuses_links_out_and_hard_links_and_keeps_the_rest(tmp_path):
    from workcell.files import leaves_root

    root, outside = tmp_path / "root", tmp_path / "outside"
    (root / "sub").mkdir(parents=True)
    outside.mkdir()
    (outside / "secret.txt").write_text("secret")
    (root / "plain.txt").write_text("mine")
    (root / "out").symlink_to(outside / "secret.txt")
    (root / "in").symlink_to(root / "plain.txt")
    os.link(outside / "secret.txt", root / "hard.txt")
    assert leaves_root(root / "plain.txt", root) is None
    assert leaves_root(root / "in", root) is None  # a symbolic link that stays inside
    assert leaves_root(root / "sub" / "new.txt", root) is None  # not there yet: may be written
    assert leaves_root(root / "sub", root) is None  # a folder (its entries are checked each)
    assert "outside the root folder" in leaves_root(root / "out", root)
    assert "outside the root folder" in leaves_root(root / ".." / "outside" / "x", root)
    why = leaves_root(root / "hard.txt", root)
    assert "2 hard links" in why
    assert "secret" not in why
    os.unlink(outside / "secret.txt")  # the last other name gone: one link, an ordinary file
    assert leaves_root(root / "hard.txt", root) is None
