"""Example builders: the thesis's solids and its three workcells (ch. 5), and beyond it
the obstacle cell (a wall between two stages, for collision-free planning) and the
conveyor cell (a belt, a light beam, a UR5e stacking boxes: programs that run together).

Each workcell example has ``build()`` (the cell), ``program(sim)`` (the thesis's program)
and ``run(mode, dt, **options)`` (both, through :func:`run_program`).
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable
from types import ModuleType
from typing import TYPE_CHECKING

from workcell.errors import ProgramError

if TYPE_CHECKING:
    from workcell.cell.workcell import Workcell
    from workcell.sim.simulator import Simulator

__all__ = ["CELLS", "CELL_HELP", "example", "load_cell", "run_program"]

# the thesis's example workcells (ch. 5): name -> module with build(), program(), run()
CELLS = {
    "joints": "workcell.examples.thesis_joints",
    "pick-place": "workcell.examples.thesis_pick_place",
    "handoff": "workcell.examples.thesis_handoff",
    "obstacle": "workcell.examples.obstacle",  # beyond the thesis: a wall between two stages
    "conveyor": "workcell.examples.conveyor",  # beyond: a belt, a beam, a UR5e, two programs
}

CELL_HELP = f"a cell saved by Workcell.save (.json), or an example cell: {', '.join(CELLS)}"


def example(name: str) -> ModuleType:
    """The module of example workcell ``name`` (one of :data:`CELLS`)."""
    if name not in CELLS:
        raise ProgramError(f"no example cell {name!r}; examples: {', '.join(CELLS)}")
    return importlib.import_module(CELLS[name])


def load_cell(spec: str | os.PathLike) -> Workcell:
    """A cell from a saved JSON file, or an example cell by name ("handoff", ...)."""
    from workcell.cell.workcell import Workcell

    if isinstance(spec, str) and spec in CELLS:
        return example(spec).build()
    return Workcell.load(spec)


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
