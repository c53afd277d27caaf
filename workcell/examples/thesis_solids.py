"""The thesis's example solids (ch. 2-3), built with the modeller, with exact reference values.

:func:`build` returns a model holding the unit cube made of one square (the thesis's six
SRT rows), the 2 x 3 x 1.5 parallelepiped made both ways (block copy with scaling; object
with a scaling relation), and one of every primitive, sweep and boolean.
:func:`report` lists each solid's properties beside its exact value.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workcell import solids, spatial
from workcell.modeller.model import Model
from workcell.modeller.surface import Surface

__all__ = ["SolidRow", "build", "format_report", "report"]

D90 = np.pi / 2
# thesis §2 unit cube: six transform_surfaces to one unit square (SRT rows, radians)
CUBE_ROWS = [
    {"rotation": (D90, 0, 0)},
    {"rotation": (D90, 0, 0), "translation": (0, 1, 0)},
    {"rotation": (0, -D90, 0)},
    {"rotation": (0, -D90, 0), "translation": (1, 0, 0)},
    {},
    {"translation": (0, 0, 1)},
]


def _ngon_area(n: int, r: float) -> float:
    return 0.5 * n * r * r * np.sin(2 * np.pi / n)


def _revolved_volume(profile: np.ndarray, steps: int, step: float) -> float:
    """Exact volume (m^3) of a polygonal (r, z) profile revolved in ``steps`` planar steps.

    Every horizontal slice is the region between regular polygons, so
    V = steps * sin(step) * M_r, with M_r the profile's first moment about the axis
    (the Pappus integral of r over the profile area), here by the edge formula.
    """
    r, z = profile[:, 0], profile[:, 1]
    r1, z1 = np.roll(r, -1), np.roll(z, -1)
    m_r = float(np.sum((r * z1 - r1 * z) * (r + r1)) / 6.0)
    return steps * np.sin(step) * abs(m_r)


def build() -> tuple[Model, dict[str, float]]:
    """The example model and the exact volume (m^3) of each block or object in it."""
    m = Model()
    exact: dict[str, float] = {}
    m.create("surface", "square1", Surface.rectangle(1.0, 1.0))
    m.create("block", "cube1", colour=(0.8, 0.3, 0.2))
    for i, row in enumerate(CUBE_ROWS):
        m.attach("cube1", "square1", spatial.srt(**row), name=f"face{i + 1}")
    exact["cube1"] = 1.0
    m.copy("cube1", "para_block", spatial.scaling(2.0, 3.0, 1.5))
    exact["para_block"] = 9.0
    m.create("object", "para_object")
    m.attach("para_object", "cube1", spatial.scaling(2.0, 3.0, 1.5))
    exact["para_object"] = 9.0
    solids.cylinder(m, "cylinder", radius=0.5, height=2.0, n=24)
    exact["cylinder"] = _ngon_area(24, 0.5) * 2.0
    solids.cone(m, "cone", radius=0.5, height=1.0, n=24)
    exact["cone"] = _ngon_area(24, 0.5) * 1.0 / 3
    solids.sphere(m, "sphere", radius=1.0, m=24, n=12)
    phi = np.linspace(-np.pi / 2, np.pi / 2, 2 * 12 + 1)
    exact["sphere"] = _revolved_volume(
        np.column_stack([np.cos(phi), np.sin(phi)]), 24, 2 * np.pi / 24
    )
    solids.ellipsoid(m, "ellipsoid", radii=(1.0, 0.5, 0.25), m=24, n=12)
    exact["ellipsoid"] = exact["sphere"] * 0.125
    solids.torus(m, "torus", major_radius=1.0, minor_radius=0.25, m=32, n=12)
    exact["torus"] = 32 * np.sin(2 * np.pi / 32) * _ngon_area(12, 0.25) * 1.0
    plate = Surface(
        [(0, 0), (4, 0), (4, 2), (0, 2)],
        [Surface.circle(0.4, 16, center=(1 + 2 * i, 1)).main for i in range(2)],
        name="plate",
    )
    solids.extrude(m, "plate", plate, height=0.2)
    exact["plate"] = plate.area * 0.2
    ring = np.array([(0.5, 0.0), (1.0, 0.0), (1.0, 0.3), (0.5, 0.3)])
    solids.revolve(m, "ring_quarter", ring, angle=D90, n=12)
    exact["ring_quarter"] = _revolved_volume(ring, 12, D90 / 12)
    t = np.linspace(0.0, 1.0, 11)
    solids.sweep(
        m,
        "taper",
        Surface.rectangle(0.2, 0.2, center=True),
        np.column_stack([0 * t, 0 * t, t]),
        scales=1 - 0.5 * t,
    )
    exact["taper"] = 1.0 / 3 * (0.04 + 0.01 + 0.02)  # frustum h/3 (A1 + A2 + sqrt(A1 A2))
    solids.box(m, "block", size=(2.0, 2.0, 1.0))
    exact["block"] = 4.0
    solids.difference(
        m,
        "block_minus_cylinder",
        "block",
        "cylinder",
        transforms=[None, spatial.translation(1, 1, -0.5)],
    )
    exact["block_minus_cylinder"] = 4.0 - _ngon_area(24, 0.5) * 1.0
    return m, exact


@dataclass(frozen=True)
class SolidRow:
    """Properties of one example solid (m, m^2, m^3) and its exact volume when known."""

    name: str
    level: str
    faces: int
    area: float
    volume: float
    exact_volume: float | None
    centroid: tuple[float, float, float]
    valid: bool


def report(model: Model, exact: dict[str, float]) -> list[SolidRow]:
    """One row per block and object of ``model`` (component surfaces are skipped)."""
    rows = []
    for level in ("block", "object"):
        for name in model.list(level):
            p = model.properties((level, name))
            mesh = model.world_mesh((level, name))
            valid = (
                model.validity((level, name)).ok if level == "block" else bool(mesh.is_watertight)
            )
            rows.append(
                SolidRow(
                    name,
                    level,
                    len(mesh.faces),
                    p.area,
                    p.volume,
                    exact.get(name),
                    tuple(p.centroid),
                    valid,
                )
            )
    return rows


def format_report(rows: list[SolidRow]) -> str:
    """A text table of :func:`report` rows."""
    head = f"{'solid':22s} {'level':6s} {'faces':>6s} {'area m^2':>10s} {'volume m^3':>12s} {'exact':>12s} {'rel.err':>8s}  valid"
    lines = [head, "-" * len(head)]
    for r in rows:
        ex = f"{r.exact_volume:12.9f}" if r.exact_volume is not None else " " * 12
        err = (
            f"{abs(r.volume - r.exact_volume) / r.exact_volume:8.1e}" if r.exact_volume else " " * 8
        )
        lines.append(
            f"{r.name:22s} {r.level:6s} {r.faces:6d} {r.area:10.6f} {r.volume:12.9f} {ex} {err}  {'yes' if r.valid else 'NO'}"
        )
    return "\n".join(lines)
