"""The command vocabulary, solids part: the modeller's primitives and sweeps (thesis §3).

Each command creates one block (and its own surfaces, named ``NAME.<part>``) with
:mod:`workcell.solids`, which validates every parameter first. Lengths in metres.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from workcell import solids
from workcell.program import args as a
from workcell.program.args import arg
from workcell.program.base import Command

if TYPE_CHECKING:
    from workcell.program.session import Session

__all__ = [
    "CreateBox",
    "CreateCone",
    "CreateCube",
    "CreateCylinder",
    "CreateExtrusion",
    "CreateSphere",
    "CreateTorus",
]

_opt_colour = a.optional(a.colour)


@dataclass(frozen=True)
class CreateCube(Command, wire="create_cube"):
    """Cube of edge ``size`` (m), a corner at the origin: one square placed six times."""

    name: str = arg(a.name)
    size: float = arg(a.number, 1.0, "m")
    colour: tuple[float, ...] | None = arg(_opt_colour, None)

    def execute(self, session: Session) -> str:
        return solids.cube(session.model, self.name, size=self.size, colour=self.colour)


@dataclass(frozen=True)
class CreateBox(Command, wire="create_box"):
    """Box of ``size`` (x, y, z) (m), a corner at the origin."""

    name: str = arg(a.name)
    size: tuple[float, ...] = arg(a.sized(3), doc="m")
    colour: tuple[float, ...] | None = arg(_opt_colour, None)

    def execute(self, session: Session) -> str:
        return solids.box(session.model, self.name, size=self.size, colour=self.colour)


@dataclass(frozen=True)
class CreateCylinder(Command, wire="create_cylinder"):
    """Cylinder about z from z = 0 to ``height`` (m), ``n`` facets."""

    name: str = arg(a.name)
    radius: float = arg(a.number, doc="m")
    height: float = arg(a.number, doc="m")
    n: int = arg(a.count, 32)
    colour: tuple[float, ...] | None = arg(_opt_colour, None)

    def execute(self, session: Session) -> str:
        return solids.cylinder(
            session.model,
            self.name,
            radius=self.radius,
            height=self.height,
            n=self.n,
            colour=self.colour,
        )


@dataclass(frozen=True)
class CreateSphere(Command, wire="create_sphere"):
    """Sphere of ``radius`` (m) at the origin: ``m`` slices, ``n`` faces per half slice."""

    name: str = arg(a.name)
    radius: float = arg(a.number, doc="m")
    m: int = arg(a.count, 16)
    n: int = arg(a.count, 8)
    colour: tuple[float, ...] | None = arg(_opt_colour, None)

    def execute(self, session: Session) -> str:
        return solids.sphere(
            session.model, self.name, radius=self.radius, m=self.m, n=self.n, colour=self.colour
        )


@dataclass(frozen=True)
class CreateCone(Command, wire="create_cone"):
    """Cone about z, base ``radius`` at z = 0, apex at ``height`` (m), ``n`` steps."""

    name: str = arg(a.name)
    radius: float = arg(a.number, doc="m")
    height: float = arg(a.number, doc="m")
    n: int = arg(a.count, 32)
    colour: tuple[float, ...] | None = arg(_opt_colour, None)

    def execute(self, session: Session) -> str:
        return solids.cone(
            session.model,
            self.name,
            radius=self.radius,
            height=self.height,
            n=self.n,
            colour=self.colour,
        )


@dataclass(frozen=True)
class CreateTorus(Command, wire="create_torus"):
    """Torus about z: ``major_radius``, ``minor_radius`` (m), ``m`` steps, ``n``-gon section."""

    name: str = arg(a.name)
    major_radius: float = arg(a.number, doc="m")
    minor_radius: float = arg(a.number, doc="m")
    m: int = arg(a.count, 32)
    n: int = arg(a.count, 16)
    colour: tuple[float, ...] | None = arg(_opt_colour, None)

    def execute(self, session: Session) -> str:
        return solids.torus(
            session.model,
            self.name,
            major_radius=self.major_radius,
            minor_radius=self.minor_radius,
            m=self.m,
            n=self.n,
            colour=self.colour,
        )


@dataclass(frozen=True)
class CreateExtrusion(Command, wire="create_extrusion"):
    """Translational sweep of surface entity ``surface`` along +z for ``height`` (m)."""

    name: str = arg(a.name)
    surface: str = arg(a.name)
    height: float = arg(a.number, doc="m")
    colour: tuple[float, ...] | None = arg(_opt_colour, None)

    def execute(self, session: Session) -> str:
        m = session.model
        m.surface(self.surface)  # a clear error when it is no surface
        return solids.extrude(m, self.name, self.surface, height=self.height, colour=self.colour)
