"""Meshes of modeller blocks for MuJoCo: binary STL bytes and convex collision pieces.

MuJoCo collides a mesh geom through its convex hull, so a non-convex solid needs convex
pieces. The rule (:func:`convex_pieces`):

1. a convex block (hull volume equals its volume within 1e-7 relative) is its own
   piece: the visual mesh asset is reused for collisions;
2. a boolean *union* block: the pieces of each operand, placed by its relation
   (recursively), so a union of convex primitives collides exactly;
3. anything else (a non-convex sweep, a difference or intersection): the convex hull
   of the whole block: conservative (it fills holes and notches) but never lets parts
   pass through each other. Build such parts from convex blocks where that matters.

Units: metres.
"""

from __future__ import annotations

import trimesh
from scipy.spatial import ConvexHull, QhullError

from workcell.modeller.model import Model

__all__ = ["convex_pieces", "is_convex", "stl_bytes"]

_CONVEX_REL_TOL = 1e-7


def is_convex(mesh: trimesh.Trimesh, rel_tol: float = _CONVEX_REL_TOL) -> bool:
    """True when the closed mesh fills its convex hull (volumes equal within ``rel_tol``)."""
    v = float(mesh.volume)
    try:
        hull = float(ConvexHull(mesh.vertices).volume)
    except QhullError:  # flat or degenerate: no volume to fill
        return False
    return v > 0 and hull - v <= rel_tol * hull


def convex_pieces(model: Model, block: str) -> tuple[list[trimesh.Trimesh], bool]:
    """Convex collision pieces of ``block`` in its own frame, and whether the block is convex.

    See the module doc for the rule. A convex block returns its own (cached) world mesh.
    """
    mesh = model.world_mesh(("block", block))
    if is_convex(mesh):
        return [mesh], True
    if model.info(("block", block)).boolean == "union":
        pieces: list[trimesh.Trimesh] = []
        for rel in model.relations(("block", block)):
            sub, _ = convex_pieces(model, rel.target)
            pieces.extend(p.copy().apply_transform(rel.transform) for p in sub)
        return pieces, False
    return [mesh.convex_hull], False


def stl_bytes(mesh: trimesh.Trimesh) -> bytes:
    """Binary STL of ``mesh`` (float32 vertices: 84 + 50 x faces bytes)."""
    return mesh.export(file_type="stl")
