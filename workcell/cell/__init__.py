"""Workcells (thesis ch. 4.4-5): parts, robots and cameras placed in the world, compiled to MJCF."""

from workcell.cell.compile import CompiledCell, compile_cell, export_cell
from workcell.cell.workcell import Camera, MovablePart, RobotPlacement, StaticPart, Workcell

__all__ = [
    "Camera",
    "CompiledCell",
    "MovablePart",
    "RobotPlacement",
    "StaticPart",
    "Workcell",
    "compile_cell",
    "export_cell",
]
