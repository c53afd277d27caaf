"""The Gantt chart of a run: what every robot and controller program did, over time.

One row per robot (its motions *moving*, its ``wait`` and ``wait_signal`` *waiting*, the
rest *idle*) and per controller program of ``run_programs`` (waiting or idle), from
:func:`workcell.sim.throughput.activity`; below them one thin row per bool signal, filled
while it is true. The title gives the run's throughput (parts per hour at each sink, else
rising edges per hour of the signals that rose). Drawn with matplotlib's Agg canvas (no
window); :func:`gantt_chart` returns the picture, :func:`save_gantt` writes a PNG.
Times are simulated seconds.
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from workcell.errors import RenderError

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["COLOURS", "gantt_chart", "save_gantt"]

COLOURS = {"moving": "#2f6fdf", "waiting": "#f0a030", "idle": "#e4e6ea", "signal": "#3aa655"}


def _signal_intervals(
    sim: Simulator, name: str, initial: Any, end: float
) -> list[tuple[float, float]]:
    from workcell.record.devices import signal_history

    out, since = [], 0.0 if initial is True else None
    for _, t, v in signal_history(sim.events).get(name, []):
        if v is True and since is None:
            since = t
        elif v is not True and since is not None:
            out.append((since, t))
            since = None
    if since is not None:
        out.append((since, end))
    return out


def gantt_chart(
    sim: Simulator, *, width: int = 1280, height: int | None = None
) -> NDArray[np.uint8]:
    """The Gantt chart of ``sim``'s run (module doc) as an (H, W, 3) uint8 picture;
    ``height`` defaults to fit the rows."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    from workcell.sim.throughput import activity

    if not (isinstance(width, int) and 200 <= width <= 8192):
        raise RenderError(f"width must be an integer in [200, 8192] pixels, got {width!r}")
    T = max(float(sim.sim_time), 1e-9)
    rows = activity(sim.events, T)
    names = [*sim.robots, *(k for k in rows if k not in sim.robots)]
    logic = sim._logic
    signals = (
        [k for k, v in logic.initial.items() if isinstance(v, bool)] if logic is not None else []
    )
    n = len(names) + 0.5 * len(signals)
    h = height if height is not None else int(110 + 42 * n)
    dpi = 100
    fig = Figure(figsize=(width / dpi, h / dpi), dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    y, ticks, labels = 0.0, [], []
    for name in names:
        ax.broken_barh([(0, T)], (y - 0.4, 0.8), color=COLOURS["idle"])
        for kind in ("moving", "waiting"):
            spans = [(a, b - a) for a, b, k in rows.get(name, []) if k == kind]
            if spans:
                ax.broken_barh(spans, (y - 0.4, 0.8), color=COLOURS[kind])
        ticks.append(y)
        labels.append(f"robot {name}" if name in sim.robots else f"program {name}")
        y -= 1.0
    for name in signals:
        spans = [(a, b - a) for a, b in _signal_intervals(sim, name, logic.initial[name], T)]
        ax.broken_barh([(0, T)], (y - 0.15, 0.3), color=COLOURS["idle"])
        if spans:
            ax.broken_barh(spans, (y - 0.15, 0.3), color=COLOURS["signal"])
        ticks.append(y)
        labels.append(f"signal {name}")
        y -= 0.5
    ax.set_yticks(ticks, labels)
    ax.set_xlim(0, T)
    ax.set_ylim(y + 0.25, 0.6)
    ax.set_xlabel("simulated time (s)")
    ax.grid(True, axis="x", alpha=0.3)
    ax.set_title(_title(sim))
    fig.legend(
        handles=[Patch(color=COLOURS[k], label=k) for k in ("moving", "waiting", "idle")]
        + ([Patch(color=COLOURS["signal"], label="signal true")] if signals else []),
        loc="outside lower center", ncol=4, frameon=False, fontsize=9,
    )  # fmt: skip
    buf = io.BytesIO()
    fig.savefig(buf, format="rgba", dpi=dpi)
    w, hh = (int(v) for v in fig.canvas.get_width_height())
    img = np.frombuffer(buf.getvalue(), np.uint8).reshape(hh, w, 4)[:, :, :3]
    return np.ascontiguousarray(img)


def _title(sim: Simulator) -> str:
    tp = sim.throughput()
    parts = [
        f"{k}: {v['parts']} parts, {v['parts_per_hour']:.0f}/h" for k, v in tp["sinks"].items()
    ]
    if not parts:
        parts = [
            f"{k}: {v['rising']} times, {v['per_hour']:.0f}/h"
            for k, v in tp["signals"].items()
            if v["rising"] and k not in sim.cell.sensors
        ][:3]
    return f"{sim.cell.name}: {sim.sim_time:.2f} s" + (f"  ({'; '.join(parts)})" if parts else "")


def save_gantt(sim: Simulator, path: str | os.PathLike, *, width: int = 1280) -> Path:
    """Write :func:`gantt_chart` as a PNG (atomically); return the path."""
    from workcell.record.render import save_png

    return save_png(gantt_chart(sim, width=width), path)
