"""Small cells with a belt, a box and sensors, shared by the device and program tests."""

from __future__ import annotations

from workcell import solids
from workcell.cell import Workcell
from workcell.spatial import translation

BOX = 0.1  # m, a cube
TOP = 0.5  # m, the belt's top
START, END, WIDTH = 0.0, 3.0, 0.3  # m


def belt_cell(
    *,
    speed: float = 0.2,
    box_x: float = 0.2,
    beam_x: float | None = None,
    run_signal: str | None = None,
    name: str = "belts",
) -> Workcell:
    """A belt along +x at height TOP from START to END, a 0.1 m box whose back face is at
    ``box_x`` (its front face at ``box_x + BOX``), resting on the belt, optionally a beam
    across the belt at ``beam_x`` and a run signal (declared true)."""
    cell = Workcell(name)
    solids.cube(cell.model, "cube", size=BOX)
    cell.add_movable("box", "cube", translation(box_x, -BOX / 2, TOP), density=500.0)
    if run_signal is not None:
        cell.add_signal(run_signal, True)
    cell.add_conveyor(
        "belt",
        start=(START, 0.0, TOP),
        end=(END, 0.0, TOP),
        width=WIDTH,
        speed=speed,
        run_signal=run_signal,
    )
    if beam_x is not None:
        z = TOP + BOX / 2
        cell.add_sensor("beam", "beam", start=(beam_x, -0.3, z), end=(beam_x, 0.3, z))
    return cell
