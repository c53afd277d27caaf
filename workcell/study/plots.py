"""Pictures of a study's results (matplotlib's Agg canvas, PNG; no window, no pyplot).

- ``cycle_time_xy.png``: the candidates over a placement plane, each a square coloured by
  its cycle time (the colour bar in seconds), infeasible ones as red crosses, the best as
  a star. The plane is the first robot base varied in both x and y (else a part's x and y,
  else the first two numeric parameters). Where candidates share a point (other
  parameters varied too) the point shows the best of them, infeasible only when all are.
- ``cycle_time_hist.png``: the distribution of the feasible candidates' cycle times, the
  best marked.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pyarrow as pa

from workcell.files import atomic_path
from workcell.study.spec import Parameter

__all__ = ["HIST_PNG", "XY_PNG", "placement_axes", "plot_study"]

XY_PNG = "cycle_time_xy.png"
HIST_PNG = "cycle_time_hist.png"


def placement_axes(parameters: Sequence[Parameter]) -> tuple[Parameter, Parameter] | None:
    """The two parameters the placement plot uses (module doc), or None."""
    numeric = [p for p in parameters if not p.text and p.field not in ("speed", "override")]
    by_name = {p.name: p for p in numeric}
    for suffix in (".base.x", ".x"):
        for p in numeric:
            if p.name.endswith(suffix):
                other = by_name.get(p.name[: -len("x")] + "y")
                if other is not None:
                    return p, other
    numeric = [p for p in parameters if not p.text]
    return (numeric[0], numeric[1]) if len(numeric) >= 2 else None


def _save(fig: Any, path: Path) -> Path:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    return path


def _xy_plot(rows: list[dict[str, Any]], px: Parameter, py: Parameter, path: Path) -> Path:
    from matplotlib.figure import Figure

    cells: dict[tuple[float, float], list[dict[str, Any]]] = {}
    for r in rows:
        cells.setdefault((r[px.name], r[py.name]), []).append(r)
    good, bad = [], []
    for (x, y), group in cells.items():
        ok = [r["cycle_time_s"] for r in group if r["feasible"]]
        (good if ok else bad).append((x, y, min(ok) if ok else math.nan))
    from matplotlib.ticker import MaxNLocator

    fig = Figure(figsize=(6.4, 5.6), layout="constrained")
    ax = fig.add_subplot()
    n_feasible = sum(1 for r in rows if r["feasible"])
    if good:
        xs, ys, ts = zip(*good, strict=True)
        art = ax.scatter(xs, ys, c=ts, cmap="viridis", marker="s", s=_marker_size(cells), zorder=2)
        fig.colorbar(art, ax=ax, label="cycle time (s)")
        i = min(range(len(ts)), key=lambda k: ts[k])
        ax.scatter(
            [xs[i]],
            [ys[i]],
            marker="*",
            s=220,
            c="white",
            edgecolors="black",
            zorder=3,
            label=f"best: {ts[i]:.2f} s",
        )
    if bad:
        bx, by, _ = zip(*bad, strict=True)
        ax.scatter(bx, by, marker="x", c="tab:red", s=40, zorder=2, label="infeasible")
    ax.set_xlabel(f"{px.name} ({px.unit})")
    ax.set_ylabel(f"{py.name} ({py.unit})")
    ax.set_title(f"cycle time over the placement: {n_feasible} of {len(rows)} feasible")
    ax.set_aspect("equal" if px.unit == py.unit else "auto", adjustable="datalim")
    ax.grid(True, alpha=0.3, zorder=0)
    ax.xaxis.set_major_locator(MaxNLocator(6))
    ax.yaxis.set_major_locator(MaxNLocator(6))
    if good or bad:
        ax.legend(
            loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, fontsize=8, frameon=False
        )
    return _save(fig, path)


def _marker_size(cells: dict[tuple[float, float], Any]) -> float:
    """Square markers about as big as the grid's spacing on a ~5 inch plot (points^2)."""
    n = max(1, len(cells))
    side = 300.0 / math.sqrt(n)  # points across one cell of a square grid
    return max(12.0, min(400.0, 0.8 * side * side))


def _histogram(rows: list[dict[str, Any]], path: Path) -> Path:
    from matplotlib.figure import Figure

    times = [r["cycle_time_s"] for r in rows if r["feasible"]]
    fig = Figure(figsize=(6.4, 4.0), layout="constrained")
    ax = fig.add_subplot()
    if times:
        ax.hist(times, bins=min(30, max(5, len(times) // 3)), color="tab:blue", alpha=0.8)
        best = min(times)
        ax.axvline(best, color="black", linestyle="--", label=f"best {best:.2f} s")
        ax.legend(fontsize=8)
    ax.set_xlabel("cycle time (s)")
    ax.set_ylabel("candidates")
    ax.set_title(f"cycle times of the {len(times)} feasible candidates (of {len(rows)})")
    ax.grid(True, alpha=0.3)
    return _save(fig, path)


def plot_study(table: pa.Table, parameters: Sequence[Parameter], out: Path) -> dict[str, Path]:
    """Write the study's PNGs (module doc) into ``out``; returns name -> path."""
    rows = table.to_pylist()
    files = {"histogram": _histogram(rows, out / HIST_PNG)}
    axes = placement_axes(parameters)
    if axes is not None:
        files["placement"] = _xy_plot(rows, axes[0], axes[1], out / XY_PNG)
    return files
