"""The cell's devices as JSON (:mod:`workcell.cell.cell_json` reads and writes a cell's
file with them): :func:`devices_to_dict` and :func:`device_sections`. Lengths m, speeds
m/s, times s.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from workcell.cell.device_types import Sensor

if TYPE_CHECKING:
    from workcell.cell.devices import DeviceItems

__all__ = ["device_sections", "devices_to_dict"]


def devices_to_dict(cell: DeviceItems) -> dict[str, list[dict[str, Any]]]:
    """The devices as JSON-able lists (lengths m, speeds m/s, times s); a kind the cell
    has none of is left out."""

    def plain(v: Any) -> Any:
        return v.tolist() if isinstance(v, np.ndarray) else v

    out = {
        "signals": [{"name": s.name, "initial": s.initial} for s in cell.signals.values()],
        "sensors": [
            {
                "name": s.name,
                "kind": s.kind,
                "robots": s.robots,
                **{k: plain(v) for k, v in s.params.items()},
            }
            for s in cell.sensors.values()
        ],
        "conveyors": [
            {
                "name": c.name,
                "start": c.start.tolist(),
                "end": c.end.tolist(),
                "width": c.width,
                "speed": c.speed,
                "run_signal": c.run_signal,
            }
            for c in cell.conveyors.values()
        ],
        "sources": [
            {
                "name": s.name,
                "part": s.part,
                "at": s.at.tolist(),
                "every": s.every,
                "count": s.count,
                "on_signal": s.on_signal,
            }
            for s in cell.sources.values()
        ],
        "sinks": [
            {"name": s.name, "center": s.center.tolist(), "size": s.size.tolist()}
            for s in cell.sinks.values()
        ],
    }
    return {k: v for k, v in out.items() if v}  # a cell without devices: as before


def device_sections(cell: DeviceItems) -> list[tuple[str, Callable[[dict[str, Any]], object]]]:
    """(JSON key, how to add one entry) for each kind of device of :func:`devices_to_dict`,
    signals first (the others name them): :mod:`workcell.cell.cell_json` reads them."""

    def sensor(e: dict[str, Any]) -> Sensor:
        params = {k: v for k, v in e.items() if k not in ("name", "kind", "robots")}
        return cell.add_sensor(e["name"], e["kind"], robots=e.get("robots", False), **params)

    return [
        ("signals", lambda e: cell.add_signal(e["name"], e["initial"])),
        ("sensors", sensor),
        (
            "conveyors",
            lambda e: cell.add_conveyor(
                e["name"],
                start=e["start"],
                end=e["end"],
                width=e["width"],
                speed=e["speed"],
                run_signal=e.get("run_signal"),
            ),
        ),
        (
            "sources",
            lambda e: cell.add_source(
                e["name"],
                e["part"],
                at=e["at"],
                every=e.get("every"),
                count=e.get("count"),
                on_signal=e.get("on_signal"),
            ),
        ),
        ("sinks", lambda e: cell.add_sink(e["name"], center=e["center"], size=e["size"])),
    ]
