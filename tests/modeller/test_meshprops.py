"""Tests of workcell.modeller.meshprops: mass properties, orientation and validity."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from workcell.errors import GeometryError
from workcell.modeller import meshprops
from workcell.modeller.meshprops import (
    MassProperties,
    mass_properties,
    orient_consistently,
    polygon_area,
    validity_report,
)

RTOL = 1e-9


def _box(extents=(1.0, 1.0, 1.0), offset=(0.0, 0.0, 0.0)):
    m = trimesh.creation.box(extents=extents)
    return np.asarray(m.vertices) + offset, np.asarray(m.faces, dtype=np.int64)


def _concat(*meshes):
    vs, fs, n = [], [], 0
    for v, f in meshes:
        vs.append(v)
        fs.append(f + n)
        n += len(v)
    return np.vstack(vs), np.vstack(fs)


def _close(a, b, rtol=RTOL, scale=None):
    """Equal to ``rtol`` relative to the largest entry of b (or to ``scale``)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    scale = max(np.abs(b).max(), 1e-300) if scale is None else scale
    np.testing.assert_allclose(a, b, rtol=rtol, atol=rtol * scale)


def _canonical(f):
    """Faces with each row rotated so its smallest index comes first (same winding)."""
    k = np.argmin(f, axis=1)[:, None]
    return np.take_along_axis(f, (k + np.arange(3)) % 3, axis=1)


def _check_against_trimesh(v, f):
    mp = mass_properties(v, f)
    ref = trimesh.Trimesh(v, f, process=False)
    _close(mp.volume, ref.volume)
    _close(mp.area, ref.area)
    size = np.ptp(v, axis=0).max()  # centroids are compared relative to the mesh size
    _close(mp.centroid, ref.center_mass, scale=size)
    _close(mp.first_moments, ref.volume * np.asarray(ref.center_mass), scale=ref.volume * size)
    _close(mp.inertia, ref.moment_inertia)
    return mp


# ---------------------------------------------------------------- polygon_area


def test_polygon_area_signs_and_ngon():
    square = np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float)
    assert polygon_area(square) == pytest.approx(2.0)
    assert polygon_area(square[::-1]) == pytest.approx(-2.0)
    n, r = 9, 0.7
    th = 2 * np.pi * np.arange(n) / n
    ngon = np.column_stack([r * np.cos(th) + 1e6, r * np.sin(th) - 3e6])
    assert polygon_area(ngon) == pytest.approx(0.5 * n * r**2 * np.sin(2 * np.pi / n), rel=1e-9)
    assert polygon_area(square[:2]) == 0.0
    with pytest.raises(GeometryError):
        polygon_area(np.zeros((4, 3)))


# ---------------------------------------------------------------- mass properties


def test_box_analytic():
    a, b, c = 1.0, 2.0, 3.0
    v, f = _box((a, b, c), offset=(0.5, 1.0, 1.5))  # bounds [0, 0, 0] - [1, 2, 3]
    mp = _check_against_trimesh(v, f)
    vol = a * b * c
    _close(mp.volume, vol)
    _close(mp.area, 2 * (a * b + b * c + c * a))
    _close(mp.centroid, [0.5, 1.0, 1.5])
    _close(mp.inertia, vol / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b]))
    # about the corner at the origin: diag V(b^2+c^2)/3, products -V ab/4 ...
    corner = vol * np.array(
        [
            [(b * b + c * c) / 3, -a * b / 4, -a * c / 4],
            [-a * b / 4, (a * a + c * c) / 3, -b * c / 4],
            [-a * c / 4, -b * c / 4, (a * a + b * b) / 3],
        ]
    )
    _close(mp.inertia_about([0, 0, 0]), corner)
    _close(mp.principal_moments, np.sort(np.diag(mp.inertia)))
    assert isinstance(mp, MassProperties)
    with pytest.raises(ValueError, match="read-only"):
        mp.centroid[0] = 1.0


@pytest.mark.parametrize("n", [3, 7, 16])
def test_polygon_prism_exact(n):
    r, h = 0.5, 2.0
    m = trimesh.creation.cylinder(radius=r, height=h, sections=n)
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    mp = _check_against_trimesh(v, f)
    # exact regular n-gon prism: V = (n/2) r^2 sin(2 pi/n) h, Izz = m r^2 (2 + cos(2 pi/n)) / 6
    vol = 0.5 * n * r**2 * np.sin(2 * np.pi / n) * h
    _close(mp.volume, vol)
    _close(mp.inertia[2, 2], vol * r**2 * (2 + np.cos(2 * np.pi / n)) / 6)


