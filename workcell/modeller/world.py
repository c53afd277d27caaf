"""World coordinates generator (thesis §3): flatten the hierarchy into meshes in world coordinates.

entity = union over its relations j of T_j(target entity). A block's placed surfaces are
welded into one closed triangle mesh (coincident vertices merged, winding made
consistent and outward); objects and scenes are the concatenation of their placed
blocks. Results are cached on each entity and dropped by the model whenever the entity
or anything it is made of changes.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import groupby
from typing import TYPE_CHECKING

import numpy as np
import trimesh
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from workcell import limits
from workcell.errors import GeometryError
from workcell.modeller.entities import _target_counts
from workcell.modeller.hashgroup import first_of_equal, has_repeat
from workcell.modeller.meshprops import MassProperties, mass_properties, orient_consistently
from workcell.spatial import det3

if TYPE_CHECKING:
    from workcell.modeller.entities import _Entity

__all__ = ["WorldPart", "facet_estimate", "merge_vertices", "place_mesh"]

DEFAULT_COLOUR = (0.7, 0.7, 0.72, 1.0)
_MERGE_REL = 1e-9  # vertices closer than this fraction of the mesh size are one vertex


@dataclass(frozen=True)
class WorldPart:
    """One placed block in world coordinates.

    ``path`` is the chain of relation names from the root entity (``"to1/tb2"``),
    ``transform`` maps the block's frame to world (4x4, m), ``mesh`` is in world
    coordinates, ``colour`` is RGBA in [0, 1].
    """

    path: str
    block: str
    object: str | None
    colour: tuple[float, ...]
    movable: bool
    transform: NDArray[np.float64]
    mesh: trimesh.Trimesh


def merge_vertices(
    vertices: NDArray[np.float64], faces: NDArray[np.int64], rel_tol: float = _MERGE_REL
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.bool_]]:
    """Weld vertices closer than ``rel_tol`` x the mesh's largest extent; drop collapsed faces.

    Returns (vertices, faces, kept) where ``kept`` marks the input faces that survived.
    Each output vertex is the first input vertex of its weld group, in input order.

    Rounds to a grid, then re-checks the few vertices that lie near a rounding boundary
    with a k-d tree, so two copies of one point are merged even when rounding splits them.
    """
    if len(vertices) == 0:
        return vertices.reshape(0, 3), faces.reshape(0, 3), np.ones(len(faces), bool)
    # column by column on purpose: axis reductions over (N, 3) rows are several times slower
    n = len(vertices)
    cols = [vertices[:, k] for k in range(3)]
    lo = [float(c.min()) for c in cols]
    cell = max(max(float(c.max()) - m for c, m in zip(cols, lo, strict=True)), 1e-12) * rel_tol
    q = np.empty((3, n), dtype=np.int64)  # grid cell of each vertex
    near_mask = np.zeros(n, dtype=bool)
    buf, r = np.empty(n), np.empty(n)
    for k in range(3):
        np.subtract(cols[k], lo[k], out=buf)
        buf *= 1.0 / cell
        np.rint(buf, out=r)
        q[k] = r
        buf -= r
        np.abs(buf, out=buf)
        near_mask |= buf > 0.499
    label = first_of_equal(q)  # exact: equal cells, not equal hashes
    new = label == np.arange(n)
    first = np.flatnonzero(new)  # first occurrences, in input order
    inv = (np.cumsum(new) - 1)[label]
    near = np.flatnonzero(near_mask)
    if len(near) > 1:  # a point near a rounding boundary may have a twin rounded the other way
        # pair the near-boundary points themselves: a cell's representative may lie up to
        # a cell diagonal away from the twin, beyond the query radius
        pairs = cKDTree(vertices[near]).query_pairs(cell, output_type="ndarray")
        ga, gb = inv[near[pairs[:, 0]]], inv[near[pairs[:, 1]]]
        split = ga != gb  # twins the rounding already put in one cell need nothing
        if split.any():
            g = coo_matrix(
                (np.ones(int(split.sum())), (ga[split], gb[split])),
                shape=(len(first), len(first)),
            )
            _, comp = connected_components(g, directed=False)
            _, first_c, inv_c = np.unique(comp, return_index=True, return_inverse=True)
            # number the merged vertices by their first occurrence again
            rank = np.empty(len(first_c), dtype=np.int64)
            rank[np.argsort(first_c)] = np.arange(len(first_c))
            first = first[np.sort(first_c)]
            inv = rank[inv_c.ravel()][inv]
    V = vertices[first]
    F = inv.take(faces)
    ok = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0])
    return V, (F if ok.all() else F[ok]), ok


def _place(
    V: NDArray[np.float64],
    F: NDArray[np.int64],
    Ts: NDArray[np.float64],
    flip: NDArray[np.bool_] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Copies of (V, F) under each transform of Ts (N, 4, 4); winding kept outward under reflection.

    ``V`` is one vertex set (P, 3) shared by every copy, or one per copy (N, P, 3) with the
    same faces. ``flip`` (N,) marks the orientation-reversing transforms when known.
    """
    # written out per output coordinate on (P, N) views, so that numpy's inner loops run
    # over the N copies (batched 3x3 matmul is slower for small matrices, and so are
    # broadcasts whose inner loops are three or P long)
    Vw = np.empty((len(Ts), V.shape[-2], 3))
    Vc = [V[..., k].T if V.ndim == 3 else V[:, k, None] for k in range(3)]  # (P, N), (P, 1)
    for c in range(3):
        o = Vw[..., c].T
        np.multiply(Vc[0], Ts[:, c, 0], out=o)
        o += Vc[1] * Ts[:, c, 1]
        o += Vc[2] * Ts[:, c, 2]
        o += Ts[:, c, 3]
    offs = (np.arange(len(Ts)) * V.shape[-2])[:, None, None]
    Fw = F + offs
    if flip is None:
        flip = det3(Ts) < 0
    if flip.any():
        Fw[flip] = Fw[flip][:, :, ::-1]
    return Vw.reshape(-1, 3), Fw.reshape(-1, 3)


