"""Stand-ins for the meshes a robot file names but does not ship, and the one warning
that lists them.

Real robot files often come without some of their meshes (a URDF copied without its
``meshes/`` folder, a MuJoCo Menagerie XML without ``assets/``). The kinematics are all
in the file, so an import still gives the robot (:func:`~workcell.robots.from_urdf`,
:func:`~workcell.robots.from_mjcf`); each link whose mesh is missing is drawn and
collides as a **capsule between its joint origins** (:func:`capsule`):

- its axis runs from the link's own frame origin (where its joint is) to the farthest
  origin of the joints it carries (its children, in the link's frame); a link that
  carries none (the last one) runs to twice its centre of mass when the file gives one
  off the origin, else it is a sphere;
- its radius comes from the file's inertia when the file states one (mass m > 0 and
  principal moments I): the radius of the solid cylinder whose moment about its own
  axis is the smallest moment, ``sqrt(2 I_min / m)``; otherwise from the neighbouring
  joints: 10 % of the longer of the link's axis and its parent's, at least 1 cm; either
  way at most half the axis plus 5 cm, so a heavy short link does not swallow its
  neighbours.

:class:`Missing` gathers the missing files while a file is read and gives one warning
naming each path as the file wrote it, the element that named it and every place it was
looked for (or, with ``strict=True``, raises that as a ModelError at the first one).
Units: metres, kilograms.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import trimesh
from numpy.typing import NDArray

from workcell.errors import ModelError
from workcell.robots.meshfile import primitive

__all__ = ["MIN_RADIUS", "Missing", "capsule"]

Array = NDArray[np.float64]
MIN_RADIUS = 0.01  # m: the thinnest stand-in from the neighbouring joints
_FROM_JOINTS = 0.1  # radius / the longer of the link's axis and its parent's
_MAX_OVER_HALF = 0.05  # m: the radius is at most half the axis plus this


def capsule(
    ends: Sequence[Array],
    *,
    com: Array | None = None,
    mass: float = 0.0,
    inertia: Array | None = None,
    parent_length: float = 0.0,
) -> trimesh.Trimesh:
    """The stand-in of a link (module doc) as a closed mesh in the link's frame (m).

    ``ends``: the origins of the joints the link carries (its frame, m); ``com`` its
    centre of mass, ``mass`` (kg) and ``inertia`` (the 3 principal moments, kg m^2) when
    the file states them; ``parent_length``: the length of the parent link's axis (m).
    """
    tips = [np.asarray(e, dtype=np.float64) for e in ends]
    tip = max(tips, key=lambda p: float(np.linalg.norm(p)), default=np.zeros(3))
    if np.linalg.norm(tip) < 1e-9 and com is not None:
        tip = 2.0 * np.asarray(com, dtype=np.float64)
    length = float(np.linalg.norm(tip))
    radius = None
    if inertia is not None and mass > 0:
        i_min = float(np.min(inertia))
        if i_min > 0:
            radius = float(np.sqrt(2.0 * i_min / mass))
    if radius is None:
        radius = max(MIN_RADIUS, _FROM_JOINTS * max(length, parent_length))
    radius = min(max(radius, MIN_RADIUS / 2), length / 2 + _MAX_OVER_HALF)
    mesh = primitive("capsule", size=(radius, length), what="a stand-in capsule")
    T = np.eye(4)
    if length > 0:  # the capsule's z axis onto the link's axis
        T = trimesh.geometry.align_vectors(np.array([0.0, 0.0, 1.0]), tip / length)
    T[:3, 3] = tip / 2
    return mesh.apply_transform(T)


@dataclass
class Missing:
    """The mesh files a robot file names but that are found nowhere (module doc):
    ``what`` names the robot file; ``strict`` raises at the first one."""

    what: str
    strict: bool = False
    entries: list[tuple[str, str, list[str], str]] = field(default_factory=list)

    def add(self, written: str, where: str, tried: Sequence[str], instead: str) -> None:
        """Record file ``written`` (as the file wrote it), named by element ``where``,
        looked for at ``tried``, replaced as ``instead`` says; ModelError at once when
        strict."""
        if self.strict:
            raise ModelError(
                f"{self.what}: {where}: mesh file '{written}' not found; tried: "
                f"{'; '.join(tried) or 'nowhere'}"
            )
        self.entries.append((written, where, list(tried), instead))

    def warn(self, stacklevel: int = 3) -> None:
        """One warning listing every missing file (nothing when none is missing)."""
        if not self.entries:
            return
        lines = "; ".join(
            f"'{w}' ({where}: {instead}; tried: {', '.join(tried) or 'nowhere'})"
            for w, where, tried, instead in self.entries
        )
        warnings.warn(
            f"{self.what}: {len(self.entries)} mesh file(s) not found (strict=True makes "
            f"this an error): {lines}",
            stacklevel=stacklevel,
        )
