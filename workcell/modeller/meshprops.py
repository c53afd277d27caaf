"""Mass properties, orientation repair and validity checks for triangle meshes.

Pure, numpy-vectorised functions on a mesh given as ``vertices`` (N, 3) float64 in metres
and ``faces`` (M, 3) int64, each face counter-clockwise seen from outside (outward normal):
:func:`polygon_area` (2-D shoelace area), :func:`mass_properties` (exact volume, centroid
and inertia by the divergence theorem), :func:`orient_consistently` (consistent winding,
closed shells outward) and :func:`validity_report` (watertightness, winding, volume sign,
degenerate faces, self-intersections: :mod:`~workcell.modeller.selfintersect`). Edges are
matched by vertex index, so duplicated vertices must be merged first.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import breadth_first_order, connected_components

from workcell.errors import GeometryError
from workcell.modeller.selfintersect import self_intersections

__all__ = [
    "MassProperties",
    "ValidityReport",
    "mass_properties",
    "orient_consistently",
    "polygon_area",
    "validity_report",
]

_CAP = 10  # indices listed per problem sentence


def _as_mesh(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces)
    v = v.reshape(0, 3) if v.size == 0 else v
    f = np.zeros((0, 3), np.int64) if f.size == 0 else f
    if v.ndim != 2 or v.shape[1] != 3:
        raise GeometryError(f"vertices must have shape (N, 3), got {v.shape}")
    if f.ndim != 2 or f.shape[1] != 3 or not np.issubdtype(f.dtype, np.integer):
        raise GeometryError(f"faces must be integers of shape (M, 3), got {f.dtype} {f.shape}")
    f = f.astype(np.int64, copy=False)
    if f.size and (f.min() < 0 or f.max() >= len(v)):
        raise GeometryError(f"face indices must lie in [0, {len(v) - 1}]")
    if not np.isfinite(v).all():
        raise GeometryError("vertices must be finite (found NaN or infinity)")
    return v, f


def _centred_triangles(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Face corners (M, 3, 3) relative to the mean face corner, for conditioning."""
    tri = v[f]
    return tri - tri.reshape(-1, 3).mean(axis=0) if len(f) else tri


def _tet6(t: np.ndarray) -> np.ndarray:
    """Six times the signed volume of each tetrahedron (origin, a, b, c)."""
    return np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2]))


