"""Building blocks out of placed surfaces: planar patches, unit-square and unit-triangle placements.

Every solid of the modeller is a block whose boundary is a list of transformed surfaces,
as in the thesis. Three tools make that cheap:

- :func:`planar_patch` turns an ordered planar 3-D polygon into a 2-D surface plus the
  rigid transform that puts it back (the thesis's "transform built from the corner points");
- :func:`parallelogram_transforms` maps the unit square onto parallelograms (side patches
  of translational sweeps, cylinder facets) with one affine transform each;
- :func:`triangle_transforms` maps the unit right triangle onto arbitrary triangles
  (general sweeps).

:func:`build_block` creates the surfaces and the block in one all-or-nothing step.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.errors import GeometryError, ModelError
from workcell.modeller.model import Model, check_name
from workcell.modeller.surface import Surface

__all__ = [
    "UNIT_SQUARE",
    "UNIT_TRIANGLE",
    "build_block",
    "parallelogram_transforms",
    "planar_patch",
    "planar_patches",
    "triangle_transforms",
]

UNIT_SQUARE = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
UNIT_TRIANGLE = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]


def planar_patches(
    points: ArrayLike, names: list[str]
) -> tuple[list[Surface], NDArray[np.float64]]:
    """Planar 3-D polygons (K, N, 3), each counter-clockwise seen from its front, as surfaces.

    Returns the K surfaces and their rigid placements (K, 4, 4): the origin is each
    polygon's first point, x points along its first edge (which must not be degenerate),
    z is its front normal (Newell's method), so ``T @ (u, v, 0, 1)`` gives back the
    corners. Repeated corners (e.g. a pole) collapse in the surface.
    """
    p = np.asarray(points, dtype=np.float64)
    nxt = np.roll(p, -1, axis=1)
    normal = np.stack(
        [
            np.sum((p[..., 1] - nxt[..., 1]) * (p[..., 2] + nxt[..., 2]), axis=1),
            np.sum((p[..., 2] - nxt[..., 2]) * (p[..., 0] + nxt[..., 0]), axis=1),
            np.sum((p[..., 0] - nxt[..., 0]) * (p[..., 1] + nxt[..., 1]), axis=1),
        ],
        axis=1,
    )
    nn = np.linalg.norm(normal, axis=1)
    x = p[:, 1] - p[:, 0]
    nx = np.linalg.norm(x, axis=1)
    scale = np.maximum(1.0, np.abs(p).max(axis=(1, 2)))
    bad = (nn <= 1e-300) | (nx <= 1e-12 * scale)
    if bad.any():
        k = int(np.argmax(bad))
        raise GeometryError(f"patch '{names[k]}' is degenerate (zero area or zero first edge)")
    z = normal / nn[:, None]
    x = x - z * np.sum(x * z, axis=1, keepdims=True)
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = np.cross(z, x)
    rel = p - p[:, :1]
    off_plane = np.abs(np.einsum("knj,kj->kn", rel, z)).max(axis=1)
    if (off_plane > 1e-9 * scale).any():
        k = int(np.argmax(off_plane > 1e-9 * scale))
        raise GeometryError(
            f"patch '{names[k]}' is not planar (a corner is {off_plane[k]:.3g} m off its plane)"
        )
    uv = np.stack([np.einsum("knj,kj->kn", rel, x), np.einsum("knj,kj->kn", rel, y)], axis=2)
    T = np.zeros((len(p), 4, 4))
    T[:, :3, 0], T[:, :3, 1], T[:, :3, 2], T[:, :3, 3], T[:, 3, 3] = x, y, z, p[:, 0], 1.0
    return Surface.convex_many(uv, names), T


def planar_patch(points: ArrayLike, *, name: str = "patch") -> tuple[Surface, NDArray[np.float64]]:
    """One planar 3-D polygon (N, 3) as (Surface, rigid placement): see :func:`planar_patches`."""
    surfaces, T = planar_patches(np.asarray(points, dtype=np.float64)[None], [name])
    return surfaces[0], T[0]


def _frames(
    e1: NDArray[np.float64], e2: NDArray[np.float64], origin: NDArray[np.float64]
) -> NDArray[np.float64]:
    n = np.cross(e1, e2)
    ln = np.linalg.norm(n, axis=1)
    if (ln <= 1e-300).any():
        raise GeometryError("a patch is degenerate: its two edges are parallel or zero")
    T = np.zeros((len(e1), 4, 4))
    T[:, :3, 0], T[:, :3, 1], T[:, :3, 2], T[:, :3, 3] = e1, e2, n / ln[:, None], origin
    T[:, 3, 3] = 1.0
    return T


def parallelogram_transforms(
    origins: ArrayLike, e1: ArrayLike, e2: ArrayLike
) -> NDArray[np.float64]:
    """Affine maps of the unit square onto parallelograms ``origin + u e1 + v e2`` (N, 4, 4).

    The third column is the unit normal ``e1 x e2 / |e1 x e2|``: the front side faces it.
    """
    o, a, b = (np.atleast_2d(np.asarray(v, dtype=np.float64)) for v in (origins, e1, e2))
    return _frames(a, b, o)


def triangle_transforms(p0: ArrayLike, p1: ArrayLike, p2: ArrayLike) -> NDArray[np.float64]:
    """Affine maps of the unit triangle (0,0),(1,0),(0,1) onto triangles (p0, p1, p2), (N, 4, 4)."""
    a, b, c = (np.atleast_2d(np.asarray(v, dtype=np.float64)) for v in (p0, p1, p2))
    return _frames(b - a, c - a, a)


def build_block(
    model: Model,
    name: str,
    surfaces: dict[str, Surface | str],
    relations: Sequence[tuple[str, ArrayLike]],
    *,
    colour: ArrayLike | None = None,
) -> str:
    """Create block ``name`` from placed surfaces, all or nothing.

    ``surfaces`` maps a key to a new :class:`Surface` (created as ``"{name}.{key}"``) or
    to the name of an existing surface entity (shared, not copied). ``relations`` lists
    (key, transforms (N, 4, 4) or (4, 4)) in order. On any error the model is unchanged.
    """
    check_name(name)
    if name in model.list("block"):
        raise ModelError(f"a block named '{name}' already exists")
    new = {k: f"{name}.{k}" for k, s in surfaces.items() if isinstance(s, Surface)}
    for _k, s in surfaces.items():
        if not isinstance(s, Surface):
            model.surface(("surface", s))  # raises a clear ModelError when unknown
    taken = [n for n in new.values() if n in model.list("surface")]
    if taken:
        raise ModelError(
            f"cannot build block '{name}': surface name(s) {', '.join(taken)} already exist"
        )
    groups = [
        (new.get(key) or surfaces[key], np.asarray(Ts, dtype=np.float64).reshape(-1, 4, 4))
        for key, Ts in relations
    ]
    created: list[str] = []
    try:
        for key, full in new.items():
            model.create("surface", full, surfaces[key])
            created.append(full)
        model.create("block", name, colour=colour)
        created.append(name)
        model.attach_groups(
            ("block", name),
            [(("surface", t), Ts) for t, Ts in groups if len(Ts)],
            return_names=False,
        )
    except Exception:
        for n in reversed(created):
            lvl = "block" if n == name else "surface"
            if model.exists((lvl, n)):
                model.remove((lvl, n))
        raise
    return name
