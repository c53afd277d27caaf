"""Native geometry work in child processes: results come back, crashes, runaways, Ctrl-C
and a killed parent never take this process (or a child) along."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
import trimesh

from workcell import Model, decompose, limits, native, solids
from workcell.errors import (
    DegenerateError,
    GeometryError,
    LimitError,
    ModelError,
    NativeCrashError,
    ProgramError,
)
from workcell.robots.meshfile import primitive

# CoACD aborts the process (std::length_error) on a cylinder this thin: checked by hand
NEEDLE = trimesh.creation.cylinder(radius=1e-12, height=1.0, sections=32)


def torus(faces: int = 40_000) -> trimesh.Trimesh:
    """A torus of about ``faces`` triangles: seconds to tens of seconds of CoACD."""
    n = int(np.sqrt(faces / 2 / 2))
    return trimesh.creation.torus(0.1, 0.03, major_sections=2 * n, minor_sections=n)


def children_of(pid: int) -> list[int]:
    """Live processes whose parent is ``pid`` and that run workcell.native."""
    out = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            stat = (d / "stat").read_text()
            cmd = (d / "cmdline").read_bytes()
        except OSError:
            continue
        ppid = int(stat.rsplit(")", 1)[1].split()[1])
        state = stat.rsplit(")", 1)[1].split()[0]
        if ppid == pid and b"workcell.native" in cmd and state != "Z":
            out.append(int(d.name))
    return out


@contextmanager
def ctrl_c_after(seconds: float) -> Iterator[None]:
    """Ctrl-C (a KeyboardInterrupt in this thread) ``seconds`` s into the block; the
    block must take it within 10 s and leave no workcell.native child behind."""

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGALRM, interrupt)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    t0 = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    assert time.monotonic() - t0 < 10
    assert children_of(os.getpid()) == []


def test_a_job_comes_back_with_the_childs_result():
    box = trimesh.creation.box(extents=(0.3, 0.2, 0.1))
    job = native.Job("workcell.decompose:coacd_pieces", (box.vertices, box.faces, 0.05), "box")
    done = []
    [pieces] = native.run([job], on_done=lambda i, label, s: done.append((i, label)))
    assert done == [(0, "box")]
    assert len(pieces) == 1  # a box is convex: one piece, the box (CoACD's, within 1e-4)
    v, f = pieces[0]
    assert trimesh.Trimesh(v, f).volume == pytest.approx(0.3 * 0.2 * 0.1, rel=1e-4)
    assert children_of(os.getpid()) == []


def test_jobs_run_on_several_children_and_keep_their_order():
    boxes = [trimesh.creation.box(extents=(0.1 * k, 0.1, 0.1)) for k in (1, 2, 3)]
    jobs = [
        native.Job("workcell.decompose:coacd_pieces", (b.vertices, b.faces, 0.05), f"box {k}")
        for k, b in enumerate(boxes)
    ]
    got = native.run(jobs, workers=2)
    vols = [trimesh.Trimesh(*g[0]).volume for g in got]
    assert vols == pytest.approx([0.001, 0.002, 0.003], rel=1e-4)


def test_only_workcell_functions_run():
    with pytest.raises(ValueError, match="workcell functions only"):
        native.run([native.Job("os:system", ("true",))])


def test_a_native_abort_is_a_model_error_naming_the_work():
    t0 = time.monotonic()
    with pytest.raises(NativeCrashError, match=r"link 'needle'.*crashed.*SIGABRT") as info:
        decompose.decompose(NEEDLE, label="link 'needle'")
    assert isinstance(info.value, ModelError)
    assert "nothing was changed" in str(info.value)
    assert time.monotonic() - t0 < 60
    assert children_of(os.getpid()) == []
    # nothing was cached: the same call fails the same way
    assert not (decompose.cache_dir() / f"{decompose.cache_key(NEEDLE, 0.05)}.npz").exists()


def test_a_runaway_job_stops_at_the_time_limit():
    t0 = time.monotonic()
    with (
        limits.using(max_native_seconds=1.0),
        pytest.raises(LimitError, match=r"block 'torus'.*max_native_seconds = 1 s"),
    ):
        decompose.decompose(torus(), label="block 'torus'")
    assert time.monotonic() - t0 < 20  # the limit, plus starting and killing the child
    assert children_of(os.getpid()) == []


def test_a_job_over_its_own_bound_gives_the_callers_value_and_the_others_go_on():
    ring, box = torus(80_000), trimesh.creation.box(extents=(0.3, 0.2, 0.1))
    jobs = [
        native.Job("workcell.decompose:coacd_pieces", (m.vertices, m.faces, 0.05), label)
        for m, label in ((ring, "torus"), (box, "box"))
    ]
    done, late = [], []

    def over(i, label, seconds):
        late.append((i, label, seconds))
        return "too late"

    t0 = time.monotonic()
    got = native.run(
        jobs, workers=1, seconds=5.0, on_timeout=over, on_done=lambda *a: done.append(a[:2])
    )
    assert got[0] == "too late"
    assert late[0][:2] == (0, "torus")
    assert late[0][2] >= 5.0
    assert trimesh.Trimesh(*got[1][0]).volume == pytest.approx(0.006, rel=1e-4)  # a fresh child
    assert sorted(done) == [(0, "torus"), (1, "box")]
    assert time.monotonic() - t0 < 40
    assert children_of(os.getpid()) == []
    with pytest.raises(LimitError, match=r"torus: .* s is over the 1 s it may take"):
        native.run(jobs[:1], seconds=1.0)  # no on_timeout: an error, as for the limit
    assert children_of(os.getpid()) == []
    # a bound in CPU seconds: the child's own time (whatever else the machine runs)
    late.clear()
    assert native.run(jobs[:1], seconds=1.0, on_timeout=over, cpu=True) == ["too late"]
    assert late[0][2] >= 1.0  # wall seconds: at least the CPU seconds of one thread
    assert children_of(os.getpid()) == []


def test_out_of_memory_in_the_child_is_a_model_error():
    with (
        limits.using(max_native_bytes=400 << 20, max_native_seconds=60),
        pytest.raises(NativeCrashError, match=r"0\.391 GiB: limit max_native_bytes"),
    ):
        decompose.decompose(torus(200_000), label="block 'big torus'")
    assert children_of(os.getpid()) == []


def test_ctrl_c_stops_the_children_at_once():
    with ctrl_c_after(1.5):
        decompose.decompose(torus(), label="block 'torus'")


def test_children_die_with_a_killed_parent(tmp_path):
    script = textwrap.dedent(
        """
        import trimesh
        from workcell import decompose
        t = trimesh.creation.torus(0.1, 0.03, major_sections=280, minor_sections=140)
        decompose.decompose(t, label="block 'torus'")
        """
    )
    env = dict(os.environ, WORKCELL_COACD_CACHE=str(tmp_path / "cache"))
    parent = subprocess.Popen([sys.executable, "-c", script], env=env)
    try:
        deadline = time.monotonic() + 60
        while not children_of(parent.pid) and time.monotonic() < deadline:
            time.sleep(0.1)
        kids = children_of(parent.pid)
        assert kids, "the parent started no child in 60 s"
        time.sleep(0.5)
        parent.kill()
        parent.wait()
        deadline = time.monotonic() + 10
        alive = kids
        while alive and time.monotonic() < deadline:
            time.sleep(0.1)
            alive = [k for k in kids if Path(f"/proc/{k}").exists() and not _zombie(k)]
        assert alive == [], "a native child outlived its killed parent"
    finally:
        parent.kill()
        parent.wait()


def _zombie(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except OSError:
        return True


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda m: solids.sphere(m, "s", radius=1e-320), "radius 1e-320 m is too small"),
        (lambda m: solids.box(m, "b", size=(1.0, 1.0, 1e-320)), "z 1e-320 m is too small"),
        (
            lambda m: solids.cylinder(m, "c", radius=1e-12, height=1.0, n=16),
            "radius 1e-12 m is too small",
        ),
        (
            lambda m: solids.torus(m, "t", major_radius=0.1, minor_radius=1e-9, m=8, n=8),
            "minor_radius 1e-09 m is too small",
        ),
    ],
)
def test_degenerate_primitives_are_model_errors_and_change_nothing(make, match):
    m = Model()
    before = m.list()
    with pytest.raises(DegenerateError, match=match) as info:
        make(m)
    assert isinstance(info.value, ModelError)
    assert isinstance(info.value, GeometryError)
    assert "at least 1e-06 m" in str(info.value)
    assert m.list() == before


def test_a_micrometre_is_still_a_solid():
    m = Model()
    solids.box(m, "foil", size=(1.0, 1.0, 1e-6))
    assert m.properties("foil").volume == pytest.approx(1e-6, rel=1e-9)


@pytest.mark.parametrize(
    ("kind", "size"),
    [("cylinder", (1e-12, 1.0)), ("box", (1.0, 1e-320, 1.0)), ("sphere", (1e-320,))],
)
def test_degenerate_robot_file_shapes_are_model_errors(kind, size):
    with pytest.raises(DegenerateError, match=r"robot\.urdf: link 'a'.*too small"):
        primitive(kind, size=size, what="robot.urdf: link 'a' collision 1")


@pytest.mark.parametrize(
    ("limit", "error"),
    [
        ({"max_native_seconds": 1.0}, LimitError),
        ({"max_native_bytes": 400 << 20}, NativeCrashError),
    ],
)
def test_a_torus_that_would_take_the_server_down_is_an_error_reply(limit, error):
    """Issue 19's attack: create_torus then simulate ran CoACD inside the server until it
    aborted (std::bad_alloc). Now the child dies or is stopped; the server answers the
    client with a typed error and serves the next command."""
    from workcell.client import Client
    from workcell.program.server import Server

    before = limits.current()
    limits.set_limits(**limit)
    srv = Server(port=0)
    srv.serve_in_thread()
    try:
        with Client(port=srv.port, timeout=120) as c:
            c.call("new_cell", "c")
            c.call("create_torus", "ring", 0.1, 0.03, 282, 141)  # ~80,000 facets
            c.call("add_static", "ring", "ring")
            with pytest.raises(error, match=r"block 'ring'"):
                c.simulate()
            assert c.call("list")["block"] == ["ring"]  # the session goes on, unchanged
            with pytest.raises(ProgramError, match="simulat"):
                c.call("sim_time")  # no simulation was started
        assert children_of(os.getpid()) == []
    finally:
        srv.stop()
        limits.set_limits(before)