@pytest.mark.parametrize(
    "mesh",
    [
        trimesh.creation.torus(1.0, 0.25, major_sections=48, minor_sections=24),
        trimesh.creation.icosphere(3, radius=0.8),
        trimesh.creation.annulus(0.4, 1.0, height=0.3, sections=40),
        trimesh.creation.capsule(1.0, 0.3),
        trimesh.creation.box(extents=(0.2, 3.0, 0.05)),
    ],
    ids=["torus", "icosphere", "annulus", "capsule", "plate"],
)
def test_against_trimesh(mesh):
    T = trimesh.transformations.random_rotation_matrix(np.random.default_rng(3).random(3))
    T[:3, 3] = [0.3, -0.2, 0.7]
    v = np.asarray(mesh.vertices) @ T[:3, :3].T + T[:3, 3]
    _check_against_trimesh(v, np.asarray(mesh.faces))


def test_far_from_origin_matches_origin():
    m = trimesh.creation.icosphere(3, radius=0.05)
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    near = _check_against_trimesh(v, f)
    shift = np.array([1000.0, -250.0, 40.0])
    far = mass_properties(v + shift, f)
    _close(far.volume, near.volume)
    _close(far.area, near.area)
    _close(far.centroid, near.centroid + shift)  # relative to |shift|
    _close(far.centroid - shift, near.centroid, rtol=1e-11, scale=0.1)  # 0.1 = sphere size
    _close(far.inertia, near.inertia)
    _close(far.first_moments, near.volume * (near.centroid + shift))


def test_rotated_box():
    R = Rotation.from_euler("xyz", [0.3, -1.1, 2.0]).as_matrix()
    v, f = _box((0.5, 1.5, 2.5))
    mp = _check_against_trimesh(v @ R.T + [2, 3, 4], f)
    I0 = 0.5 * 1.5 * 2.5 / 12 * np.diag([1.5**2 + 2.5**2, 0.5**2 + 2.5**2, 0.5**2 + 1.5**2])
    _close(mp.inertia, R @ I0 @ R.T)
    _close(mp.principal_moments, np.sort(np.diag(I0)))


@settings(max_examples=60, deadline=None)
@given(
    size=st.tuples(*[st.floats(0.01, 10.0)] * 3),
    quat=st.tuples(*[st.floats(-1.0, 1.0)] * 4).filter(lambda q: np.linalg.norm(q) > 0.1),
    shift=st.tuples(*[st.floats(-1000.0, 1000.0)] * 3),
)
def test_random_boxes_analytic(size, quat, shift):
    a, b, c = size
    R = Rotation.from_quat(quat).as_matrix()
    v, f = _box(size)
    mp = mass_properties(v @ R.T + shift, f)
    vol = a * b * c
    _close(mp.volume, vol)
    _close(mp.area, 2 * (a * b + b * c + c * a))
    np.testing.assert_allclose(mp.centroid, shift, rtol=0, atol=RTOL * max(a, b, c))
    _close(mp.inertia, R @ np.diag([b * b + c * c, a * a + c * c, a * a + b * b]) @ R.T * vol / 12)


def test_empty_and_bad_input():
    mp = mass_properties(np.zeros((0, 3)), np.zeros((0, 3), np.int64))
    assert mp.volume == 0.0
    assert mp.area == 0.0
    assert not mp.centroid.any()
    assert not mp.inertia.any()
    with pytest.raises(GeometryError):
        mass_properties(np.zeros((3, 3)), np.array([[0, 1, 3]]))
    with pytest.raises(GeometryError):
        mass_properties(np.zeros((3, 2)), np.array([[0, 1, 2]]))


# ---------------------------------------------------------------- orientation


@settings(max_examples=40, deadline=None)
@given(mask=st.lists(st.booleans(), min_size=12, max_size=12))
def test_orient_cube_random_flips(mask):
    v, f = _box()
    mask = np.array(mask)
    bad = np.where(mask[:, None], f[:, [0, 2, 1]], f)
    fixed, flipped = orient_consistently(v, bad)
    np.testing.assert_array_equal(fixed, f)  # exactly the outward cube
    np.testing.assert_array_equal(flipped, mask)
    assert mass_properties(v, fixed).volume == pytest.approx(1.0)


def test_orient_inverted_icosphere():
    m = trimesh.creation.icosphere(3)
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    fixed, flipped = orient_consistently(v, f[:, ::-1])
    assert flipped.all()
    np.testing.assert_array_equal(_canonical(fixed), _canonical(f))


