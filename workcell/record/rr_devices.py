"""The cell's devices, signals, programs and results in a rerun recording (for
:mod:`workcell.record.rerun_log`).

- ``/world/sensors/{name}``: a light beam as a line from its start to its end, a proximity
  sensor's ray to its range, a presence box; green while its signal is false, red while
  true, logged at frame 0 and at each change; ``/world/sinks/{name}``: a sink's box;
- ``/signals/{name}``: each signal's value over time (bools as 0 and 1), a step at each
  change;
- ``/programs/{name}``: per robot and controller program of ``run_programs``, its activity
  over time: 2 moving, 1 waiting, 0 idle (:func:`workcell.sim.throughput.activity`);
- ``/results/throughput`` (a text document: parts per hour, each robot's moving / waiting
  / idle fractions) and ``/results/gantt`` (the Gantt chart,
  :mod:`workcell.record.gantt`), both static.

Times on the recording's three timelines (see :mod:`workcell.record.rerun_log`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import rerun as rr
from numpy.typing import NDArray

from workcell.record.devices import BROKEN_RGBA, CLEAR_RGBA, SINK_RGBA, signal_history
from workcell.record.rr_scene import entity_part, index_columns

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["PROGRAMS", "RESULTS", "SENSORS", "SIGNALS", "has_logic", "log_devices"]

SENSORS = "/world/sensors"
SINKS = "/world/sinks"
SIGNALS = "/signals"
PROGRAMS = "/programs"
RESULTS = "/results"
_LEVEL = {"moving": 2.0, "waiting": 1.0}


def has_logic(sim: Simulator) -> bool:
    """Whether the run has devices or programs to show (module doc)."""
    cell = sim.cell
    devices = cell.signals or cell.sensors or cell.conveyors or cell.sources or cell.sinks
    return bool(devices) or any((e.data or {}).get("program_name") for e in sim.events)


def _rgba(v: tuple[float, ...]) -> NDArray[np.uint8]:
    return (np.array(v) * 255).round().astype(np.uint8)


def log_devices(
    rec: rr.RecordingStream,
    sim: Simulator,
    frame_of: NDArray[np.int64],
    wall_of: NDArray[np.float64],
    first: tuple[int, float, float],
    last: tuple[int, float, float],
) -> None:
    """Log the module doc's entities; ``frame_of`` and ``wall_of``: each event's frame and
    wall time; ``first``/``last``: (frame, sim_time, wall_time) of the run's ends."""
    events = sim.events
    history = signal_history(events)
    where = {id(e): k for k, e in enumerate(events)}
    changes: dict[str, list[tuple[int, float, float, Any]]] = {}
    for e in events:
        d = e.data or {}
        if e.kind == "signal" and "signal" in d:
            k = where[id(e)]
            changes.setdefault(d["signal"], []).append((frame_of[k], e.t, wall_of[k], d["value"]))
    _sensors(rec, sim, changes, first)
    for k in sim.cell.sinks.values():
        rec.log(
            f"{SINKS}/{entity_part(k.name)}",
            rr.Boxes3D(centers=[k.center], half_sizes=[k.size / 2], colors=[_rgba(SINK_RGBA)]),
            static=True,
        )
    logic = getattr(sim, "_logic", None)
    initial = dict(logic.initial) if logic is not None else {}
    for name in [*initial, *(n for n in history if n not in initial)]:
        rows, value = [(first[0], first[1], first[2], initial.get(name, 0))], initial.get(name, 0)
        for f, t, w, v in changes.get(name, []):
            rows += [(f, t, w, value), (f, t, w, v)]
            value = v
        rows.append((last[0], last[1], last[2], value))
        f, t, w, v = zip(*rows, strict=True)
        rec.send_columns(
            f"{SIGNALS}/{entity_part(name)}",
            index_columns(f, t, w),
            rr.Scalars.columns(scalars=np.array(v, dtype=np.float64)),
        )
    _programs(rec, sim, first, last)
    _results(rec, sim)


def _sensors(
    rec: rr.RecordingStream,
    sim: Simulator,
    changes: dict[str, list[tuple[int, float, float, Any]]],
    first: tuple[int, float, float],
) -> None:
    for s in sim.cell.sensors.values():
        ent = f"{SENSORS}/{entity_part(s.name)}"
        rows = [(first[0], first[1], first[2], False), *changes.get(s.name, [])]
        f, t, w, v = zip(*rows, strict=True)
        colours = np.array([_rgba(BROKEN_RGBA if x else CLEAR_RGBA) for x in v])
        idx = index_columns(f, t, w)
        p = s.params
        if s.kind == "presence":
            rec.log(ent, rr.Boxes3D(centers=[p["center"]], half_sizes=[p["size"] / 2]), static=True)
            rec.send_columns(ent, idx, rr.Boxes3D.columns(colors=colours))
            continue
        if s.kind == "beam":
            strip = [p["start"], p["end"]]
        else:
            strip = [p["origin"], p["origin"] + p["range"] * p["direction"]]
        rec.log(ent, rr.LineStrips3D([strip], radii=0.004), static=True)
        rec.send_columns(ent, idx, rr.LineStrips3D.columns(colors=colours))


def _programs(
    rec: rr.RecordingStream,
    sim: Simulator,
    first: tuple[int, float, float],
    last: tuple[int, float, float],
) -> None:
    from workcell.sim.throughput import activity

    times = sim.timeline.sim_times()
    walls = sim.timeline.wall_times()
    for name, spans in activity(sim.events, float(sim.sim_time)).items():
        points = [(first[1], 0.0)]
        for a, b, kind in spans:
            points += [(a, 0.0), (a, _LEVEL[kind]), (b, _LEVEL[kind]), (b, 0.0)]
        points.append((last[1], 0.0))
        t = np.array([p[0] for p in points])
        f = np.clip(np.searchsorted(times, t + 1e-9, side="right") - 1, 0, len(times) - 1)
        rec.send_columns(
            f"{PROGRAMS}/{entity_part(name)}",
            index_columns(f, t, walls[f]),
            rr.Scalars.columns(scalars=np.array([p[1] for p in points])),
        )


def _results(rec: rr.RecordingStream, sim: Simulator) -> None:
    from workcell.sim.throughput import format_throughput

    if not hasattr(sim, "throughput"):
        return
    text = format_throughput(sim.throughput())
    rec.log(f"{RESULTS}/throughput", rr.TextDocument(text), static=True)
    if sim.robots:
        from workcell.record.gantt import gantt_chart

        rec.log(f"{RESULTS}/gantt", rr.Image(gantt_chart(sim, width=1000)), static=True)
