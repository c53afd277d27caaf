"""Devices, signals, programs and results in a rerun recording, read back with
rerun.chunk.RrdReader and checked against the run's own events: the beam turns red at the
frames its signal is true, the signal series steps at its changes, copies not yet made
and parts a sink removed are shrunk to nothing, the programs' activity and the results
are there."""

from __future__ import annotations

import numpy as np
import pytest
from test_rerun_log import read, read_static

from workcell import solids
from workcell.cell import Workcell
from workcell.record import record
from workcell.record.devices import BROKEN_RGBA, CLEAR_RGBA
from workcell.sim import Simulator
from workcell.spatial import translation


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    cell = Workcell("flow")
    solids.cube(cell.model, "cube", size=0.1)
    cell.add_movable("box", "cube", translation(0, 2, 0), density=500.0)
    cell.add_signal("done", False)
    cell.add_conveyor("belt", start=(0, 0, 0.5), end=(3, 0, 0.5), width=0.3, speed=0.5)
    cell.add_source("feeder", "box", at=(0.1, -0.05, 0.5), every=1.0, count=2)
    cell.add_sensor("beam", "beam", start=(1.0, -0.3, 0.55), end=(1.0, 0.3, 0.55))
    cell.add_sink("out", center=(2.0, 0, 0.55), size=(0.2, 0.4, 0.4))
    cell.add_robot("puma", "puma260", base=translation(0, -1.2, 0))
    sim = Simulator(cell, dt=0.01)
    q0 = sim.joints("puma")

    def robot(s):
        s.wait_signal("beam", True)
        s.move_joints_absolute("puma", q0 + np.radians([20, 0, 0, 0, 0, 0]))
        s.set_signal("done", True)

    def controller(s):
        s.wait_signal("done", True)
        s.wait(3.0)

    sim.run_programs({"puma": robot, "controller": controller})
    path = tmp_path_factory.mktemp("rec") / "flow.rrd"
    record(sim, path, fps=None)
    return sim, path


def _changes(sim, name):
    return [
        (e.frame, e.data["value"])
        for e in sim.events
        if e.kind == "signal" and e.data["signal"] == name
    ]


def test_the_beam_is_red_exactly_while_its_signal_is_true(run):
    sim, path = run
    frames, colours = read(path, "/world/sensors/beam", "LineStrips3D:colors")
    want = [(0, False), *_changes(sim, "beam")]
    assert [int(f) for f in frames] == [f for f, _ in want]
    rgba = lambda c: int.from_bytes(bytes((np.array(c) * 255).round().astype(np.uint8)), "big")  # noqa: E731
    expected = [rgba(BROKEN_RGBA if v else CLEAR_RGBA) for _, v in want]
    assert colours.reshape(-1).tolist() == expected
    strip = read_static(path, "/world/sensors/beam", "LineStrips3D:strips")
    assert np.allclose(strip.reshape(-1, 3), [[1.0, -0.3, 0.55], [1.0, 0.3, 0.55]], atol=1e-6)


def test_signal_series_step_at_their_changes(run):
    sim, path = run
    frames, values = read(path, "/signals/done", "Scalars:scalars")
    ((f, v),) = _changes(sim, "done")
    assert v is True
    assert values[frames < f].max() == 0.0
    assert values[frames > f].min() == 1.0
    assert frames[-1] == sim.frames - 1


def test_copies_are_shrunk_to_nothing_while_they_are_out_of_the_world(run):
    sim, path = run
    made = {e.data["part"]: e.frame for e in sim.events if e.kind == "source"}
    sunk = {e.data["part"]: e.frame for e in sim.events if e.kind == "sink"}
    assert set(made) == set(sunk) == {"box_1", "box_2"}
    for part in ("box_1", "box_2"):
        frames, scale = read(path, f"/world/bodies/{part}", "Transform3D:scale")
        here = (frames >= made[part]) & (frames < sunk[part])
        assert np.all(scale[here] == 1.0)
        assert np.all(scale[~here] == 0.0)
        _, t = read(path, f"/world/bodies/{part}", "Transform3D:translation")
        assert np.all(t[~here] == 0.0)  # at the origin: nothing far away to frame
    frames, scale = read(path, "/world/bodies/box", "Transform3D:scale")  # the pattern
    assert np.all(scale == 0.0)


def test_the_programs_and_the_results_are_recorded(run):
    _sim, path = run
    for name in ("puma", "controller"):
        _, level = read(path, f"/programs/{name}", "Scalars:scalars")
        assert set(np.unique(level)) <= {0.0, 1.0, 2.0}
        assert level.max() >= 1.0
    _, puma = read(path, "/programs/puma", "Scalars:scalars")
    assert puma.max() == 2.0  # it moved
    text = read_static(path, "/results/throughput", "TextDocument:text")
    assert "sink out: 2 parts" in str(text)
    assert read_static(path, "/results/gantt", "Image:buffer").size > 1000
