"""Hash-table grouping (workcell.modeller.hashgroup) and the world mesher's weld and
winding test built on it, each compared with a sorting reference written here.

References: np.unique (sorting) for grouping and repeats; a weld written from its rule
(grid cells by np.unique, near-boundary twins joined through a k-d tree, each weld group
represented by its first input vertex, groups numbered by first appearance); the winding
test as a sort of directed edges plus the signed volume.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from workcell import spatial
from workcell.modeller import hashgroup, world
from workcell.modeller.model import Model
from workcell.modeller.patches import UNIT_SQUARE, build_block
from workcell.modeller.solids import _sphere_parts, cube_face_transforms
from workcell.modeller.surface import Surface

FLIP = spatial.scaling(1.0, 1.0, -1.0)


def ref_first_of_equal(cols):
    rows = np.stack(cols, axis=1)
    _, first, inv = np.unique(rows, axis=0, return_index=True, return_inverse=True)
    return first[inv.ravel()]


def ref_merge(vertices, faces, rel_tol=1e-9):
    """The weld rule by sorting: same grid as the mesher, exact cell equality."""
    lo = vertices.min(axis=0)
    cell = max(float((vertices.max(axis=0) - lo).max()), 1e-12) * rel_tol
    g = (vertices - lo) * (1.0 / cell)
    q = np.rint(g)
    near = np.flatnonzero((np.abs(g - q) > 0.499).any(axis=1))
    _, groups = np.unique(q, axis=0, return_inverse=True)
    groups = groups.ravel()
    n_groups = int(groups.max()) + 1
    a, b = np.zeros(0, int), np.zeros(0, int)
    if len(near) > 1:
        pairs = cKDTree(vertices[near]).query_pairs(cell, output_type="ndarray")
        a, b = groups[near[pairs[:, 0]]], groups[near[pairs[:, 1]]]
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(n_groups, n_groups))
    comp = connected_components(graph, directed=False)[1][groups]
    _, first, inv = np.unique(comp, return_index=True, return_inverse=True)
    order = np.argsort(first)  # number the groups by first appearance
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    V = vertices[first[order]]
    F = rank[inv.ravel()][faces]
    ok = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0])
    return V, F[ok], ok


def ref_outward(V, F):
    if len(F) == 0:
        return True
    he = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)
    if len(np.unique(he, axis=0)) < len(he):
        return False
    t = V[F] - V.mean(axis=0)
    return float(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum()) > 0


# --- grouping -------------------------------------------------------------------------

int_rows = st.integers(1, 3).flatmap(
    lambda k: st.lists(
        st.tuples(*[st.sampled_from([-(2**40), -7, 0, 1, 2, 3, 2**40, 2**62])] * k),
        min_size=1,
        max_size=300,
    )
)


@settings(max_examples=60, deadline=None)
@given(int_rows)
def test_first_of_equal_matches_sorting(rows):
    cols = [np.ascontiguousarray(c, dtype=np.int64) for c in np.array(rows, np.int64).T]
    assert np.array_equal(hashgroup.first_of_equal(cols), ref_first_of_equal(cols))


def test_first_of_equal_survives_total_hash_collisions(monkeypatch):
    # every row hashes to 0: all rounds collide, and the sorting fallback settles the rest
    monkeypatch.setattr(hashgroup, "_row_hash", lambda cols: np.zeros(len(cols[0]), np.uint64))
    rng = np.random.default_rng(1)
    cols = [rng.integers(0, 40, 2000) for _ in range(3)]
    assert np.array_equal(hashgroup.first_of_equal(cols), ref_first_of_equal(cols))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(-(2**62), 2**62), max_size=400), st.booleans())
def test_has_repeat_matches_sorting(values, repeat):
    keys = np.array(values + values[:1] * repeat, dtype=np.int64)
    assert hashgroup.has_repeat(keys) == (len(np.unique(keys)) < len(keys))


@pytest.mark.parametrize("repeat", [False, True])
def test_has_repeat_survives_total_slot_collisions(monkeypatch, repeat):
    monkeypatch.setattr(hashgroup, "_slots", lambda h, r: (np.zeros(len(h), np.intp), 16))
    keys = np.arange(0, 3000, 3, dtype=np.int64)
    if repeat:
        keys[-1] = keys[500]
    assert hashgroup.has_repeat(keys) == repeat


# --- the weld -------------------------------------------------------------------------

CELL = 1e-9  # the corners (0,0,0) and (1,1,1) make the extent 1


def _across_boundary(k):
    """Consecutive floats around (k + 1/2) cells, where the grid rounds either way."""
    x = (k + 0.5) * CELL
    return [np.nextafter(x, -np.inf), x, np.nextafter(x, np.inf)]


@st.composite
def clouds(draw):
    """Points in the unit cube with exact copies, copies moved by a few ulps or a fraction
    of a cell, and runs of points straddling a rounding boundary; random faces on them."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    base = rng.uniform(0.1, 0.9, (draw(st.integers(1, 20)), 3))
    pts = [np.zeros(3), np.ones(3), *base]
    for _ in range(draw(st.integers(0, 40))):
        p = base[rng.integers(len(base))].copy()
        kind = rng.integers(4)
        if kind == 1:
            p = np.nextafter(p, p + rng.choice([-1, 1], 3))
        elif kind == 2:
            p = p + rng.uniform(-0.7, 0.7, 3) * CELL
        elif kind == 3:  # a boundary-straddling twin of a grid point
            k = int(rng.integers(100_000_000, 900_000_000))
            axis = int(rng.integers(3))
            for x in _across_boundary(k):
                q = p.copy()
                q[axis] = x
                pts.append(q)
        pts.append(p)
    V = np.array(pts)
    F = rng.integers(0, len(V), (draw(st.integers(0, 60)), 3))
    return V, F


