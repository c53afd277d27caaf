"""Primitive solids built the thesis's way (thesis §3): each a block of placed surfaces.

- cube / box: one unit square attached six times (scaled for a box);
- cylinder: one unit square patched ``n`` times plus two n-gon caps;
- sphere: ``n`` distinct faces per half slice, each placed ``m`` times about z, the other
  hemisphere by reflection in the xy-plane;
- ellipsoid: the sphere's relations with an unequal scaling applied (a scaled copy);
- cone, torus: rotational sweeps (:mod:`workcell.modeller.sweeps`).

Every function takes the model and the new block's name, validates its parameters,
creates the block (and its own surfaces, named ``"{name}.<part>"``) and returns the name.
Lengths in metres.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell import limits, spatial
from workcell.checks import check_size, is_finite_number
from workcell.errors import GeometryError
from workcell.modeller.model import Model
from workcell.modeller.patches import (
    UNIT_SQUARE,
    build_block,
    parallelogram_transforms,
    planar_patches,
)
from workcell.modeller.surface import Surface
from workcell.modeller.sweeps import revolve

__all__ = ["box", "cone", "cube", "cylinder", "ellipsoid", "sphere", "torus"]

_FLIP = spatial.scaling(1.0, 1.0, -1.0)  # turns a placed surface over (front side to -z)


def _positive(name: str, **values: float) -> None:
    """Each value a number > 0 (not a bool, not a string), at least
    :data:`~workcell.checks.MIN_LENGTH` and at most ``max_coordinate`` (m)."""
    for key, v in values.items():
        if not (is_finite_number(v) and v > 0):
            raise GeometryError(f"solid '{name}': {key} must be a positive number, got {v!r}")
        check_size(f"solid '{name}'", key, float(v))
        limits.check("max_coordinate", float(v), f"solid '{name}': {key}")


def _count(name: str, key: str, v: object, minimum: int) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < minimum:
        raise GeometryError(f"solid '{name}': {key} must be an integer >= {minimum}, got {v!r}")
    return int(v)


def _triple(name: str, key: str, v: object) -> NDArray[np.float64]:
    values = list(v) if isinstance(v, (list, tuple, np.ndarray)) else []
    if len(values) != 3 or not all(is_finite_number(x) for x in values):
        raise GeometryError(f"solid '{name}': {key} must be three numbers, got {v!r}")
    return np.array(values, dtype=np.float64)


def cube_face_transforms() -> NDArray[np.float64]:
    """The thesis's six SRT rows for the unit cube, with the three inward faces turned over.

    Rows: R_x=90; R_x=90,T_y=1; R_y=-90; R_y=-90,T_x=1; identity; T_z=1. R_x=90 turns the
    square's front (+z) to -y and R_y=-90 turns it to -x, so the faces at y=1, x=1 and z=0
    would face into the cube: they are placed with z scaled by -1.
    """
    d = np.pi / 2
    rows = [
        spatial.srt(rotation=(d, 0, 0)),
        spatial.srt(rotation=(d, 0, 0), translation=(0, 1, 0)) @ _FLIP,
        spatial.srt(rotation=(0, -d, 0)),
        spatial.srt(rotation=(0, -d, 0), translation=(1, 0, 0)) @ _FLIP,
        _FLIP,
        spatial.srt(translation=(0, 0, 1)),
    ]
    return np.stack(rows)


def box(
    model: Model, name: str, *, size: ArrayLike = (1.0, 1.0, 1.0), colour: ArrayLike | None = None
) -> str:
    """Box ``size = (x, y, z)`` (m) with a corner at the origin: one unit square placed six times."""
    s = _triple(name, "size (x, y, z)", size)
    _positive(name, x=float(s[0]), y=float(s[1]), z=float(s[2]))
    Ts = spatial.scaling(*s) @ cube_face_transforms()
    return build_block(
        model,
        name,
        {"square": Surface(UNIT_SQUARE, name=f"{name}.square")},
        [("square", Ts)],
        colour=colour,
    )


def cube(model: Model, name: str, *, size: float = 1.0, colour: ArrayLike | None = None) -> str:
    """Cube of edge ``size`` (m), corner at the origin: one unit square attached six times."""
    _positive(name, size=size)
    return box(model, name, size=(size, size, size), colour=colour)


def cylinder(
    model: Model,
    name: str,
    *,
    radius: float,
    height: float,
    n: int = 32,
    colour: ArrayLike | None = None,
) -> str:
    """Cylinder about z from z=0 to ``height`` (m); ``n`` facets with vertices on the circle.

    Thesis construction: facet angle theta = 2 pi / n, facet width l = r sqrt(2 (1 - cos theta));
    facet i is the unit square scaled (l, h), turned and moved to (-r sin(i theta), r cos(i theta), 0);
    one n-gon caps the bottom (turned over) and the top.
    """
    _positive(name, radius=radius, height=height)
    n = _count(name, "n", n, 3)
    limits.check("max_facets", 4 * n - 4, f"cylinder '{name}' (n = {n})")
    t = 2 * np.pi * np.arange(n + 1) / n
    P = np.column_stack([-radius * np.sin(t), radius * np.cos(t), np.zeros(n + 1)])
    sides = parallelogram_transforms(P[:-1], P[1:] - P[:-1], np.tile([0.0, 0.0, height], (n, 1)))
    cap = Surface.regular_polygon(n, radius, phase=np.pi / 2, name=f"{name}.cap")
    caps = np.stack([_FLIP, spatial.translation(0, 0, height)])
    return build_block(
        model,
        name,
        {"square": Surface(UNIT_SQUARE, name=f"{name}.square"), "cap": cap},
        [("square", sides), ("cap", caps)],
        colour=colour,
    )


def _sphere_parts(
    name: str, m: int, n: int, radii: NDArray[np.float64]
) -> tuple[dict[str, Surface], list[tuple[str, NDArray[np.float64]]]]:
    """Unit-sphere faces: n distinct faces per half slice, each placed m times, mirrored below;
    every placement then scaled by ``radii`` (a, b, c) (m)."""
    alpha, beta = np.pi / (2 * n), 2 * np.pi / m
    lam = np.arange(m) * beta
    Rz = np.zeros((m, 4, 4))  # rotations about z by k beta
    Rz[:, 0, 0] = Rz[:, 1, 1] = np.cos(lam)
    Rz[:, 1, 0] = np.sin(lam)
    Rz[:, 0, 1] = -Rz[:, 1, 0]
    Rz[:, 2, 2] = Rz[:, 3, 3] = 1.0
    surfaces, relations = {}, []
    lat = np.arange(n + 1) * alpha
    lat[-1] = np.pi / 2  # the pole exactly
    ring = np.column_stack([np.cos(lat), np.zeros(n + 1), np.sin(lat)])  # longitude 0
    turned = ring * [np.cos(beta), 1.0, 1.0]  # longitude beta
    turned[:, 1] = ring[:, 0] * np.sin(beta)
    # band j: (lat j, 0), (lat j, beta), (lat j+1, beta), (lat j+1, 0), outward-facing
    corners = np.stack([ring[:-1], turned[:-1], turned[1:], ring[1:]], axis=1)
    names = [f"{name}.band{j}" for j in range(n)]
    patches, F = planar_patches(corners, names)
    # all placements at once: (n bands, 2 hemispheres, m slices, 4, 4); the lower hemisphere is
    # the reflection z -> -z (row 2 negated), the scaling multiplies rows 0-2 by (a, b, c)
    both = np.empty((n, 2, m, 4, 4))
    np.matmul(Rz[None], F[:, None], out=both[:, 0])
    both[:, 1] = both[:, 0]
    both[:, 1, :, 2] *= -1.0
    both *= np.array([*radii, 1.0])[:, None]
    for j in range(n):
        surfaces[f"band{j}"] = patches[j]
        relations.append((f"band{j}", both[j].reshape(-1, 4, 4)))
    return surfaces, relations


def sphere(
    model: Model,
    name: str,
    *,
    radius: float,
    m: int = 16,
    n: int = 8,
    colour: ArrayLike | None = None,
) -> str:
    """Sphere of ``radius`` (m) centred at the origin: ``m`` slices, ``n`` faces per half slice.

    Latitude step alpha = pi / (2 n), longitude step beta = 2 pi / m; vertices on the sphere.
    """
    _positive(name, radius=radius)  # its own name in messages (the ellipsoid's: a, b, c)
    return ellipsoid(model, name, radii=(radius, radius, radius), m=m, n=n, colour=colour)


def ellipsoid(
    model: Model,
    name: str,
    *,
    radii: ArrayLike,
    m: int = 16,
    n: int = 8,
    colour: ArrayLike | None = None,
) -> str:
    """Ellipsoid with semi-axes ``radii = (a, b, c)`` (m): a unit sphere's faces scaled unequally."""
    r = _triple(name, "radii (a, b, c)", radii)
    _positive(name, a=float(r[0]), b=float(r[1]), c=float(r[2]))
    m = _count(name, "m", m, 3)
    n = _count(name, "n", n, 1)
    limits.check("max_facets", 4 * m * n, f"sphere or ellipsoid '{name}' (m = {m}, n = {n})")
    surfaces, relations = _sphere_parts(name, m, n, r)
    return build_block(model, name, surfaces, relations, colour=colour)


