"""Pictures of a study's results (matplotlib's Agg canvas, PNG; no window, no pyplot).

- ``cycle_time_xy.png``: the candidates over a placement plane, each a square coloured by
  its cycle time (one colour bar in seconds for all panels), infeasible ones as red
  crosses, the best as a star. The plane is the first robot base varied in both x and y
  (else a part's x and y, else the first two numeric parameters). A study that varies
  which robot stands somewhere (``ROBOT.robot``) gets one panel per robot, so no robot
  is drawn over another. Where candidates of a panel share a point (other parameters
  varied too), the square shows the best of the feasible ones and a red cross marks any
  infeasible one: no infeasible candidate is hidden.
- ``cycle_time_hist.png``: the distribution of the feasible candidates' cycle times, the
  best marked; not written when no candidate is feasible (nothing to show: the
  command line says so instead).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pyarrow as pa

from workcell.files import atomic_path
from workcell.study.spec import Parameter

__all__ = ["HIST_PNG", "XY_PNG", "placement_axes", "placement_figure", "plot_study"]

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


def _panels(
    rows: list[dict[str, Any]], texts: Sequence[Parameter]
) -> list[tuple[str, list[dict[str, Any]]]]:
    """(title, rows) per combination of the named parameters' values (robot choices), in
    the order they first appear; one untitled panel when none is varied."""
    groups: dict[tuple[Any, ...], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault(tuple(r[p.name] for p in texts), []).append(r)
    return [
        (", ".join(f"{p.target} = {v}" for p, v in zip(texts, key, strict=True)), group)
        for key, group in groups.items()
    ]


def placement_figure(
    rows: list[dict[str, Any]],
    px: Parameter,
    py: Parameter,
    texts: Sequence[Parameter] = (),
) -> Any:
    """The placement plot (module doc) of ``rows`` over ``px`` x ``py``, a panel per
    value of the ``texts`` parameters: a matplotlib Figure (not drawn yet)."""
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    panels = _panels(rows, texts)
    cols = min(3, len(panels))
    nrows = math.ceil(len(panels) / cols)
    fig = Figure(figsize=(1.2 + 4.6 * cols, 1.2 + 4.2 * nrows), layout="constrained")
    times = [r["cycle_time_s"] for r in rows if r["feasible"]]
    norm = Normalize(min(times), max(times)) if times else None
    best = min(times) if times else None
    art = None
    axes = [fig.add_subplot(nrows, cols, k + 1) for k in range(len(panels))]
    for ax, (title, group) in zip(axes, panels, strict=True):
        cells: dict[tuple[float, float], list[dict[str, Any]]] = {}
        for r in group:
            cells.setdefault((r[px.name], r[py.name]), []).append(r)
        good, bad = [], []
        for (x, y), members in cells.items():
            ok = [r["cycle_time_s"] for r in members if r["feasible"]]
            if ok:
                good.append((x, y, min(ok)))
            if len(ok) < len(members):
                bad.append((x, y))
        size = _marker_size(cells) / cols
        if good:
            xs, ys, ts = zip(*good, strict=True)
            art = ax.scatter(xs, ys, c=ts, cmap="viridis", norm=norm, marker="s", s=size, zorder=2)
            if best in ts:
                i = ts.index(best)
                ax.scatter(
                    [xs[i]], [ys[i]], marker="*", s=220, c="white", edgecolors="black",
                    zorder=4, label=f"best: {best:.2f} s",
                )  # fmt: skip
        if bad:
            bx, by = zip(*bad, strict=True)
            ax.scatter(bx, by, marker="x", c="tab:red", s=40, zorder=3, label="infeasible")
        n_ok = sum(1 for r in group if r["feasible"])
        head = f"{title}: " if title else "cycle time over the placement: "
        ax.set_title(f"{head}{n_ok} of {len(group)} feasible", fontsize=10 if title else 12)
        ax.set_xlabel(f"{px.name} ({px.unit})")
        ax.set_ylabel(f"{py.name} ({py.unit})")
        ax.set_aspect("equal" if px.unit == py.unit else "auto", adjustable="datalim")
        ax.grid(True, alpha=0.3, zorder=0)
        ax.xaxis.set_major_locator(MaxNLocator(6))
        ax.yaxis.set_major_locator(MaxNLocator(6))
        if good or bad:
            ax.legend(
                loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, fontsize=8,
                frameon=False,
            )  # fmt: skip
    if art is not None:
        fig.colorbar(art, ax=axes, label="cycle time (s)")
    if texts:
        n_ok = sum(1 for r in rows if r["feasible"])
        fig.suptitle(f"cycle time over the placement: {n_ok} of {len(rows)} feasible")
    return fig


def _xy_plot(
    rows: list[dict[str, Any]],
    px: Parameter,
    py: Parameter,
    path: Path,
    texts: Sequence[Parameter] = (),
) -> Path:
    return _save(placement_figure(rows, px, py, texts), path)


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
    """Write the study's PNGs (module doc) into ``out``; returns name -> path (no
    ``histogram`` when no candidate is feasible)."""
    rows = table.to_pylist()
    files = {}
    if any(r["feasible"] for r in rows):
        files["histogram"] = _histogram(rows, out / HIST_PNG)
    axes = placement_axes(parameters)
    if axes is not None and rows:
        texts = [p for p in parameters if p.text]
        files["placement"] = _xy_plot(rows, axes[0], axes[1], out / XY_PNG, texts)
    return files
