"""Self-intersections of a triangle mesh: an AABB-tree broad phase, exact narrow phase.

:func:`self_intersections` finds every pair of faces that intersect (the check behind
:func:`~workcell.modeller.meshprops.validity_report`). The broad phase descends a complete
binary tree of boxes over Morton-ordered face centres on both sides at once; the narrow
phase tests triangle pairs exactly: the interval test on the line where two planes meet,
a 2-D separating-axis test for coplanar pairs. Coordinates are metres, vectorised in numpy.
"""

from __future__ import annotations

import numpy as np

__all__ = ["self_intersections"]

_REL_EPS = 1e-9  # distances below this fraction of the triangle size count as zero
_LEAF = 4  # triangles per leaf of the broad-phase AABB tree
_CHUNK = 1 << 14  # leaf pairs expanded at once (bounds memory to a few tens of MB)
# children of a node pair (a, a) and (a, b) in a heap-numbered tree: 2a + offset
_SELF_A, _SELF_B = np.array([0, 1, 0]), np.array([0, 1, 1])
_PAIR_A, _PAIR_B = np.array([0, 0, 1, 1]), np.array([0, 1, 0, 1])


def _spread_bits(x: np.ndarray) -> np.ndarray:
    """Spread the low 10 bits of x so that two zero bits follow each (Morton code)."""
    for shift, mask in ((16, 0x030000FF), (8, 0x0300F00F), (4, 0x030C30C3), (2, 0x09249249)):
        x = (x | (x << np.uint64(shift))) & np.uint64(mask)
    return x


