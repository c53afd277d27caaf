"""The cell's devices in pictures: sensors drawn over the cell, signals over time.

:func:`device_paths` gives the polylines :class:`~workcell.record.render.CellRenderer`
draws over a frame (:func:`~workcell.record.render.render_frame` and the contact sheets
draw them): a light beam as a line from its start to its end, green while nothing crosses
it and red while it is broken; a proximity sensor's ray to its range, the same colours;
a presence box's and a sink's edges (presence green or red, sinks blue-grey). A sensor's
state at a frame is its signal's value there, read from the timeline's ``signal`` events
(:func:`signal_history`).

Sizes m, times s.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from workcell.cell.workcell import Workcell
    from workcell.sim.timeline import Event

__all__ = [
    "BROKEN_RGBA",
    "CLEAR_RGBA",
    "SINK_RGBA",
    "box_edges",
    "device_paths",
    "signal_at",
    "signal_history",
]

CLEAR_RGBA = (0.15, 0.85, 0.25, 1.0)  # a beam nothing crosses
BROKEN_RGBA = (0.95, 0.10, 0.08, 1.0)  # a broken beam
SINK_RGBA = (0.35, 0.45, 0.60, 1.0)
Array = NDArray[np.float64]
_CORNERS = np.array(list(itertools.product((-0.5, 0.5), repeat=3)))


def signal_history(events: Sequence[Event]) -> dict[str, list[tuple[int, float, Any]]]:
    """Each signal's changes, in order: (frame, time s, value), from ``signal`` events."""
    out: dict[str, list[tuple[int, float, Any]]] = {}
    for e in events:
        d = e.data or {}
        if e.kind == "signal" and "signal" in d:
            out.setdefault(d["signal"], []).append((e.frame, e.t, d["value"]))
    return out


def signal_at(
    history: dict[str, list[tuple[int, float, Any]]], name: str, frame: int, initial: Any
) -> Any:
    """The value of signal ``name`` at timeline ``frame`` (``initial`` before any change)."""
    value = initial
    for f, _, v in history.get(name, []):
        if f > frame:
            break
        value = v
    return value


def box_edges(center: Array, size: Array) -> list[Array]:
    """The 12 edges (2 x 3 points each) of a box on the world axes."""
    P = np.asarray(center) + _CORNERS * np.asarray(size)
    edges = []
    for i, j in itertools.combinations(range(8), 2):
        if np.count_nonzero(_CORNERS[i] != _CORNERS[j]) == 1:
            edges.append(np.vstack([P[i], P[j]]))
    return edges


def device_paths(
    cell: Workcell, events: Sequence[Event] = (), frame: int = 0
) -> list[tuple[Array, tuple[float, ...]]]:
    """Polylines (points (k, 3) m, RGBA) of ``cell``'s sensors and sinks at timeline
    ``frame`` of a run with ``events`` (module doc); none for a cell without them."""
    if not (cell.sensors or cell.sinks):
        return []
    history = signal_history(events)
    out: list[tuple[Array, tuple[float, ...]]] = []
    for s in cell.sensors.values():
        on = bool(signal_at(history, s.name, frame, False))
        rgba = BROKEN_RGBA if on else CLEAR_RGBA
        p = s.params
        if s.kind == "beam":
            out.append((np.vstack([p["start"], p["end"]]), rgba))
        elif s.kind == "proximity":
            out.append((np.vstack([p["origin"], p["origin"] + p["range"] * p["direction"]]), rgba))
        else:
            out.extend((e, rgba) for e in box_edges(p["center"], p["size"]))
    for k in cell.sinks.values():
        out.extend((e, SINK_RGBA) for e in box_edges(k.center, k.size))
    return out
