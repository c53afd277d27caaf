"""Example builders: the thesis's solids and its three workcells (ch. 5).

Each workcell example has ``build()`` (the cell), ``program(sim)`` (the thesis's program)
and ``run(mode, dt, **options)`` (both, through :func:`run_program`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from workcell.cell.workcell import Workcell
    from workcell.sim.simulator import Simulator

__all__ = ["run_program"]


def run_program(
    cell: Workcell,
    program: Callable[[Simulator], object],
    mode: str = "path",
    dt: float = 0.01,
    **options: object,
) -> Simulator:
    """Simulate ``cell`` in ``mode`` with sampling interval ``dt`` (s), run ``program`` on
    it and, in playback mode, replay the stored frames; return the finished simulator.
    ``options`` go to :class:`~workcell.sim.simulator.Simulator`."""
    from workcell.sim.simulator import Simulator

    sim = Simulator(cell, mode=mode, dt=dt, **options)
    program(sim)
    if mode == "playback":
        sim.play()
    return sim
