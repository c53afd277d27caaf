"""Boolean (CSG) blocks: union, difference and intersection through manifold3d.

A boolean block keeps its operands as relations to other blocks (so they cannot be
removed while it uses them) and is evaluated in double precision (manifold3d's
``Mesh64``): :func:`union`, :func:`difference` and :func:`intersection` evaluate it when
they create it (a failing or empty result is refused, the model left as it was); the
result is cached and evaluated again when asked for after an operand changed.
"""

from __future__ import annotations

from collections.abc import Sequence

import manifold3d
import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.errors import GeometryError
from workcell.modeller.model import Model
from workcell.modeller.world import place_mesh

__all__ = ["difference", "evaluate_boolean", "intersection", "union"]

Arrays = tuple[NDArray[np.float64], NDArray[np.int64]]


def _manifold(V: NDArray[np.float64], F: NDArray[np.int64], what: str) -> manifold3d.Manifold:
    mesh = manifold3d.Mesh64(
        vert_properties=np.array(V, dtype=np.float64, order="C"),
        tri_verts=np.array(F, dtype=np.uint64, order="C"),
    )
    m = manifold3d.Manifold(mesh)
    if m.status() != manifold3d.Error.NoError:
        raise GeometryError(f"{what} is not a closed manifold solid ({m.status().name})")
    return m


def evaluate_boolean(
    op: str, operands: Sequence[tuple[Arrays, NDArray[np.float64]]], *, name: str
) -> Arrays:
    """Evaluate ``op`` over operand meshes, each (vertices, faces) placed by a 4x4 transform."""
    ms = []
    for i, ((V, F), T) in enumerate(operands):
        Vw, Fw = place_mesh(V, F, T)
        ms.append(_manifold(Vw, Fw, f"operand {i + 1} of boolean block '{name}'"))
    if op == "union":
        out = manifold3d.Manifold.batch_boolean(ms, manifold3d.OpType.Add)
    elif op == "intersection":
        out = manifold3d.Manifold.batch_boolean(ms, manifold3d.OpType.Intersect)
    else:
        out = (
            ms[0] - manifold3d.Manifold.batch_boolean(ms[1:], manifold3d.OpType.Add)
            if len(ms) > 2
            else ms[0] - ms[1]
        )
    res = out.to_mesh64()
    return np.asarray(res.vert_properties, dtype=np.float64)[:, :3].copy(), np.asarray(
        res.tri_verts, dtype=np.int64
    ).copy()


def _make(
    op: str,
    model: Model,
    name: str,
    operands: Sequence[str],
    transforms: Sequence[ArrayLike | None] | None,
    colour: ArrayLike | None,
) -> str:
    model.create_boolean(name, op, list(operands), transforms, colour=colour)
    try:  # evaluated now: a failing or empty result is refused, the model left as it was
        if len(model.world_mesh(("block", name)).faces) == 0:
            raise GeometryError(
                f"boolean block '{name}' is empty: the {op} of {', '.join(map(str, operands))} "
                "leaves no solid"
            )
    except BaseException:
        model.remove(("block", name))
        raise
    return name


def union(
    model: Model,
    name: str,
    *operands: str,
    transforms: Sequence[ArrayLike | None] | None = None,
    colour: ArrayLike | None = None,
) -> str:
    """Block ``name`` = the union of operand blocks (each optionally placed by a transform)."""
    return _make("union", model, name, operands, transforms, colour)


def difference(
    model: Model,
    name: str,
    *operands: str,
    transforms: Sequence[ArrayLike | None] | None = None,
    colour: ArrayLike | None = None,
) -> str:
    """Block ``name`` = the first operand block minus all the others."""
    return _make("difference", model, name, operands, transforms, colour)


def intersection(
    model: Model,
    name: str,
    *operands: str,
    transforms: Sequence[ArrayLike | None] | None = None,
    colour: ArrayLike | None = None,
) -> str:
    """Block ``name`` = the common part of all operand blocks."""
    return _make("intersection", model, name, operands, transforms, colour)