def test_orient_two_boxes_one_inverted():
    v, f = _concat(_box(), _box((2, 1, 1), offset=(5, 0, 0)))
    bad = f.copy()
    bad[12:] = bad[12:, ::-1]
    fixed, flipped = orient_consistently(v, bad)
    np.testing.assert_array_equal(flipped, np.arange(24) >= 12)
    np.testing.assert_array_equal(_canonical(fixed), _canonical(f))
    assert validity_report(v, fixed).ok


def test_orient_torus_random_flips():
    m = trimesh.creation.torus(1.0, 0.3, major_sections=24, minor_sections=12)
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    mask = np.random.default_rng(7).random(len(f)) < 0.4
    fixed, flipped = orient_consistently(v, np.where(mask[:, None], f[:, ::-1], f))
    np.testing.assert_array_equal(flipped, mask)
    np.testing.assert_array_equal(_canonical(fixed), _canonical(f))


def test_orient_fast_path_skips_bfs(monkeypatch):
    def boom(*args, **kwargs):
        raise AssertionError("BFS run on a consistent mesh")

    monkeypatch.setattr(meshprops, "breadth_first_order", boom)
    v, f = _box()
    fixed, flipped = orient_consistently(v, f)
    np.testing.assert_array_equal(fixed, f)
    assert not flipped.any()


def test_orient_open_shell_keeps_majority():
    v, f = _box()
    f = f[1:]  # open box
    mask = np.zeros(len(f), bool)
    mask[[2, 7]] = True
    fixed, flipped = orient_consistently(v, np.where(mask[:, None], f[:, [0, 2, 1]], f))
    np.testing.assert_array_equal(flipped, mask)
    np.testing.assert_array_equal(fixed, f)


# ---------------------------------------------------------------- validity


def _cross_box_pairs(pairs, n_first):
    return bool(len(pairs)) and bool(np.all((pairs[:, 0] < n_first) & (pairs[:, 1] >= n_first)))


def test_valid_box():
    rep = validity_report(*_box())
    assert rep.ok
    assert rep.watertight
    assert rep.winding_consistent
    assert rep.positive_volume
    assert rep.volume == pytest.approx(1.0)
    assert rep.problems == []
    assert rep.summary().startswith("valid solid")
    assert rep.boundary_edges.shape == (0, 2)
    assert rep.intersecting_faces.shape == (0, 2)


def test_box_missing_face():
    v, f = _box()
    rep = validity_report(v, f[1:])
    assert not rep.watertight
    assert not rep.ok
    assert rep.winding_consistent
    expected = sorted(tuple(sorted(e)) for e in [f[0, [0, 1]], f[0, [1, 2]], f[0, [2, 0]]])
    assert sorted(map(tuple, rep.boundary_edges.tolist())) == expected
    assert "boundary edges" in rep.summary()


def test_one_flipped_face():
    v, f = _box()
    f = f.copy()
    f[5] = f[5, ::-1]
    rep = validity_report(v, f)
    assert rep.watertight
    assert not rep.winding_consistent
    assert not rep.ok
    assert any("faces" in p and "5" in p for p in rep.problems)


def test_inverted_box():
    v, f = _box()
    rep = validity_report(v, f[:, ::-1])
    assert rep.watertight
    assert rep.winding_consistent
    assert not rep.positive_volume
    assert rep.volume == pytest.approx(-1.0)
    assert not rep.ok


def test_overlapping_boxes_intersect():
    v, f = _concat(_box(), _box(offset=(0.5, 0.5, 0.5)))
    rep = validity_report(v, f)
    assert rep.watertight
    assert rep.winding_consistent
    assert not rep.ok
    assert _cross_box_pairs(rep.intersecting_faces, 12)
    assert len(rep.intersecting_faces) == 18  # as counted by independent checkers (notes §3)
    assert "... and 8 more" in rep.summary()


def test_disjoint_boxes_ok():
    rep = validity_report(*_concat(_box(), _box(offset=(1.5, 0.2, 0.0))))
    assert rep.ok


def test_box_poking_through_face():
    v, f = _concat(_box(), _box((0.3, 0.3, 0.3), offset=(0.0, 0.0, 0.5)))
    rep = validity_report(v, f)
    assert _cross_box_pairs(rep.intersecting_faces, 12)
    top = np.flatnonzero(np.isclose(v[f][:, :, 2], 0.5).all(axis=1))  # the big box's top
    assert set(rep.intersecting_faces[:, 0]) <= set(top.tolist())