def _overlap(box: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether boxes a and b overlap; ``box`` rows are (xmin, ymin, zmin, xmax, ymax, zmax)."""
    p, q = box[a], box[b]
    ok = (p[:, 0] <= q[:, 3]) & (q[:, 0] <= p[:, 3])
    for k in (1, 2):
        ok &= (p[:, k] <= q[:, k + 3]) & (q[:, k] <= p[:, k + 3])
    return ok


def _union(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    return np.hstack([np.minimum(p[:, :3], q[:, :3]), np.maximum(p[:, 3:], q[:, 3:])])


def _candidate_pairs(box: np.ndarray) -> np.ndarray:
    """All pairs (i, j), i < j, of overlapping boxes (K, 6), found by descending a complete
    binary AABB tree over Morton-ordered box centres on both sides at once. The work grows
    with the number of overlapping node pairs, not with the spread of box sizes."""
    k = len(box)
    if k < 2:
        return np.zeros((0, 2), np.int64)
    centre = 0.5 * (box[:, :3] + box[:, 3:])
    span = np.ptp(centre, axis=0)
    q = ((centre - centre.min(axis=0)) / np.where(span > 0, span, 1.0) * 1023).astype(np.uint64)
    code = _spread_bits(q[:, 0]) << np.uint64(2) | _spread_bits(q[:, 1]) << np.uint64(1)
    size = 1 << max(0, (-(-k // _LEAF) - 1).bit_length())  # leaves, a power of two
    slot = np.full((size, _LEAF), -1, np.int64)
    slot.flat[:k] = np.argsort(code | _spread_bits(q[:, 2]), kind="stable")
    empty = np.array([np.inf] * 3 + [-np.inf] * 3)
    node = np.where(slot[:, 0, None] >= 0, box[slot[:, 0]], empty)
    for c in range(1, _LEAF):
        node = _union(node, np.where(slot[:, c, None] >= 0, box[slot[:, c]], empty))
    levels = [node]
    while len(levels[-1]) > 1:
        levels.append(_union(levels[-1][0::2], levels[-1][1::2]))
    a = b = np.zeros(1, np.int64)
    for node in levels[-2::-1]:  # children of the current node pairs, level by level
        same = a == b
        s, ra, rb = 2 * a[same, None], 2 * a[~same, None], 2 * b[~same, None]
        a = np.concatenate([(s + _SELF_A).ravel(), (ra + _PAIR_A).ravel()])
        b = np.concatenate([(s + _SELF_B).ravel(), (rb + _PAIR_B).ravel()])
        keep = _overlap(node, a, b)
        a, b = a[keep], b[keep]
    gi, gj = np.divmod(np.arange(_LEAF * _LEAF), _LEAF)
    out = [np.zeros((0, 2), np.int64)]
    for c in range(0, len(a), _CHUNK):  # expand leaf pairs to triangle pairs
        la, lb = a[c : c + _CHUNK, None], b[c : c + _CHUNK, None]
        ti, tj = slot[la, gi].ravel(), slot[lb, gj].ravel()
        keep = (ti >= 0) & (tj >= 0) & ((la != lb) | (gi < gj)).ravel()
        ti, tj = ti[keep], tj[keep]
        keep = _overlap(box, ti, tj)
        out.append(np.column_stack([np.minimum(ti, tj), np.maximum(ti, tj)])[keep])
    return np.concatenate(out)


def _interval(p: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Extent, along the line of the two planes, of a triangle's cut by the other plane:
    ``p`` are corner coordinates along the line's dominant axis, ``d`` signed distances."""
    pn, dn = np.roll(p, -1, axis=1), np.roll(d, -1, axis=1)
    cross = d * dn < 0
    t = p + (pn - p) * d / np.where(cross, d - dn, 1.0)
    lo = np.minimum(np.where(cross, t, np.inf), np.where(d == 0, p, np.inf)).min(axis=1)
    hi = np.maximum(np.where(cross, t, -np.inf), np.where(d == 0, p, -np.inf)).max(axis=1)
    return lo, hi


_KEEP_2D = np.array([[1, 2], [0, 2], [0, 1]])


def _coplanar_overlap(P: np.ndarray, normal: np.ndarray, eps: np.ndarray) -> np.ndarray:
    """Whether coplanar triangles P[:, :3], P[:, 3:] overlap in area (touching does not
    count): separating-axis test on the six edge normals after dropping the dominant axis."""
    q = np.take_along_axis(P, _KEEP_2D[np.abs(normal).argmax(axis=1)][:, None, :], axis=2)
    u, w = q[:, :3], q[:, 3:]
    e = np.concatenate([np.roll(u, -1, axis=1) - u, np.roll(w, -1, axis=1) - w], axis=1)
    ax = np.stack([-e[..., 1], e[..., 0]], axis=-1)
    ax /= np.maximum(np.linalg.norm(ax, axis=-1, keepdims=True), 1e-300)
    proj = [ax[..., 0] * q[:, None, k, 0] + ax[..., 1] * q[:, None, k, 1] for k in range(6)]
    umin, umax = (
        np.minimum(np.minimum(*proj[:2]), proj[2]),
        np.maximum(np.maximum(*proj[:2]), proj[2]),
    )
    wmin, wmax = (
        np.minimum(np.minimum(*proj[3:5]), proj[5]),
        np.maximum(np.maximum(*proj[3:5]), proj[5]),
    )
    sep = (umax <= wmin + eps[:, None]) | (wmax <= umin + eps[:, None])
    return ~sep.any(axis=1)


def _pair_hits(
    t: np.ndarray, n: np.ndarray, f: np.ndarray, i: np.ndarray, j: np.ndarray, eps: np.ndarray
) -> np.ndarray:
    """Narrow phase for face pairs (i, j) of corners t (M, 3, 3), unit normals n, faces f."""
    U, V, nU, nV = t[i], t[j], n[i], n[j]
    dU = np.einsum("kpi,ki->kp", U - V[:, :1], nV)
    dV = np.einsum("kpi,ki->kp", V - U[:, :1], nU)
    dU[np.abs(dU) <= eps[:, None]] = 0.0
    dV[np.abs(dV) <= eps[:, None]] = 0.0
    apart = np.zeros(len(U), dtype=bool)
    for d in (dU, dV):
        apart |= (d > 0).all(axis=1) | (d < 0).all(axis=1)
    flat_u, flat_v = ~dU.any(axis=1), ~dV.any(axis=1)
    hit = np.zeros(len(U), dtype=bool)
    sel = np.flatnonzero(~apart & (flat_u | flat_v))
    normal = np.where(flat_v[sel, None], nU[sel], nV[sel])
    hit[sel] = _coplanar_overlap(np.concatenate([U[sel], V[sel]], axis=1), normal, eps[sel])
    sel = np.flatnonzero(~apart & ~(flat_u | flat_v))
    fi, fj = f[i[sel]], f[j[sel]]
    shared = sum((fi[:, a] == fj[:, b]).astype(np.int8) for a in range(3) for b in range(3))
    sel = sel[shared < 2]  # non-coplanar faces sharing an edge meet only on that edge
    axis = np.abs(np.cross(nU[sel], nV[sel])).argmax(axis=1)[:, None, None]
    lo1, hi1 = _interval(np.take_along_axis(U[sel], axis, 2)[..., 0], dU[sel])
    lo2, hi2 = _interval(np.take_along_axis(V[sel], axis, 2)[..., 0], dV[sel])
    overlap = np.minimum(hi1, hi2) - np.maximum(lo1, lo2)
    hit[sel] = np.where(shared[shared < 2] == 1, overlap > eps[sel], overlap >= 0)
    return hit


def self_intersections(t: np.ndarray, f: np.ndarray, use: np.ndarray) -> np.ndarray:
    """Intersecting face pairs (P, 2), i < j, among faces ``use`` of centred corners ``t``."""
    idx = np.flatnonzero(use)
    tri, fu = t[idx], f[idx]
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    pairs = _candidate_pairs(np.hstack([lo, hi]))
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    size = (hi - lo).max(axis=1)
    floor = 1e-15 * (np.abs(t).max() if t.size else 0.0)
    hits = [np.zeros((0, 2), np.int64)]
    for c in range(0, len(pairs), 1 << 17):
        i, j = pairs[c : c + (1 << 17)].T
        eps = _REL_EPS * np.maximum(size[i], size[j]) + floor
        hits.append(np.column_stack([idx[i], idx[j]])[_pair_hits(tri, normal, fu, i, j, eps)])
    out = np.concatenate(hits)
    return out[np.lexsort(out.T[::-1])]