def cone(
    model: Model,
    name: str,
    *,
    radius: float,
    height: float,
    n: int = 32,
    colour: ArrayLike | None = None,
) -> str:
    """Cone about z, base radius ``radius`` at z=0, apex at z=``height`` (m): a rotational sweep."""
    _positive(name, radius=radius, height=height)
    n = _count(name, "n", n, 3)
    return revolve(model, name, [(0.0, 0.0), (radius, 0.0), (0.0, height)], n=n, colour=colour)


def torus(
    model: Model,
    name: str,
    *,
    major_radius: float,
    minor_radius: float,
    m: int = 32,
    n: int = 16,
    colour: ArrayLike | None = None,
) -> str:
    """Torus about z: an ``n``-gon of ``minor_radius`` centred at ``major_radius`` (m), swept in ``m`` steps."""
    _positive(name, major_radius=major_radius, minor_radius=minor_radius)
    if minor_radius >= major_radius:
        raise GeometryError(
            f"solid '{name}': minor_radius ({minor_radius}) must be smaller than major_radius ({major_radius})"
        )
    m = _count(name, "m", m, 3)
    n = _count(name, "n", n, 3)
    t = 2 * np.pi * np.arange(n) / n
    profile = np.column_stack([major_radius + minor_radius * np.cos(t), minor_radius * np.sin(t)])
    return revolve(model, name, profile, n=m, colour=colour)