def polygon_area(points: np.ndarray) -> float:
    """Signed area (m^2) of a closed 2-D polygon given as (N, 2) points in metres.

    The closing point must not be repeated. Uses A = 1/2 sum(x_i y_{i+1} - x_{i+1} y_i)
    (after centring, which the formula is invariant to); positive for counter-clockwise.
    """
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2:
        raise GeometryError(f"polygon points must have shape (N, 2), got {p.shape}")
    if len(p) < 3:
        return 0.0
    x, y = (p - p.mean(axis=0)).T
    return float(0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


@dataclass(frozen=True, eq=False)
class MassProperties:
    """Mass properties of a solid of unit density (multiply by kg/m^3 for mass units).

    ``area`` surface area (m^2); ``volume`` signed volume (m^3); ``centroid`` (3,) (m);
    ``first_moments`` (3,) = volume * centroid (m^4); ``inertia`` (3, 3) about the centroid
    in world axes (m^5, i.e. kg m^2 per kg/m^3) with Ixx = integral of (y^2 + z^2) dV and
    Ixy = -integral of x y dV, the convention of trimesh's ``moment_inertia``.
    """

    area: float
    volume: float
    centroid: np.ndarray
    first_moments: np.ndarray
    inertia: np.ndarray

    def __post_init__(self) -> None:
        for name in ("centroid", "first_moments", "inertia"):
            arr = np.array(getattr(self, name), dtype=np.float64)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    def inertia_about(self, point: np.ndarray) -> np.ndarray:
        """Inertia tensor (m^5, unit density) about ``point`` (m), world axes (parallel axis)."""
        d = self.centroid - np.asarray(point, dtype=np.float64)
        return self.inertia + self.volume * (d @ d * np.eye(3) - np.outer(d, d))

    @property
    def principal_moments(self) -> np.ndarray:
        """Principal moments of inertia about the centroid (m^5), ascending."""
        return np.linalg.eigvalsh(self.inertia)


def mass_properties(vertices: np.ndarray, faces: np.ndarray) -> MassProperties:
    """Exact mass properties (unit density) of a closed, consistently oriented mesh.

    By the divergence theorem the solid is a sum of signed tetrahedra (reference point,
    a, b, c), one per face, with the reference point at the mean face corner so that
    meshes far from the origin do not lose digits. For a tetrahedron with corners
    0, a, b, c and D = a . (b x c): integral of 1 = D/6, of x_i = D (a+b+c)_i / 24, and of
    x_i x_j = D (a_i a_j + b_i b_j + c_i c_j + s_i s_j) / 120 with s = a + b + c. This is
    exact for any closed polyhedron, holes (genus > 0) and several shells included.
    An inside-out mesh gives negative volume and inertia. If the volume is zero (flat or
    empty mesh) the centroid is the reference point (the origin for an empty mesh).
    """
    v, f = _as_mesh(vertices, faces)
    if len(f) == 0:
        return MassProperties(0.0, 0.0, np.zeros(3), np.zeros(3), np.zeros((3, 3)))
    tri = v[f]
    ref = tri.reshape(-1, 3).mean(axis=0)
    t = tri - ref
    area = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum()
    det = _tet6(t)
    corners = np.concatenate([t.transpose(1, 0, 2), t.sum(axis=1)[None]])  # (4, M, 3)
    volume = det.sum() / 6.0
    first = det @ corners[3] / 24.0
    second = np.einsum("k,pki,pkj->ij", det, corners, corners) / 120.0
    g = first / volume if volume != 0.0 else np.zeros(3)
    cov = second - volume * np.outer(g, g)  # integral of x x^T about the centroid
    inertia = np.trace(cov) * np.eye(3) - cov
    centroid = ref + g
    return MassProperties(float(area), float(volume), centroid, volume * centroid, inertia)


def _edge_groups(f: np.ndarray, n_vertices: int) -> tuple[np.ndarray, ...]:
    """Half-edges (3M, 2), their undirected-edge group, group keys and use counts."""
    he = f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    key = he.min(axis=1) * max(n_vertices, 1) + he.max(axis=1)
    keys, group, count = np.unique(key, return_inverse=True, return_counts=True)
    return he, group.ravel(), keys, count


def _manifold_pairs(group: np.ndarray, count: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two half-edge indices of every edge used by exactly two faces."""
    order = np.argsort(group, kind="stable")
    start = np.cumsum(count) - count
    two = start[count == 2]
    return order[two], order[two + 1]


def _flip(f: np.ndarray, mask: np.ndarray) -> np.ndarray:
    return np.where(mask[:, None], f[:, [0, 2, 1]], f)


def _two_colour(
    m: int, f1: np.ndarray, f2: np.ndarray, odd: np.ndarray, label: np.ndarray
) -> np.ndarray:
    """Flip mask making every manifold edge (f1, f2) consistent; ``odd`` means one must flip.

    A BFS forest (virtual root m joined to the first face of each shell) gives every face a
    tree parent; the parity of the path to the root is then summed by pointer jumping.
    """
    _, first = np.unique(label, return_index=True)
    rows = np.concatenate([f1, f2, np.full(len(first), m)])
    cols = np.concatenate([f2, f1, first])
    graph = coo_array((np.ones(len(rows)), (rows, cols)), shape=(m + 1, m + 1)).tocsr()
    _, pred = breadth_first_order(graph, m, directed=True, return_predecessors=True)
    parent = pred[:m].astype(np.int64)
    top = parent == m
    keys = np.concatenate([f1 * (m + 1) + f2, f2 * (m + 1) + f1])
    order = np.argsort(keys)
    pos = np.searchsorted(keys[order], np.arange(m) * (m + 1) + parent)
    parity = np.concatenate([odd, odd])[order][np.minimum(pos, len(keys) - 1)] & ~top
    jump = np.where(top, np.arange(m), parent)
    while True:
        nxt = jump[jump]
        if np.array_equal(nxt, jump):
            return parity
        parity, jump = parity ^ parity[jump], nxt


def orient_consistently(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rewind faces consistently; return ``(faces_fixed, flipped)``, ``flipped`` a (M,) mask.

    Shells are the components of the face graph joined through manifold edges (used by
    exactly two faces); only those edges propagate orientation. Within a shell the faces
    are 2-coloured so that every manifold edge is used once in each direction. A closed
    shell (all its edges manifold) with negative signed volume is then flipped whole; an
    open shell keeps the orientation that flips the fewest faces. Flipping swaps the last
    two indices of a face. If the winding is already consistent no BFS is run.
    """
    v, f = _as_mesh(vertices, faces)
    m = len(f)
    flipped = np.zeros(m, dtype=bool)
    if m == 0:
        return f.copy(), flipped
    he, group, _, count = _edge_groups(f, len(v))
    h1, h2 = _manifold_pairs(group, count)
    f1, f2 = h1 // 3, h2 // 3
    forward = he[:, 0] < he[:, 1]
    keep = f1 != f2
    f1, f2, odd = f1[keep], f2[keep], (forward[h1] == forward[h2])[keep]
    adjacency = coo_array((np.ones(len(f1)), (f1, f2)), shape=(m, m)).tocsr()
    n_shells, label = connected_components(adjacency, directed=False)
    if odd.any():
        flipped = _two_colour(m, f1, f2, odd, label)
    volume = np.bincount(label, _tet6(_centred_triangles(v, _flip(f, flipped))), n_shells)
    open_face = np.bincount(np.arange(3 * m) // 3, count[group] != 2, m) > 0
    is_open = np.bincount(label, open_face, n_shells) > 0
    n_flipped = np.bincount(label, flipped, n_shells)
    invert = np.where(is_open, 2 * n_flipped > np.bincount(label, None, n_shells), volume < 0)
    flipped ^= invert[label]
    return _flip(f, flipped), flipped


@dataclass(frozen=True, eq=False)
class ValidityReport:
    """Result of :func:`validity_report`. Edges are sorted vertex-index pairs (K, 2);
    ``degenerate_faces`` are face indices; ``intersecting_faces`` (P, 2) face-index pairs
    i < j; ``volume`` is the signed volume (m^3); ``problems`` are readable sentences."""

    watertight: bool
    winding_consistent: bool
    positive_volume: bool
    volume: float
    boundary_edges: np.ndarray
    nonmanifold_edges: np.ndarray
    degenerate_faces: np.ndarray
    intersecting_faces: np.ndarray
    ok: bool
    problems: list[str]

    def summary(self) -> str:
        """One line for a valid solid, otherwise one line per problem."""
        if self.ok:
            return f"valid solid: watertight, consistently wound, volume {self.volume:.6g} m^3"
        return "invalid mesh:\n" + "\n".join(f"- {p}" for p in self.problems)


def _listing(items: list) -> str:
    text = ", ".join(str(i) for i in items[:_CAP])
    return text + (f" ... and {len(items) - _CAP} more" if len(items) > _CAP else "")


def validity_report(
    vertices: np.ndarray,
    faces: np.ndarray,
    *,
    check_self_intersection: bool = True,
    tol: float = 1e-12,
) -> ValidityReport:
    """Check that a mesh bounds a valid solid and say what is wrong if it does not.

    Watertight: every (index-based, undirected) edge is used by exactly two faces.
    Winding consistent: every such manifold edge is used once in each direction.
    Positive volume: signed volume (m^3) > 0. Degenerate faces: area < ``tol`` (m^2).
    Self-intersections (non-degenerate faces only): an AABB-tree broad phase, then exact
    triangle-triangle tests. Non-coplanar pairs use the interval test on the line where
    the two planes meet; pairs sharing one vertex intersect only if the intervals overlap
    beyond that vertex (the same as testing each opposite edge against the other
    triangle); non-coplanar pairs sharing an edge are skipped, since they can only meet on
    that edge. Coplanar pairs (within 1e-9 of the triangle size) use a 2-D separating-axis
    test, so folded-over neighbours are found. Limitation: non-adjacent triangles that
    merely touch (a point or segment) may or may not be reported, and unmerged duplicate
    vertices make neighbours look non-adjacent.
    """
    v, f = _as_mesh(vertices, faces)
    m = len(f)
    he, group, keys, count = _edge_groups(f, len(v))
    n = max(len(v), 1)

    def edges(mask: np.ndarray) -> np.ndarray:
        return np.column_stack([keys[mask] // n, keys[mask] % n]).astype(np.int64)

    def faces_on(mask: np.ndarray) -> list[int]:
        return np.unique(np.flatnonzero(mask[group]) // 3).tolist()

    boundary, nonmanifold = edges(count == 1), edges(count > 2)
    h1, h2 = _manifold_pairs(group, count)
    forward = he[:, 0] < he[:, 1]
    bad = forward[h1] == forward[h2]
    t = _centred_triangles(v, f)
    volume = float(_tet6(t).sum() / 6.0) if m else 0.0
    area = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
    degenerate = np.flatnonzero(area < tol)
    if check_self_intersection and m > 1:
        pairs = self_intersections(t, f, area >= tol)
    else:
        pairs = np.zeros((0, 2), np.int64)

    problems = [] if m else ["The mesh has no faces."]
    if len(boundary):
        problems.append(
            f"Not watertight: {len(boundary)} boundary edges on faces "
            f"{_listing(faces_on(count == 1))} (vertex pairs {_listing(boundary.tolist())})."
        )
    if len(nonmanifold):
        problems.append(
            f"{len(nonmanifold)} non-manifold edges (used by more than two faces) on faces "
            f"{_listing(faces_on(count > 2))} (vertex pairs {_listing(nonmanifold.tolist())})."
        )
    if bad.any():
        wrong = np.unique(np.concatenate([h1[bad], h2[bad]]) // 3).tolist()
        problems.append(
            f"Winding inconsistent across {int(bad.sum())} edges between faces "
            f"{_listing(wrong)}; orient_consistently can fix this."
        )
    if m and volume <= 0:
        problems.append(f"Signed volume {volume:.6g} m^3 is not positive (inside out or flat).")
    if len(degenerate):
        problems.append(
            f"{len(degenerate)} degenerate faces (area < {tol:g} m^2): "
            f"{_listing(degenerate.tolist())}."
        )
    if len(pairs):
        problems.append(
            f"Self-intersecting: {len(pairs)} face pairs intersect: "
            f"{_listing([tuple(p) for p in pairs.tolist()])}."
        )
    return ValidityReport(
        watertight=bool(np.all(count == 2)),
        winding_consistent=not bad.any(),
        positive_volume=volume > 0,
        volume=volume,
        boundary_edges=boundary,
        nonmanifold_edges=nonmanifold,
        degenerate_faces=degenerate,
        intersecting_faces=pairs,
        ok=not problems,
        problems=problems,
    )
