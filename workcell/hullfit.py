"""Whether a mesh's convex hull can stand for it: how far the hull strays from the mesh.

MuJoCo collides a mesh as its convex hull. For a mesh that is nearly convex (a robot
link with a shallow recess) the hull is as good as convex pieces would be and costs no
decomposition: :func:`hull_deviation` measures how far the hull strays (its largest
distance from the mesh's surface, and the volume it adds), and a :class:`HullFit` says
how far it may (:mod:`workcell.decompose` checks it before running CoACD). Units: the
distance as a fraction of the mesh's bounding-box diagonal, the volume as a fraction of
the mesh's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh
from scipy.spatial import cKDTree

__all__ = ["HullFit", "hull_deviation"]

_SPACING = 0.005  # the mesh's sampling step, x its bounding-box diagonal
_NEAR = 8  # facets of this many nearest samples are measured exactly
_SEED = 0


@dataclass(frozen=True)
class HullFit:
    """When a mesh's convex hull stands for it, with no decomposition: the hull lies
    within ``distance`` x the mesh's bounding-box diagonal of the mesh's surface
    everywhere (the one-sided Hausdorff distance from the hull's surface to the mesh's),
    and, for a closed mesh, adds at most ``volume`` x the mesh's volume (an open mesh has
    no volume: the distance alone decides). See :func:`hull_deviation`."""

    distance: float
    volume: float


def hull_deviation(mesh: trimesh.Trimesh) -> tuple[float, float | None]:
    """How far the convex hull of ``mesh`` strays from it: (the largest distance from the
    hull's surface to the mesh's surface / the mesh's bounding-box diagonal, the hull's
    volume over the mesh's minus 1, or None for a mesh that is not closed).

    The distance is measured from points on the hull's surface (its facets' centres and
    5,000 samples) to the mesh's facets, exactly to the facets of the :data:`_NEAR`
    nearest of dense samples of the mesh's surface (a step of :data:`_SPACING` = 0.5 % of
    the diagonal, every facet's centre included): never below the true distance at those
    points; the points themselves may miss the farthest spot by about their spacing.
    Seeded: the same mesh gives the same numbers. Units: none (ratios)."""
    hull = mesh.convex_hull
    diag = float(np.linalg.norm(mesh.extents))
    if diag <= 0:
        return 0.0, None
    n = int(np.clip(mesh.area / (_SPACING * diag) ** 2, 2000, 200_000))
    points, faces = trimesh.sample.sample_surface(mesh, n, seed=_SEED)
    points = np.vstack([points, mesh.triangles_center])
    faces = np.concatenate([faces, np.arange(len(mesh.faces))])
    on_hull = np.vstack(
        [trimesh.sample.sample_surface(hull, 5000, seed=_SEED)[0], hull.triangles_center]
    )
    near = faces[cKDTree(points).query(on_hull, k=_NEAR)[1]]  # (m, k) candidate facets
    P = np.repeat(on_hull, _NEAR, axis=0)
    Q = trimesh.triangles.closest_point(mesh.triangles[near.ravel()], P)
    far = float(np.linalg.norm(P - Q, axis=1).reshape(-1, _NEAR).min(axis=1).max()) / diag
    closed = mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    return far, (float(hull.volume / mesh.volume) - 1.0 if closed else None)
