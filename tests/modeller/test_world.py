"""Tests of the world coordinates generator: world meshes, world parts, caching, welding.

Expected positions are the block's own vertices with the relation transforms applied by
hand (numpy), volumes from closed forms.
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import workcell
from workcell import solids, spatial
from workcell.errors import GeometryError
from workcell.modeller.surface import Surface
from workcell.modeller.world import DEFAULT_COLOUR, WorldPart, merge_vertices

RTOL = 1e-12


def _rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


def _apply(T, V):
    T = np.asarray(T)
    return np.asarray(V) @ T[:3, :3].T + T[:3, 3]


def _sorted_rows(v):
    v = np.asarray(v)
    return v[np.lexsort(np.round(v, 9).T[::-1])]


T1 = spatial.euler([0.2, -0.4, 1.1], translation=(2.0, -1.0, 0.5))
T2 = spatial.translation(-3.0, 0.0, 1.0) @ spatial.scaling(1.0, 2.0, 0.5)
T_SCENE = spatial.euler([0.0, 0.3, -0.7], translation=(10.0, 5.0, -2.0))


@pytest.fixture
def cell():
    """An object of two placed blocks (cube, cylinder) and a scene holding it twice."""
    m = workcell.Model()
    solids.cube(m, "cube", size=0.5)
    solids.cylinder(m, "cyl", radius=0.2, height=0.6, n=7)
    m.create("object", "obj")
    m.attach("obj", "cube", T1, name="base")
    m.attach("obj", "cyl", T2, name="post")
    m.create("scene", "sc")
    m.attach("sc", "obj", T_SCENE, name="left")
    m.attach("sc", "obj", spatial.translation(0.0, 4.0, 0.0), name="right")
    return m


# ==================================================================== world meshes


def test_object_world_mesh_is_blocks_placed_by_hand(cell):
    m = cell
    vc = np.asarray(m.world_mesh("cube").vertices)
    vy = np.asarray(m.world_mesh("cyl").vertices)
    mesh = m.world_mesh("obj")
    expected = np.vstack([_apply(T1, vc), _apply(T2, vy)])
    np.testing.assert_allclose(_sorted_rows(mesh.vertices), _sorted_rows(expected), atol=1e-12)
    n_faces = len(m.world_mesh("cube").faces) + len(m.world_mesh("cyl").faces)
    assert len(mesh.faces) == n_faces
    vol = 0.5**3 * abs(np.linalg.det(T1[:3, :3])) + m.properties("cyl").volume * 1.0
    assert _rel(m.properties("obj").volume, vol) < RTOL
    assert _rel(mesh.volume, vol) < 1e-9
    # the centroid is the volume-weighted mean of the placed parts' centroids
    c1 = _apply(T1, m.properties("cube").centroid)
    c2 = _apply(T2, m.properties("cyl").centroid)
    w1, w2 = 0.5**3, m.properties("cyl").volume
    np.testing.assert_allclose(
        m.properties("obj").centroid, (w1 * c1 + w2 * c2) / (w1 + w2), atol=1e-12
    )


def test_scene_world_mesh_and_parts_compose_transforms(cell):
    m = cell
    parts = m.world_parts("sc")
    assert [p.path for p in parts] == ["left/base", "left/post", "right/base", "right/post"]
    tos = {"left": T_SCENE, "right": spatial.translation(0.0, 4.0, 0.0)}
    tbs = {"base": T1, "post": T2}
    blocks = {"base": "cube", "post": "cyl"}
    for p in parts:
        assert isinstance(p, WorldPart)
        to, tb = p.path.split("/")
        T = tos[to] @ tbs[tb]
        np.testing.assert_allclose(p.transform, T, atol=1e-12)
        assert p.block == blocks[tb]
        assert p.object == "obj"
        block_v = np.asarray(m.world_mesh(p.block).vertices)
        np.testing.assert_allclose(p.mesh.vertices, _apply(T, block_v), atol=1e-12)
        np.testing.assert_array_equal(p.mesh.faces, m.world_mesh(p.block).faces)
        assert p.mesh.volume > 0
    all_v = np.vstack([p.mesh.vertices for p in parts])
    np.testing.assert_allclose(
        _sorted_rows(m.world_mesh("sc").vertices), _sorted_rows(all_v), atol=1e-12
    )
    assert _rel(m.properties("sc").volume, 2 * m.properties("obj").volume) < RTOL
    assert m.validity("sc").ok


def test_block_and_object_world_parts(cell):
    m = cell
    (p,) = m.world_parts("cube")
    assert (p.path, p.block, p.object) == ("cube", "cube", None)
    np.testing.assert_array_equal(p.transform, np.eye(4))
    parts = m.world_parts("obj")
    assert [(q.path, q.block, q.object) for q in parts] == [
        ("base", "cube", "obj"),
        ("post", "cyl", "obj"),
    ]


def test_colour_precedence_and_movable(cell):
    m = cell
    red, green = (1.0, 0.0, 0.0, 1.0), (0.0, 1.0, 0.0, 0.5)
    # nothing coloured: the default
    assert all(p.colour == tuple(DEFAULT_COLOUR) for p in m.world_parts("obj"))
    assert all(len(p.colour) == 4 for p in m.world_parts("sc"))
    # the object's colour for blocks without one
    m.set_colour("obj", green)
    assert [p.colour for p in m.world_parts("obj")] == [green, green]
    # a block's own colour wins over the object's
    m.set_colour("cube", red[:3])
    assert [p.colour for p in m.world_parts("obj")] == [red, green]
    assert [p.colour for p in m.world_parts("sc")] == [red, green, red, green]
    m.set_colour("obj", None)
    assert [p.colour for p in m.world_parts("obj")] == [red, tuple(DEFAULT_COLOUR)]
    # movable: from the object, or from the block
    assert not any(p.movable for p in m.world_parts("sc"))
    m.set_movable("cyl", True)
    assert [p.movable for p in m.world_parts("obj")] == [False, True]
    m.set_movable("obj", True)
    assert all(p.movable for p in m.world_parts("sc"))


def test_surface_world_mesh_is_flat():
    m = workcell.Model()
    s = Surface([(0, 0), (3, 0), (3, 2), (0, 2)], [[(1, 0.5), (2, 0.5), (2, 1.5), (1.2, 1.5)]])
    m.create("surface", "plate", s)
    mesh = m.world_mesh("plate")
    assert np.all(np.asarray(mesh.vertices)[:, 2] == 0.0)
    assert mesh.area == pytest.approx(6.0 - 0.9, rel=RTOL)
    p = m.properties("plate")
    assert p.area == pytest.approx(6.0 - 0.9, rel=RTOL)
    poly = shapely.Polygon(s.main, s.holes)
    np.testing.assert_allclose(p.centroid, [poly.centroid.x, poly.centroid.y, 0.0], atol=1e-12)


# ==================================================================== reflections


def test_reflected_placements_give_positive_volume():
    m = workcell.Model()
    solids.cylinder(m, "cyl", radius=0.3, height=1.0, n=9)
    v0 = m.properties("cyl").volume
    M = spatial.scaling(-1.0, 1.0, 1.0)
    # an object with a mirrored TB
    m.create("object", "o")
    m.attach("o", "cyl", spatial.translation(1, 2, 3) @ M)
    assert np.linalg.det(m.relation("o", "tb1").transform[:3, :3]) < 0
    mesh = m.world_mesh("o")
    assert mesh.volume > 0
    assert mesh.is_winding_consistent
    assert m.validity("o").ok
    assert _rel(m.properties("o").volume, v0) < RTOL
    (p,) = m.world_parts("o")
    assert p.mesh.volume > 0
    np.testing.assert_allclose(
        p.mesh.vertices, _apply(p.transform, m.world_mesh("cyl").vertices), atol=1e-12
    )
    # a block copied with a reflection: every relation mirrored
    m.copy("cyl", "mirror", spatial.scaling(1.0, -2.0, 1.0))
    assert m.validity("mirror").ok
    assert _rel(m.properties("mirror").volume, 2 * v0) < RTOL
    # objects in a scene are placed rigidly: a mirror is refused there
    m.create("scene", "s")
    with pytest.raises(GeometryError):
        m.attach("s", "o", M)


# ==================================================================== caching


def test_world_mesh_and_parts_are_cached(cell):
    m = cell
    for ref in ("cube", "obj", "sc"):
        assert m.world_mesh(ref) is m.world_mesh(ref)
        a, b = m.world_parts(ref), m.world_parts(ref)
        assert all(x is y for x, y in zip(a, b, strict=True))
        assert m.properties(ref) is m.properties(ref)


def test_set_transform_updates_mesh_and_spares_siblings(cell):
    m = cell
    m.create("object", "sibling")
    m.attach("sibling", "cube")
    sib, cube, obj = m.world_mesh("sibling"), m.world_mesh("cube"), m.world_mesh("obj")
    sib_props = m.properties("sibling")
    T_new = spatial.translation(7.0, 0.0, 0.0)
    m.set_transform("obj", "base", T_new)
    mesh = m.world_mesh("obj")
    assert mesh is not obj
    expected = np.vstack([_apply(T_new, cube.vertices), _apply(T2, m.world_mesh("cyl").vertices)])
    np.testing.assert_allclose(_sorted_rows(mesh.vertices), _sorted_rows(expected), atol=1e-12)
    assert m.world_parts("obj")[0].transform[0, 3] == 7.0
    # the scene holding the object follows; the block and an unrelated object keep caches
    np.testing.assert_allclose(m.world_parts("sc")[0].transform, T_SCENE @ T_new, atol=1e-12)
    assert m.world_mesh("cube") is cube
    assert m.world_mesh("sibling") is sib
    assert m.properties("sibling") is sib_props


def test_set_colour_updates_parts(cell):
    m = cell
    parts = m.world_parts("obj")
    cyl_mesh = m.world_mesh("cyl")
    m.set_colour("cube", (0.2, 0.4, 0.6))
    new = m.world_parts("obj")
    assert new[0].colour == (0.2, 0.4, 0.6, 1.0)
    assert new[0] is not parts[0]
    assert m.world_mesh("cyl") is cyl_mesh


def test_detach_updates_mesh(cell):
    m = cell
    n_cube, n_cyl = len(m.world_mesh("cube").faces), len(m.world_mesh("cyl").faces)
    assert len(m.world_mesh("sc").faces) == 2 * (n_cube + n_cyl)
    vol = m.properties("obj").volume
    m.detach("obj", "post")
    assert len(m.world_mesh("obj").faces) == n_cube
    assert len(m.world_mesh("sc").faces) == 2 * n_cube
    assert [p.path for p in m.world_parts("sc")] == ["left/base", "right/base"]
    assert _rel(m.properties("obj").volume, vol - m.properties("cyl").volume) < 1e-12


def test_set_surface_updates_mesh_and_spares_siblings():
    m = workcell.Model()
    m.create("surface", "rect", Surface.rectangle(1.0, 1.0))
    m.create("block", "plate")
    m.attach("plate", "rect")
    m.attach("plate", "rect", spatial.translation(0, 0, 1.0))
    solids.cube(m, "cube", size=1.0)
    m.create("object", "o")
    m.attach("o", "plate", spatial.translation(5, 0, 0))
    m.create("object", "other")
    m.attach("other", "cube")
    other, cube = m.world_mesh("other"), m.world_mesh("cube")
    plate = m.world_mesh("plate")
    assert m.world_mesh("o").area == pytest.approx(2.0, rel=RTOL)
    m.set_surface("rect", Surface.rectangle(2.0, 3.0))
    assert m.world_mesh("plate") is not plate
    assert m.world_mesh("o").area == pytest.approx(12.0, rel=RTOL)
    np.testing.assert_allclose(m.world_mesh("o").bounds, [[5, 0, 0], [7, 3, 1]], atol=1e-12)
    assert m.world_mesh("other") is other
    assert m.world_mesh("cube") is cube


# ==================================================================== welding


def _run_across_boundary(k, cell, half_width=100):
    """Consecutive floats (one ulp apart) around (k + 1/2) cell, where the weld's rounding
    grid has a boundary, however the grid coordinate (x - lo) / cell is rounded."""
    x = (k + 0.5) * cell
    for _ in range(half_width):
        x = np.nextafter(x, -np.inf)
    run = [x]
    for _ in range(2 * half_width):
        run.append(np.nextafter(run[-1], np.inf))
    run = np.array(run)
    assert np.ptp(run) < 1e-13
    assert len(np.unique(np.round(run / cell))) == 2  # the run straddles a boundary
    return run


def _weld_map(V, idx):
    """Output vertex of each input vertex idx (faces (0, 1, i) for i in idx)."""
    F = np.column_stack([np.zeros(len(idx), int), np.ones(len(idx), int), idx])
    Vm, Fm, kept = merge_vertices(np.asarray(V, float), F)
    assert kept.all()
    return Fm[:, 2], Vm


def _welded(V, i, j):
    out, Vm = _weld_map(V, [i, j])
    return out[0] == out[1], Vm


def test_merge_welds_points_split_by_rounding():
    cell = 1e-9  # the grid: 1e-9 x the extent, which the two corners make 1
    run = _run_across_boundary(400_000_000, cell)
    V = [(0, 0, 0), (1, 1, 1), *[(x, 0.25, 0.25) for x in run]]
    out, Vm = _weld_map(V, np.arange(2, len(V)))
    assert len(set(out.tolist())) == 1
    assert len(Vm) == 3
    # a face whose corners are two copies of the point collapses and is dropped
    F = np.array([[0, 1, 2], [2, len(V) - 1, 0]])
    _, Fm, kept = merge_vertices(np.asarray(V, float), F)
    assert kept.tolist() == [True, False]
    assert len(Fm) == 1


def test_merge_welds_split_points_whatever_else_shares_their_cells():
    # decoy vertices share the two grid cells the run falls in, but lie on their far
    # sides, more than one cell from the other cell's points: whichever vertex stands for
    # each cell, the run (points one ulp apart) must still weld into one vertex
    cell = 1e-9
    k, j, l_ = 400_000_000, 250_000_000, 250_000_000
    run = _run_across_boundary(k, cell)
    y, z = j * cell, l_ * cell
    low = ((k - 0.45) * cell, y + 0.45 * cell, z + 0.45 * cell)
    high = ((k + 1.45) * cell, y - 0.45 * cell, z - 0.45 * cell)
    pts = [(x, y, z) for x in run]
    V = np.asarray([(0, 0, 0), (1, 1, 1), *[low, high] * 100, *pts, *[high, low] * 100], float)
    idx = np.arange(202, 202 + len(pts))
    q = np.round(V / cell)
    assert set(map(tuple, q[idx])) == {tuple(q[2]), tuple(q[3])}  # decoys share the cells
    assert np.linalg.norm(V[idx] - V[2], axis=1).min() > 1.1 * cell
    assert np.linalg.norm(V[idx] - V[3], axis=1).min() > 1.1 * cell
    out, _ = _weld_map(V, idx)
    assert len(set(out.tolist())) == 1


@settings(max_examples=60, deadline=None)
@given(
    p=st.tuples(*[st.floats(0.0, 1.0)] * 3),
    d=st.tuples(*[st.floats(-1.0, 1.0)] * 3),
    scale=st.sampled_from([1e-13, 1e-14, 1e-15]),
)
def test_merge_welds_any_nearby_pair(p, d, scale):
    # two copies of a point a few 1e-15 apart (as two transforms of one corner give) are
    # always welded, wherever the rounding grid falls
    q = np.asarray(p) + scale * np.asarray(d)
    V = [(0, 0, 0), (1, 1, 1), p, q]
    assume(min(np.abs(np.asarray(p)).max(), np.abs(np.asarray(p) - 1).max()) > 1e-6)
    same, _ = _welded(V, 2, 3)
    assert same


@pytest.mark.parametrize(
    "offset",
    [(2e-9, 0, 0), (0, -3e-9, 0), (2e-9, 2e-9, 2e-9), (1.2e-9, 0, 0)],
)
def test_merge_keeps_points_beyond_tolerance(offset):
    # tolerance: 1e-9 x the extent (1 here). 1.2e-9 along an axis always lands in another
    # cell; the larger offsets are beyond the cell's diagonal too
    for base in [(0.5, 0.5, 0.5), (0.25 + 0.5e-9, 0.3, 0.7), (0.123456789, 0.5, 0.5)]:
        q = np.asarray(base) + offset
        V = [(0, 0, 0), (1, 1, 1), base, q]
        same, Vm = _welded(V, 2, 3)
        assert not same
        assert len(Vm) == 4


def test_merge_scales_with_the_mesh():
    # the tolerance is relative: a 1e-6 gap is welded in a 10 km mesh, not in a 1 m one
    for extent, welded in ((1e4, True), (1.0, False)):
        V = [(0, 0, 0), (extent, extent, extent), (0.3, 0.3, 0.3), (0.3 + 1e-6, 0.3, 0.3)]
        same, _ = _welded(V, 2, 3)
        assert same == welded


@settings(max_examples=25, deadline=None)
@given(
    rot=st.tuples(*[st.floats(-np.pi, np.pi)] * 3),
    t=st.tuples(*[st.floats(-1e3, 1e3)] * 3),
    size=st.tuples(*[st.floats(0.01, 10.0)] * 3),
)
def test_copied_block_placed_anywhere_stays_closed(rot, t, size):
    # each face's corners are computed through a different transform product: the welder
    # must join them into a closed solid wherever it lands
    m = workcell.Model()
    solids.box(m, "b", size=size)
    T = spatial.translation(*t) @ spatial.euler(rot)
    m.copy("b", "moved", T)
    mesh = m.world_mesh("moved")
    assert len(mesh.vertices) == 8
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert _rel(m.properties("moved").volume, float(np.prod(size))) < 1e-9
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)]) * size
    np.testing.assert_allclose(
        _sorted_rows(mesh.vertices), _sorted_rows(_apply(T, corners)), atol=1e-9 * np.max(size)
    )


# ==================================================================== scale


def test_scene_of_1000_instanced_cubes():
    s = 0.1
    m = workcell.Model()
    solids.cube(m, "cube", size=s)
    m.create("object", "unit")
    m.attach("unit", "cube")
    m.create("scene", "grid")
    idx = np.array([(i, j, k) for i in range(10) for j in range(10) for k in range(10)], float)
    R = Rotation.from_euler("z", 0.3).as_matrix()
    Ts = np.tile(np.eye(4), (1000, 1, 1))
    Ts[:, :3, :3] = R
    Ts[:, :3, 3] = idx * 0.25
    m.attach_many("grid", "unit", Ts)
    mesh = m.world_mesh("grid")
    assert len(mesh.faces) == 12000
    assert len(mesh.vertices) == 8000
    assert _rel(m.properties("grid").volume, 1000 * s**3) < 1e-12
    assert _rel(mesh.volume, 1000 * s**3) < 1e-9
    parts = m.world_parts("grid")
    assert len(parts) == 1000
    assert parts[999].path == "to1000/tb1"
    centre = _apply(Ts[999], [s / 2] * 3)
    np.testing.assert_allclose(parts[999].mesh.vertices.mean(axis=0), centre, atol=1e-12)