def test_fin_face_nonmanifold():
    v, f = _box()
    a, b = f[0, 0], f[0, 1]
    v2 = np.vstack([v, [[2.0, 2.0, 2.0]]])
    rep = validity_report(v2, np.vstack([f, [[a, b, 8]]]))
    assert not rep.watertight
    assert not rep.ok
    np.testing.assert_array_equal(rep.nonmanifold_edges, [sorted([a, b])])
    assert len(rep.boundary_edges) == 2
    assert "non-manifold" in rep.summary()


def test_icosphere_ok():
    m = trimesh.creation.icosphere(4)
    rep = validity_report(m.vertices, m.faces)
    assert rep.ok
    assert len(rep.intersecting_faces) == 0


def test_large_icosphere_is_valid():
    # speed is measured by scripts/bench_modeller.py, not asserted here
    m = trimesh.creation.icosphere(5)
    rep = validity_report(np.asarray(m.vertices), np.asarray(m.faces))
    assert rep.ok
    assert len(rep.intersecting_faces) == 0


def test_annulus_with_inner_wall_pushed_out():
    m = trimesh.creation.annulus(0.5, 1.0, height=0.4, sections=32)
    v, f = np.asarray(m.vertices).copy(), np.asarray(m.faces)
    assert validity_report(v, f).ok
    radius = np.hypot(v[:, 0], v[:, 1])
    angle = np.arctan2(v[:, 1], v[:, 0])
    moved = (radius < 0.75) & (np.abs(angle) < 0.5)
    v[moved, :2] *= 2.6  # inner wall now passes through the outer wall
    rep = validity_report(v, f)
    assert rep.watertight
    assert rep.winding_consistent
    assert len(rep.intersecting_faces) > 0
    touched = np.isin(f, np.flatnonzero(moved)).any(axis=1)
    assert touched[rep.intersecting_faces].any(axis=1).all()


def test_perforated_plate():
    plate = trimesh.creation.box(extents=[0.2, 0.1, 0.01])
    holes = [
        trimesh.creation.cylinder(
            0.003,
            0.05,
            sections=24,
            transform=trimesh.transformations.translation_matrix([x, y, 0]),
        )
        for x in np.linspace(-0.09, 0.09, 10)
        for y in np.linspace(-0.045, 0.045, 10)
    ]
    d = trimesh.boolean.difference([plate, *holes], engine="manifold")
    v, f = np.asarray(d.vertices), np.asarray(d.faces)
    assert validity_report(v, f).ok
    pin = trimesh.creation.cylinder(0.001, 0.03, sections=12)  # through solid plate at (0, 0)
    rep = validity_report(*_concat((v, f), (np.asarray(pin.vertices), np.asarray(pin.faces))))
    assert _cross_box_pairs(rep.intersecting_faces, len(f))


def test_degenerate_face_reported():
    v, f = _box()
    v2 = np.vstack([v, [[0.0, 0.0, 5.0], [0.0, 0.0, 6.0], [0.0, 0.0, 7.0]]])
    rep = validity_report(v2, np.vstack([f, [[8, 9, 10], [0, 0, 1]]]))
    np.testing.assert_array_equal(rep.degenerate_faces, [12, 13])
    assert not rep.ok
    assert "degenerate" in rep.summary()


def test_empty_mesh_report():
    rep = validity_report(np.zeros((0, 3)), np.zeros((0, 3), np.int64))
    assert not rep.ok
    assert rep.volume == 0.0


def test_unchecked_self_intersection():
    v, f = _concat(_box(), _box(offset=(0.5, 0.5, 0.5)))
    assert validity_report(v, f, check_self_intersection=False).ok


# ---------------------------------------------------------------- adjacent-pair rules


def _pair(t1, t2):
    v = np.array(t1 + t2, float)
    rep = validity_report(v, np.array([[0, 1, 2], [3, 4, 5]]))
    return len(rep.intersecting_faces) > 0


def _shared(t1, t2):
    """Two triangles given by corner lists; equal corners become one shared vertex."""
    pts = {tuple(p) for p in t1 + t2}
    pts = sorted(pts)
    v = np.array(pts, float)
    f = np.array([[pts.index(tuple(p)) for p in t] for t in (t1, t2)])
    return len(validity_report(v, f).intersecting_faces) > 0


def test_shared_vertex_rules():
    o = (0.0, 0.0, 0.0)
    # opposite edge of the second triangle pierces the first one
    assert _shared([o, (2, 0, 0), (0, 2, 0)], [o, (0.5, 0.5, -1), (0.5, 0.5, 1)])
    # they only meet at the shared vertex
    assert not _shared([o, (2, 0, 0), (0, 2, 0)], [o, (-1, 0, 1), (0, -1, 1)])
    assert not _shared([o, (2, 0, 0), (0, 2, 0)], [o, (-0.5, -0.5, -1), (-0.5, -0.5, 1)])
    # coplanar fan neighbours only touch; coplanar overlapping wedges intersect
    assert not _shared([o, (1, 0, 0), (1, 1, 0)], [o, (0, 1, 0), (-1, 1, 0)])
    assert _shared([o, (1, 0, 0), (1, 1, 0)], [o, (1, 0.5, 0), (0, 1, 0)])