@settings(max_examples=80, deadline=None)
@given(clouds())
def test_merge_vertices_matches_the_sorting_weld(cloud):
    V, F = cloud
    got = world.merge_vertices(V, F)
    want = ref_merge(V, F)
    for g, w in zip(got, want, strict=True):
        assert np.array_equal(g, w)


def test_merge_vertices_welds_the_boundary_runs_of_the_reference():
    p = np.full(3, 0.5)
    runs = []
    for x in _across_boundary(400_000_000):
        q = p.copy()
        q[0] = x
        runs.append(q)
    V = np.array([np.zeros(3), np.ones(3), *runs, p])
    Vm, _, _ = world.merge_vertices(V, np.zeros((0, 3), np.int64))
    assert len(Vm) == 4  # two corners, the run as one vertex, and p
    assert np.array_equal(Vm, ref_merge(V, np.zeros((0, 3), np.int64))[0])


# --- whole blocks: hashing path against the sorting references ------------------------


@st.composite
def blocks(draw):
    """A box or a small sphere, some of its relations turned over (needing repair),
    placed by a random rotation, translation and scaling (sometimes a reflection)."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    if draw(st.booleans()):
        surfaces = {"square": Surface(UNIT_SQUARE, name="b.square")}
        relations = [("square", cube_face_transforms())]
    else:
        surfaces, relations = _sphere_parts(
            "b", draw(st.integers(3, 9)), draw(st.integers(1, 4)), np.ones(3)
        )
    scale = rng.uniform(0.2, 3.0, 3) * (rng.choice([-1, 1]) if draw(st.booleans()) else 1)
    T = spatial.euler(rng.uniform(-np.pi, np.pi, 3), translation=rng.uniform(-5, 5, 3))
    T = T @ spatial.scaling(*scale)
    out = []
    for key, Ts in relations:
        Ts = T @ Ts
        turn = rng.random(len(Ts)) < draw(st.sampled_from([0.0, 0.2, 1.0]))
        Ts[turn] = Ts[turn] @ FLIP
        out.append((key, Ts))
    return surfaces, out


@settings(max_examples=40, deadline=None)
@given(blocks())
def test_block_meshes_match_the_sorting_pipeline(block):
    surfaces, relations = block
    results = []
    for patched in (False, True):
        m = Model()
        build_block(m, "b", surfaces, relations)
        with pytest.MonkeyPatch.context() as mp:
            if patched:
                mp.setattr(world, "merge_vertices", ref_merge)
                mp.setattr(world, "_outward", ref_outward)
            mesh = m.world_mesh("b")
            results.append((mesh.vertices, mesh.faces, world.reoriented_relations(m._get("b"))))
    (V1, F1, r1), (V2, F2, r2) = results
    assert np.array_equal(V1, V2)
    assert np.array_equal(F1, F2)
    assert r1 == r2
    assert mesh.is_watertight
    assert mesh.volume > 0


@settings(max_examples=60, deadline=None)
@given(blocks(), st.integers(0, 3))
def test_outward_test_matches_the_sorting_reference(block, damage):
    """The fast winding test on a welded block, then damaged: one face turned over (a
    repeated directed edge), all turned over (negative volume), a face duplicated."""
    surfaces, relations = block
    m = Model()
    build_block(m, "b", surfaces, relations)
    mesh = m.world_mesh("b")
    V, F = np.asarray(mesh.vertices), np.array(mesh.faces)
    if damage == 1:
        F[0] = F[0, ::-1]
    elif damage == 2:
        F = F[:, ::-1].copy()
    elif damage == 3:
        F = np.concatenate([F, F[:1]])
    assert world._outward(V, F) == ref_outward(V, F)
    assert world._outward(V, F) == (damage == 0)