def place_mesh(
    V: NDArray[np.float64], F: NDArray[np.int64], T: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """One mesh (V, F) placed by a 4x4 transform T; faces turned over under a reflection."""
    return _place(V, F, T[None])


def _group(
    targets: list, Ts: NDArray[np.float64]
) -> list[tuple[object, NDArray[np.float64], NDArray[np.int64]]]:
    """Group relations by target: (target, transforms, relation indices), in first-seen order."""
    if not targets:
        return []
    # runs of one target (entities compare by identity), counted in C
    runs = [(t, len(list(g))) for t, g in groupby(targets)]
    if len({id(t) for t, _ in runs}) == len(runs):  # each target in one contiguous run
        out, a = [], 0
        for t, k in runs:
            out.append((t, Ts[a : a + k], np.arange(a, a + k)))
            a += k
        return out
    ids = np.fromiter(map(id, targets), dtype=np.int64, count=len(targets))
    _, first, inv = np.unique(ids, return_index=True, return_inverse=True)
    order = np.argsort(inv, kind="stable")
    ends = np.cumsum(np.bincount(inv))
    starts = ends - np.bincount(inv)
    out = []
    for k in np.argsort(first):
        idx = order[starts[k] : ends[k]]
        out.append((targets[first[k]], Ts[idx], idx))
    return out


def _outward(V: NDArray[np.float64], F: NDArray[np.int64]) -> bool:
    """Fast test: no directed edge is used twice (consistent winding) and the volume is positive."""
    if len(F) == 0:
        return True
    i, j, k = (np.ascontiguousarray(F[:, c]) for c in range(3))
    m, nv = len(F), np.int64(len(V))
    key = np.empty(3 * m, dtype=np.int64)  # directed edges (a, b) as a * nv + b
    for part, (a, b) in enumerate(((i, j), (j, k), (k, i))):
        np.multiply(a, nv, out=key[part * m : (part + 1) * m])
        key[part * m : (part + 1) * m] += b
    if has_repeat(key):
        return False
    # six times the signed volume, sum of a . (b x c) over faces, about the vertex mean;
    # gathered column by column (row gathers of (M, 3) arrays are several times slower);
    # summed without BLAS: a threaded dot waits tens of ms for its threads on a busy machine
    x, y, z = (V[:, c] - V[:, c].mean() for c in range(3))
    yj, zj, yk, zk = y[j], z[j], y[k], z[k]
    six = x[i] * (yj * zk - zj * yk)
    six += y[i] * (zj * x[k] - x[j] * zk)
    six += z[i] * (x[j] * yk - yj * x[k])
    return float(six.sum()) > 0


def _surface_arrays(e: _Entity) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    V2, F = e.surface.triangulate()
    V = np.zeros((len(V2), 3))
    V[:, :2] = V2
    return V, F


def _block_arrays(e: _Entity) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Closed, outward-wound mesh of a block in its own frame. Cached."""
    hit = e.cache.get("arrays")
    if hit is not None:
        return hit
    if e.boolean:
        from workcell.modeller.csg import evaluate_boolean

        ops = [(_block_arrays(t), T) for t, T in zip(e.rels.targets, e.rels.T, strict=True)]
        V, F = evaluate_boolean(e.boolean, ops, name=e.name)
        e.cache["flipped"] = []
    else:
        Vs, Fs, rel_of_face = [], [], []
        base = 0
        flips = det3(e.rels.T) < 0
        # surfaces with the same triangulation (e.g. all quads) are placed in one batch
        shapes: dict[tuple[int, bytes], list] = {}
        for t, Ts, idx in _group(e.rels.targets, e.rels.T):
            SV, SF = _surface_arrays(t)
            shapes.setdefault((len(SV), SF.tobytes()), []).append((SV, SF, Ts, idx))
        for members in shapes.values():
            SF = members[0][1]
            idx = np.concatenate([m[3] for m in members])
            if len(members) == 1:
                SV = members[0][0]
            else:
                which = np.repeat(np.arange(len(members)), [len(m[3]) for m in members])
                SV = np.stack([m[0] for m in members])[which]
            Vw, Fw = _place(SV, SF, e.rels.T[idx], flips[idx])
            Vs.append(Vw)
            Fs.append(Fw + base)
            rel_of_face.append(np.repeat(idx, len(SF)))
            base += len(Vw)
        if not Vs:
            V, F = np.zeros((0, 3)), np.zeros((0, 3), np.int64)
            rel = np.zeros(0, np.int64)
        else:
            V, F, kept = merge_vertices(np.concatenate(Vs), np.concatenate(Fs))
            rel = np.concatenate(rel_of_face)[kept]
        if _outward(V, F):
            e.cache["flipped"] = []
        else:
            F, flipped = orient_consistently(V, F)
            e.cache["flipped"] = sorted({e.rels.names[i] for i in np.unique(rel[flipped])})
    V.flags.writeable = False
    F.flags.writeable = False
    e.cache["arrays"] = (V, F)
    return V, F


def reoriented_relations(e: _Entity) -> list[str]:
    """Names of a block's relations whose surfaces were turned over to face outward."""
    _block_arrays(e)
    return e.cache["flipped"]


def _placed_blocks(e: _Entity) -> list[tuple[str, _Entity, _Entity | None, NDArray[np.float64]]]:
    """(path, block, object, world transform) of every block instance under ``e``."""
    if e.level == "block":
        return [(e.name, e, None, np.eye(4))]
    if e.level == "object":
        return [
            (n, b, e, T) for n, b, T in zip(e.rels.names, e.rels.targets, e.rels.T, strict=True)
        ]
    if e.level == "scene":
        out = []
        for n, o, T in zip(e.rels.names, e.rels.targets, e.rels.T, strict=True):
            out.extend(
                (f"{n}/{m}", b, o, T @ Tb)
                for m, b, Tb in zip(o.rels.names, o.rels.targets, o.rels.T, strict=True)
            )
        return out
    raise GeometryError(f"{e.label} has no placed blocks")


def facet_estimate(e: _Entity) -> int:
    """Triangles of the entity's world mesh, counted from its relations without meshing
    (a surface of n contour points and h holes: n - 2 + 2 h; a boolean: its operands').
    Cached."""
    hit = e.cache.get("facets")
    if hit is None:
        if e.level == "surface":
            hit = e.surface.n_edges - 2 + 2 * len(e.surface.holes)
        else:
            hit = sum(facet_estimate(t) * n for t, n in _target_counts(e).items())
        e.cache["facets"] = hit
    return hit


def _check_facets(e: _Entity) -> None:
    """Refuse (LimitError) to mesh an entity of more than ``max_facets`` triangles."""
    if "arrays" not in e.cache and "mesh" not in e.cache:
        limits.check("max_facets", facet_estimate(e), f"the mesh of {e.label}")


def _arrays(e: _Entity) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    if e.level == "surface":
        return _surface_arrays(e)
    _check_facets(e)
    if e.level == "block":
        return _block_arrays(e)
    placed = _placed_blocks(e)
    if not placed:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    Vs, Fs, base = [], [], 0
    for b, Ts, _ in _group([p[1] for p in placed], np.stack([p[3] for p in placed])):
        V, F = _place(*_block_arrays(b), Ts)
        Vs.append(V)
        Fs.append(F + base)
        base += len(V)
    return np.concatenate(Vs), np.concatenate(Fs)


def entity_mesh(e: _Entity) -> trimesh.Trimesh:
    """The entity as one world-coordinate Trimesh (objects/scenes: parts concatenated). Cached."""
    hit = e.cache.get("mesh")
    if hit is None:
        V, F = _arrays(e)
        hit = trimesh.Trimesh(vertices=V, faces=F, process=False, validate=False)
        hit.metadata.update({"name": e.name, "level": e.level})
        e.cache["mesh"] = hit
    return hit


def entity_parts(e: _Entity) -> list[WorldPart]:
    """One WorldPart per placed block of ``e``, carrying its source names and colour. Cached."""
    hit = e.cache.get("parts")
    if hit is None:
        _check_facets(e)
        hit = []
        for path, b, o, T in _placed_blocks(e):
            Vw, Fw = place_mesh(*_block_arrays(b), T)
            colour = b.colour or (o.colour if o is not None else None) or e.colour or DEFAULT_COLOUR
            movable = b.movable or (o is not None and o.movable)
            mesh = trimesh.Trimesh(vertices=Vw, faces=Fw, process=False, validate=False)
            mesh.metadata.update({"name": path, "block": b.name})
            T = T.copy()
            T.flags.writeable = False
            hit.append(
                WorldPart(path, b.name, None if o is None else o.name, colour, movable, T, mesh)
            )
        e.cache["parts"] = hit
    return list(hit)


def entity_properties(e: _Entity) -> MassProperties:
    """Geometric properties of ``e`` (unit density; objects and scenes sum their parts)."""
    hit = e.cache.get("props")
    if hit is None:
        if e.level == "surface":
            s = e.surface
            V2, F = s.triangulate()
            tri = V2[F]
            u, w = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
            a = 0.5 * (u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0])  # 2-D np.cross is deprecated
            c2 = (a[:, None] * tri.mean(axis=1)).sum(axis=0) / a.sum()
            z = np.zeros(3)
            hit = MassProperties(
                float(s.area), 0.0, np.array([c2[0], c2[1], 0.0]), z, np.zeros((3, 3))
            )
        else:
            hit = mass_properties(*_arrays(e))
        e.cache["props"] = hit
    return hit