def test_shared_edge_rules():
    o, x = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0)
    assert not _shared([o, x, (0, 1, 0)], [x, o, (0, -1, 0)])  # flat neighbours
    assert not _shared([o, x, (0, 1, 0)], [x, o, (0, 0, 1)])  # hinge
    assert _shared([o, x, (0, 1, 0)], [x, o, (0.5, 0.5, 0)])  # folded over


def test_coplanar_non_adjacent():
    assert _pair([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0.2, 0.2, 0), (2, 0.2, 0), (0.2, 2, 0)])
    assert not _pair([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(1, 1, 0), (2, 1, 0), (1, 2, 0)])
    assert _pair([(0, 0, 0), (3, 0, 0), (0, 3, 0)], [(0.5, 0.5, 0), (1, 0.5, 0), (0.5, 1, 0)])


# ---------------------------------------------------------------- brute force cross-check


def _segment_hits_triangle(p, q, tri):
    """Möller-Trumbore ray test restricted to the segment p-q (no coplanar handling)."""
    d = q - p
    e1, e2 = tri[1] - tri[0], tri[2] - tri[0]
    h = np.cross(d, e2)
    a = e1 @ h
    if abs(a) < 1e-14:
        return False
    s = p - tri[0]
    u = (s @ h) / a
    w = np.cross(s, e1)
    vv = (d @ w) / a
    t = (e2 @ w) / a
    return 0.0 <= u <= 1.0 and vv >= 0.0 and u + vv <= 1.0 and 0.0 <= t <= 1.0


def _brute_3d(v, f):
    out = set()
    for i in range(len(f)):
        for j in range(i + 1, len(f)):
            shared = set(f[i]) & set(f[j])
            if len(shared) >= 2:
                continue
            hit = False
            for a, b in ((i, j), (j, i)):
                edges = [(f[a][k], f[a][(k + 1) % 3]) for k in range(3)]
                edges = [e for e in edges if not shared & set(e)]  # opposite edge if shared
                hit |= any(_segment_hits_triangle(v[p], v[q], v[f[b]]) for p, q in edges)
            if hit:
                out.add((i, j))
    return out


@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 12), pool=st.integers(4, 40))
def test_matches_brute_force_soups(seed, n, pool):
    rng = np.random.default_rng(seed)
    v = rng.random((pool, 3))
    f = np.array([rng.choice(pool, 3, replace=False) for _ in range(n)])
    f = f[np.unique(np.sort(f, axis=1), axis=0, return_index=True)[1]]  # no duplicates
    rep = validity_report(v, f, tol=0.0)
    assert set(map(tuple, rep.intersecting_faces.tolist())) == _brute_3d(v, f)


def _brute_2d(tris):
    def orient(a, b, c):
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    def inside(p, t):
        s = [orient(t[k], t[(k + 1) % 3], p) for k in range(3)]
        return all(x > 0 for x in s) or all(x < 0 for x in s)

    out = set()
    for i in range(len(tris)):
        for j in range(i + 1, len(tris)):
            A, B = tris[i], tris[j]
            hit = any(inside(p, B) for p in A) or any(inside(p, A) for p in B)
            for k in range(3):
                for m in range(3):
                    p, q, r, s = A[k], A[(k + 1) % 3], B[m], B[(m + 1) % 3]
                    d1, d2 = orient(p, q, r), orient(p, q, s)
                    d3, d4 = orient(r, s, p), orient(r, s, q)
                    hit |= d1 * d2 < 0 and d3 * d4 < 0
            if hit:
                out.add((i, j))
    return out


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 10))
def test_matches_brute_force_coplanar(seed, n):
    rng = np.random.default_rng(seed)
    xy = rng.random((n, 3, 2)) * 0.6 + rng.random((n, 1, 2))
    R = Rotation.from_rotvec(rng.normal(size=3)).as_matrix()
    v = np.concatenate([xy, np.full((n, 3, 1), 0.25)], axis=2).reshape(-1, 3) @ R.T
    f = np.arange(3 * n).reshape(n, 3)
    rep = validity_report(v, f, tol=0.0)
    assert set(map(tuple, rep.intersecting_faces.tolist())) == _brute_2d(xy)
