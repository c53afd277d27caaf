"""Public solid constructors: ``workcell.solids.<shape>(model, name, **params)`` -> block name.

Primitives built the thesis's way (:mod:`workcell.modeller.solids`), sweeps
(:mod:`workcell.modeller.sweeps`) and booleans (:mod:`workcell.modeller.csg`).
Lengths in metres, angles in radians.
"""

from workcell.modeller.csg import difference, intersection, union
from workcell.modeller.solids import box, cone, cube, cylinder, ellipsoid, sphere, torus
from workcell.modeller.sweeps import extrude, revolve, sweep

__all__ = [
    "box",
    "cone",
    "cube",
    "cylinder",
    "difference",
    "ellipsoid",
    "extrude",
    "intersection",
    "revolve",
    "sphere",
    "sweep",
    "torus",
    "union",
]
