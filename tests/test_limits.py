"""Issue 14, item 7: one budget of work limits for every front end.

Each attack of the issue is performed from Python (and, where it reaches the machine the
same way, from the command language and the server): it must be refused before the work
starts (in a fraction of a second, allocating nothing), with a LimitError naming the
limit and how to raise it, and change nothing. Raising the limit lets the work run."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from workcell import LimitError, Model, limits, solids
from workcell.errors import WorkcellError
from workcell.examples import thesis_joints
from workcell.limits import DEFAULTS, MAX_SIM_TIME, Limits
from workcell.program import Session
from workcell.program.interpreter import Interpreter
from workcell.sim import Simulator
from workcell.sim.timeline import Timeline


def refused(fn, limit: str, seconds: float = 1.0) -> LimitError:
    """Run ``fn``; it must raise LimitError naming ``limit`` and how to raise it, fast
    (``seconds`` of CPU time: the work done, whatever the machine's load)."""
    t0 = time.process_time()
    with pytest.raises(LimitError) as info:
        fn()
    assert time.process_time() - t0 < seconds
    message = str(info.value)
    assert f"over the limit {limit} = " in message
    assert f"workcell.limits.using({limit}=...)" in message
    assert f"--limit {limit}=N" in message
    return info.value


@pytest.fixture
def sim():
    return Simulator(thesis_joints.build(), dt=0.01, check_collisions=False)


def state(s: Simulator) -> tuple:
    return s.sim_time, s.frames, len(s.events), tuple(s.joints("puma"))


# ------------------------------------------------------------------ the API
def test_the_defaults_fit_the_machine_and_are_documented():
    assert DEFAULTS.max_facets * 1.7e3 < 1.5e9  # ~1.7 KB per facet while meshing
    assert DEFAULTS.max_frames_per_command * (2 + 30) * 8 < 1e9  # 30 joints: under 1 GB
    assert DEFAULTS.max_sim_time < MAX_SIM_TIME < 2**63 / 1e9  # int64 ns never overflow
    assert DEFAULTS.max_coordinate == 1e6
    doc = limits.__doc__ or ""
    for name in Limits.__dataclass_fields__:
        assert f"``{name}``" in doc


def test_limits_are_validated():
    with pytest.raises(LimitError, match="finite number > 0"):
        Limits(max_facets=0)
    with pytest.raises(LimitError, match="whole number"):
        Limits(max_frames=1.5)
    with pytest.raises(LimitError, match=r"at most 9\.2e"):
        Limits(max_sim_time=1e10)  # recordings would show NaT past 9.2e9 s
    with pytest.raises(LimitError, match="unknown limit max_facet;"):
        limits.set_limits(max_facet=1)
    assert limits.parse_limit("max_facets=2e6") == ("max_facets", 2e6)
    with pytest.raises(LimitError, match="NAME=VALUE"):
        limits.parse_limit("facets=3")


def test_using_is_local_to_the_block_and_the_thread_and_set_limits_is_global():
    seen = {}
    with limits.using(max_facets=7):
        assert limits.current().max_facets == 7
        with limits.using(max_frames=9):
            assert (limits.current().max_facets, limits.current().max_frames) == (7, 9)
        t = threading.Thread(target=lambda: seen.setdefault("other", limits.current()))
        t.start()
        t.join()
    assert seen["other"] == DEFAULTS  # another thread is not affected
    assert limits.current() == DEFAULTS
    try:
        limits.set_limits(max_facets=11)
        t = threading.Thread(target=lambda: seen.setdefault("global", limits.current()))
        t.start()
        t.join()
        assert seen["global"].max_facets == 11
    finally:
        limits.set_limits(DEFAULTS)
    assert limits.current() == DEFAULTS


# ------------------------------------------------------------------ facets
def test_a_10000_by_10000_sphere_is_refused_before_allocating():
    m = Model()
    e = refused(lambda: solids.sphere(m, "s", radius=1.0, m=10_000, n=10_000), "max_facets")
    assert "400,000,000 facets" in str(e)  # 12 GiB of transforms were allocated before
    refused(lambda: solids.cylinder(m, "c", radius=1.0, height=1.0, n=1_000_000), "max_facets")
    refused(
        lambda: solids.torus(m, "t", major_radius=2, minor_radius=1, m=2000, n=2000), "max_facets"
    )
    refused(lambda: solids.cone(m, "k", radius=1.0, height=1.0, n=10**6), "max_facets")
    assert m.list() == {"surface": [], "block": [], "object": [], "scene": []}


def test_sweeps_and_surfaces_count_their_facets():
    m = Model()
    ring = np.column_stack([np.cos(np.linspace(0, 6, 2000)), np.sin(np.linspace(0, 6, 2000))])
    with limits.using(max_facets=1000):
        refused(lambda: solids.extrude(m, "e", ring, height=1.0), "max_facets")
        refused(lambda: solids.revolve(m, "r", [(1, 0), (2, 0), (2, 1)], n=400), "max_facets")
        path = np.column_stack([np.zeros(400), np.zeros(400), np.linspace(0, 1, 400)])
        square = [(0, 0), (0.1, 0), (0.1, 0.1), (0, 0.1)]
        refused(lambda: solids.sweep(m, "w", square, path), "max_facets")
    assert m.list("block") == []


def test_instancing_cannot_multiply_a_mesh_past_the_limit():
    m = Model()
    solids.cylinder(m, "c", radius=1.0, height=1.0, n=1000)  # 3996 facets
    m.create("object", "o")
    m.attach_many("o", "c", np.repeat(np.eye(4)[None], 5, axis=0))
    with limits.using(max_facets=10_000):
        refused(lambda: m.world_mesh("o"), "max_facets")  # 19,980: counted, not meshed
        refused(lambda: m.properties("o"), "max_facets")
        refused(lambda: m.world_parts("o"), "max_facets")
        assert len(m.world_mesh("c").faces) == 3996  # a single one is fine


def test_raising_the_limit_lets_the_work_run():
    m = Model()
    with limits.using(max_facets=100):
        refused(lambda: solids.sphere(m, "s", radius=1.0, m=8, n=4), "max_facets")  # 128
    solids.sphere(m, "s", radius=1.0, m=8, n=4)
    assert len(m.world_mesh("s").faces) <= 4 * 8 * 4


# ------------------------------------------------------------------ frames, spill, clock
def test_a_line_sampled_every_nanometre_is_refused_before_any_work(sim):
    T = sim.tool_pose("puma")
    T[:3, 3] += [0.0, 0.0, -0.05]
    before = state(sim)
    e = refused(lambda: sim.move_straight_line("puma", T, step=1e-9), "max_frames_per_command")
    assert "0.05 m line sampled every 1e-09 m" in str(e)  # 6 GiB were allocated before
    refused(lambda: sim.move_straight_line("puma", T, step=1e-320), "max_frames_per_command")
    assert state(sim) == before


def test_a_tiny_dt_or_speed_is_refused_per_command(sim):
    fine = Simulator(thesis_joints.build(), dt=1e-7, check_collisions=False)
    before = state(fine)
    refused(lambda: fine.move_joints_relative("puma", np.radians([10, 0, 0, 0, 0, 0])),
            "max_frames_per_command")  # fmt: skip
    assert state(fine) == before
    sim.set_speed("puma", 1e-300)  # a valid speed; the move it makes would never end
    refused(
        lambda: sim.move_joints_relative("puma", [0.1, 0, 0, 0, 0, 0]), "max_frames_per_command"
    )
    coarse = Simulator(thesis_joints.build(), dt=1000.0, check_collisions=False)
    coarse.set_speed("puma", 1e-9)  # 0.1 rad at 1e-9 rad/s: 1e8 s in 1e5 frames of 1000 s
    refused(lambda: coarse.move_joints_relative("puma", [0.1, 0, 0, 0, 0, 0]), "max_sim_time")


def test_the_frames_of_a_simulation_are_bounded(sim):
    with limits.using(max_frames=200):
        sim.move_joints_relative("puma", np.radians([30, 0, 0, 0, 0, 0]))  # 175 frames
        before = state(sim)
        e = refused(lambda: sim.move_joints_relative("puma", np.radians([-30, 0, 0, 0, 0, 0])),
                    "max_frames")  # fmt: skip
        assert "the simulation's frames" in str(e)
        assert state(sim) == before


def test_the_spill_file_is_bounded(sim):
    small = Simulator(thesis_joints.build(), dt=1e-3, memory_limit=0, check_collisions=False)
    with limits.using(max_spill_bytes=100_000):
        refused(lambda: small.move_joints_relative("puma", np.radians([30, 0, 0, 0, 0, 0])),
                "max_spill_bytes")  # fmt: skip
        assert small.frames == 1
    tl = Timeline(3, chunk=4, memory_limit=0)
    with limits.using(max_spill_bytes=200):
        tl.extend(np.arange(5.0), np.arange(5.0), np.zeros((5, 3)))  # 200 bytes
        refused(lambda: tl.extend([9.0], [9.0], np.zeros((1, 3))), "max_spill_bytes")


def test_a_wait_past_the_clock_limit_is_refused(sim):
    before = state(sim)
    refused(lambda: sim.wait(1e300), "max_sim_time")  # it broke the clock before
    refused(lambda: sim.wait(1e10), "max_sim_time")  # it became NaT in recordings before
    assert state(sim) == before
    sim.wait(DEFAULTS.max_sim_time)
    assert sim.sim_time == DEFAULTS.max_sim_time


# ------------------------------------------------------------------ the other front ends
def test_the_language_and_the_server_obey_the_same_limits(tmp_path):
    from workcell.client import Client
    from workcell.program.server import Server

    session = Session(base_dir=tmp_path)
    interp = Interpreter(session, out=lambda text: None)
    with pytest.raises(LimitError, match="max_facets"):
        interp.run_line("create sphere s radius 1 slices 10000 faces 10000")
    srv = Server(port=0, root=tmp_path)
    srv.serve_in_thread()
    try:
        with Client(port=srv.port, timeout=30) as c:
            with pytest.raises(LimitError, match="max_facets"):  # the same type on the wire
                c.call("create_sphere", name="s", radius=1.0, m=10_000, n=10_000)
            c.example_cell(name="joints")
            c.simulate(mode="path", dt=0.01)
            with pytest.raises(LimitError, match="max_sim_time"):
                c.wait(1e300)
            assert c.sim_time == 0.0
    finally:
        srv.stop()
    assert issubclass(LimitError, WorkcellError)
