"""What a part rests on: vertical drops onto supports, and a support's top face.

A part *rests* when it cannot move straight down: its drop distance is zero. The drop
distance of a part onto the things below it (static parts, movable parts, the ground; never
robots, which move) is computed exactly on the convex collision pieces the simulator
collides (MuJoCo's meshes in world coordinates): for a part piece A and a support piece B
whose footprints overlap, the largest downward translation before they touch is

    min (a_z - b_z)  over points a of A and b of B on one vertical line,

a small linear program over convex combinations of their vertices (``scipy``'s HiGHS),
which covers every kind of first contact (vertex on face, face on vertex, edge on edge).
Pieces the part already overlaps, or that lie above it, are not supports. The ground is
the plane z = 0 of the compiled cell (any horizontal plane geom at its height).

:func:`top_face` gives a support's top face: the highest upward-facing faces of its world
mesh (their area-weighted centroid, for "centroid over the top face").
Units: metres.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import mujoco
import numpy as np
import trimesh
from numpy.typing import NDArray
from scipy.optimize import linprog

__all__ = ["Drop", "drop", "geom_vertices", "top_face"]

Array = NDArray[np.float64]
_UP = 1.0 - 1e-9  # normal z of an upward face
_TOL = 1e-6  # m: overlaps below this count as touching (meshes are float32 in MuJoCo)


@dataclass(frozen=True)
class Drop:
    """How far (``distance``, m, >= 0) a part can move straight down before it touches
    ``support`` (a thing label: a part name or "ground"); ``distance`` is inf and
    ``support`` None when nothing is below it."""

    distance: float
    support: str | None


def geom_vertices(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> Array:
    """World vertices (k, 3) of collision geom ``g``: a mesh's vertices, or the corners of
    another geom's bounding box (exact for boxes, enclosing for round geoms)."""
    R = data.geom_xmat[g].reshape(3, 3)
    if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
        mid = model.geom_dataid[g]
        a, n = model.mesh_vertadr[mid], model.mesh_vertnum[mid]
        V = np.asarray(model.mesh_vert[a : a + n], dtype=np.float64)
    else:
        c, h = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        V = c + signs * h
    return V @ R.T + data.geom_xpos[g]


def _vertical_gap(A: Array, B: Array) -> float | None:
    """min (a_z - b_z) over vertical lines through both convex hulls of A and B (k, 3),
    or None when their footprints do not overlap."""
    lo = np.maximum(A[:, :2].min(axis=0), B[:, :2].min(axis=0))
    hi = np.minimum(A[:, :2].max(axis=0), B[:, :2].max(axis=0))
    if np.any(lo > hi + _TOL):
        return None
    na, nb = len(A), len(B)
    c = np.concatenate([A[:, 2], -B[:, 2]])
    eq = np.zeros((4, na + nb))
    eq[0, :na], eq[0, na:] = A[:, 0], -B[:, 0]
    eq[1, :na], eq[1, na:] = A[:, 1], -B[:, 1]
    eq[2, :na] = 1.0
    eq[3, na:] = 1.0
    res = linprog(c, A_eq=eq, b_eq=[0.0, 0.0, 1.0, 1.0], bounds=(0, None), method="highs")
    return float(res.fun) if res.status == 0 else None


def drop(pieces: Iterable[Array], supports: Iterable[tuple[str, Array | float]]) -> Drop:
    """The drop of a part made of convex ``pieces`` (world vertices, (k, 3) each) onto
    ``supports``: (label, world vertices of one convex piece) or (label, the height of a
    horizontal plane, m). See the module doc."""
    pieces = [np.asarray(p, dtype=np.float64) for p in pieces]
    best, label = np.inf, None
    for name, B in supports:
        if np.isscalar(B):
            gap = min(float(p[:, 2].min()) for p in pieces) - float(B)  # type: ignore[arg-type]
            if gap >= -_TOL and gap < best:
                best, label = max(gap, 0.0), name
            continue
        B = np.asarray(B, dtype=np.float64)
        for A in pieces:
            gap = _vertical_gap(A, B)
            if gap is None or gap < -_TOL:
                continue  # beside it, under it or overlapping it
            if gap < best:
                best, label = max(gap, 0.0), name
    return Drop(float(best), label)


def top_face(mesh: trimesh.Trimesh) -> tuple[Array, float]:
    """(area-weighted centroid (3,), height) of the highest upward-facing faces of a
    world ``mesh`` (its top face: a table's top, a bin's rim)."""
    up = np.flatnonzero(mesh.face_normals[:, 2] > _UP)
    if len(up) == 0:
        z = float(mesh.vertices[:, 2].max())
        c = mesh.vertices[np.isclose(mesh.vertices[:, 2], z)].mean(axis=0)
        return c, z
    zs = mesh.triangles_center[up, 2]
    top = up[zs >= zs.max() - 1e-9]
    w = mesh.area_faces[top]
    c = (mesh.triangles_center[top] * w[:, None]).sum(axis=0) / w.sum()
    return c, float(zs.max())
