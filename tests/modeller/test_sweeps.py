"""Tests of the sweeps (thesis §3): translational (extrude), rotational (revolve) and the
position/direction-curve sweep with scaling.

Expected values come from outside the code: area x height (and Cavalieri for oblique
directions), shapely's area and centroid with the exact m-step revolve formula
V = n sin(angle / n) * A * r_bar, trimesh.creation.revolve / extrude_polygon of the same
profile, the frustum and prismatoid formulas, and Pappus' theorem in the limit.
"""

from __future__ import annotations

import numpy as np
import pytest
import shapely
import trimesh
from helpers import assembled_as_placed, check_solid, snapshot
from hypothesis import given, settings
from hypothesis import strategies as st

import workcell
from workcell import solids, spatial
from workcell.errors import GeometryError, ModelError
from workcell.modeller.surface import Surface

RTOL = 1e-12

MAIN = [(0.0, 0.0), (4.0, 0.0), (4.0, 3.0), (0.0, 3.0)]
HOLES = [
    [(0.5, 0.5), (1.5, 0.5), (1.5, 1.5), (0.5, 1.5)],
    [(2.0, 2.0), (3.0, 2.0), (2.5, 2.7)],
]
# main 12 m^2, minus a unit square and a triangle of base 1, height 0.7
AREA_WITH_HOLES = 12.0 - 1.0 - 0.35


def _rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


def _revolve_volume(profile, n, angle=2 * np.pi, holes=()):
    """Exact volume of the n-step revolve: n sin(angle/n) times the profile's first moment
    about the axis (shapely computes area and centroid)."""
    poly = shapely.Polygon(profile, holes)
    return n * np.sin(angle / n) * poly.area * poly.centroid.x


def _closed(p):
    p = np.asarray(p, float)
    return np.vstack([p, p[:1]])


# ==================================================================== extrude


def test_extrude_with_holes_volume_patches_genus():
    m = workcell.Model()
    s = Surface(MAIN, HOLES)
    assert s.area == pytest.approx(AREA_WITH_HOLES, rel=RTOL)
    h = 0.7
    assert solids.extrude(m, "ex", s, height=h) == "ex"
    mesh = check_solid(m, "ex")
    p = m.properties("ex")
    assert _rel(p.volume, AREA_WITH_HOLES * h) < RTOL
    # thesis rule: m + n side patches (4 main edges, 4 + 3 hole edges) plus 2 caps
    rels = m.relations("ex")
    n_edges = 4 + 4 + 3
    assert len(rels) == n_edges + 2
    targets = [r.target for r in rels]
    side = max(set(targets), key=targets.count)
    assert targets.count(side) == n_edges
    assert m.surface(side).area == pytest.approx(1.0)  # the unit square, placed per edge
    # genus = number of holes: Euler characteristic 2 - 2 g
    assert mesh.euler_number == 2 - 2 * len(HOLES)
    # independent: trimesh's extrusion of the same polygon
    ref = trimesh.creation.extrude_polygon(shapely.Polygon(MAIN, HOLES), h)
    assert _rel(p.volume, ref.volume) < 1e-9
    assert _rel(p.area, ref.area) < 1e-9
    np.testing.assert_allclose(p.centroid, ref.center_mass, atol=1e-9)


@pytest.mark.parametrize(
    "d", [(0.3, -0.4, 0.7), (0.0, 0.0, -0.7), (0.2, 0.1, -0.5), (-2.0, 1.5, 0.25)]
)
def test_extrude_oblique_and_downward_cavalieri(d):
    m = workcell.Model()
    s = Surface(MAIN, HOLES)
    solids.extrude(m, "ex", s, direction=d)
    mesh = check_solid(m, "ex")
    p = m.properties("ex")
    assert _rel(p.volume, AREA_WITH_HOLES * abs(d[2])) < RTOL
    assert mesh.euler_number == 2 - 2 * len(HOLES)
    # the solid is the surface's points plus t d, t in [0, 1]: its centroid is the
    # surface's centroid plus d / 2
    poly = shapely.Polygon(MAIN, HOLES)
    c2 = np.array([poly.centroid.x, poly.centroid.y, 0.0])
    np.testing.assert_allclose(p.centroid, c2 + np.asarray(d) / 2, atol=1e-12)
    z = np.asarray(mesh.vertices)[:, 2]
    assert np.isclose(z.min(), min(0.0, d[2]), atol=1e-15)
    assert np.isclose(z.max(), max(0.0, d[2]), atol=1e-15)


def test_extrude_downward_is_mirror_of_upward():
    m = workcell.Model()
    solids.extrude(m, "up", Surface(MAIN, HOLES), height=0.7)
    solids.extrude(m, "down", Surface(MAIN, HOLES), direction=(0, 0, -0.7))
    vu = np.asarray(m.world_mesh("up").vertices)
    vd = np.asarray(m.world_mesh("down").vertices) * [1, 1, -1]
    key = lambda v: v[np.lexsort(np.round(v, 9).T[::-1])]  # noqa: E731
    np.testing.assert_allclose(key(vu), key(vd), atol=1e-14)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"direction": (1.0, 1.0, 0.0)},
        {"direction": (1.0, 0.0, 1e-14)},
        {"direction": (0.0, 0.0, 0.0)},
        {"height": 0.0},
        {"height": float("nan")},
        {"direction": (0.0, 0.0, float("inf"))},
        {"direction": (0.0, 1.0)},
        {"height": 1.0, "direction": (0.0, 0.0, 1.0)},
        {},
    ],
)
def test_extrude_bad_direction_raises_and_changes_nothing(kwargs):
    m = workcell.Model()
    m.create("surface", "prof", Surface(MAIN, HOLES))
    before = snapshot(m)
    with pytest.raises(GeometryError):
        solids.extrude(m, "ex", "prof", **kwargs)
    assert snapshot(m) == before
    assert not m.exists("ex")


def test_extrude_bad_profile_raises():
    m = workcell.Model()
    with pytest.raises(GeometryError):  # a bow tie is not a simple polygon
        solids.extrude(m, "ex", [(0, 0), (1, 1), (1, 0), (0, 1)], height=1.0)
    with pytest.raises(GeometryError):  # two points are not a surface
        solids.extrude(m, "ex", [(0, 0), (1, 1)], height=1.0)
    with pytest.raises(ModelError):  # unknown surface entity
        solids.extrude(m, "ex", "no_such_surface", height=1.0)
    assert m.list() == {"surface": [], "block": [], "object": [], "scene": []}


def test_extrude_of_existing_surface_shares_it():
    m = workcell.Model()
    m.create("surface", "prof", Surface(MAIN, HOLES))
    assert m.pointed_by("prof") == 0
    solids.extrude(m, "ex1", "prof", height=1.0)
    assert m.pointed_by("prof") == 2  # the two caps
    solids.extrude(m, "ex2", "prof", direction=(0.1, 0.0, -2.0))
    assert m.pointed_by("prof") == 4
    assert "ex1.profile" not in m.list("surface")
    assert _rel(m.properties("ex2").volume, 2 * AREA_WITH_HOLES) < RTOL
    with pytest.raises(ModelError):
        m.remove("prof")
    # points given directly make the block's own profile surface
    solids.extrude(m, "ex3", MAIN, height=1.0)
    assert m.pointed_by("ex3.profile") == 2


_coord = st.floats(-3.0, 3.0, allow_nan=False)


@settings(max_examples=25, deadline=None)
@given(
    w=st.floats(0.1, 5.0),
    hgt=st.floats(0.1, 5.0),
    hole=st.floats(0.05, 0.9),
    dx=_coord,
    dy=_coord,
    dz=st.one_of(st.floats(0.05, 4.0), st.floats(-4.0, -0.05)),
)
def test_extrude_random_cavalieri(w, hgt, hole, dx, dy, dz):
    # a rectangle with a centred rectangular hole, swept along a random direction
    hw, hh = hole * w / 2, hole * hgt / 2
    main = [(-w / 2, -hgt / 2), (w / 2, -hgt / 2), (w / 2, hgt / 2), (-w / 2, hgt / 2)]
    hl = [(-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh)]
    m = workcell.Model()
    solids.extrude(m, "ex", Surface(main, [hl]), direction=(dx, dy, dz))
    mesh = m.world_mesh("ex")
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert mesh.euler_number == 0
    area = w * hgt * (1 - hole**2)
    assert _rel(m.properties("ex").volume, area * abs(dz)) < 1e-11
    np.testing.assert_allclose(m.properties("ex").centroid, np.array([dx, dy, dz]) / 2, atol=1e-11)


# ==================================================================== revolve

PROFILE = np.array([(1.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.5, 1.5), (1.0, 1.0)])


@pytest.mark.parametrize("n", [3, 12, 40])
def test_revolve_full_exact_and_vs_trimesh(n):
    m = workcell.Model()
    assert solids.revolve(m, "r", PROFILE, n=n) == "r"
    mesh = check_solid(m, "r")
    p = m.properties("r")
    assert _rel(p.volume, _revolve_volume(PROFILE, n)) < RTOL
    ref = trimesh.creation.revolve(_closed(PROFILE), sections=n)
    assert _rel(p.volume, ref.volume) < 1e-9
    assert _rel(p.area, ref.area) < 1e-9
    np.testing.assert_allclose(p.inertia, ref.moment_inertia, atol=1e-9 * np.abs(p.inertia).max())
    assert mesh.euler_number == 0
    assert len(mesh.vertices) == n * len(PROFILE)


@pytest.mark.parametrize(("angle", "n"), [(2.0, 6), (np.pi / 2, 1), (np.pi, 9), (6.0, 30)])
def test_revolve_partial_capped(angle, n):
    m = workcell.Model()
    solids.revolve(m, "r", PROFILE, n=n, angle=angle)
    mesh = check_solid(m, "r")
    assert mesh.euler_number == 2
    p = m.properties("r")
    assert _rel(p.volume, _revolve_volume(PROFILE, n, angle)) < RTOL
    ref = trimesh.creation.revolve(_closed(PROFILE), angle=angle, sections=n, cap=True)
    assert _rel(p.volume, ref.volume) < 1e-9
    assert _rel(p.area, ref.area) < 1e-9
    # the two caps are the profile itself (2 x its area) plus the swept sides
    side_area = p.area - 2 * shapely.Polygon(PROFILE).area
    assert side_area > 0
    # the start cap lies in the xz-plane (y = 0), the end cap in the plane at `angle`
    v = np.asarray(mesh.vertices)
    phi = np.arctan2(v[:, 1], v[:, 0]) % (2 * np.pi)
    phi[phi > angle + 1e-9] -= 2 * np.pi
    assert phi.min() > -1e-12
    assert phi.max() < angle + 1e-12


def test_revolve_partial_of_existing_surface_shares_it():
    m = workcell.Model()
    m.create("surface", "prof", Surface(PROFILE))
    solids.revolve(m, "full", "prof", n=8)
    assert m.pointed_by("prof") == 0  # a full revolve has no caps
    solids.revolve(m, "part", "prof", n=8, angle=1.0)
    assert m.pointed_by("prof") == 2
    assert _rel(m.properties("part").volume, _revolve_volume(PROFILE, 8, 1.0)) < RTOL


@pytest.mark.parametrize("angle", [2 * np.pi, 1.3])
def test_revolve_profile_touching_axis(angle):
    # cone-like: an edge on the axis sweeps to nothing, its neighbours meet at the axis
    prof = np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 2.0)])
    n = 10
    m = workcell.Model()
    solids.revolve(m, "r", prof, n=n, angle=angle)
    mesh = check_solid(m, "r")
    assert mesh.euler_number == 2
    p = m.properties("r")
    assert _rel(p.volume, _revolve_volume(prof, n, angle)) < RTOL
    full = angle >= 2 * np.pi
    ref = trimesh.creation.revolve(
        _closed(prof), angle=None if full else angle, sections=n, cap=not full
    )
    assert _rel(p.volume, ref.volume) < 1e-9
    assert _rel(p.area, ref.area) < 1e-9


def test_revolve_profile_with_hole():
    outer = [(1.0, 0.0), (3.0, 0.0), (3.0, 2.0), (1.0, 2.0)]
    hole = [(1.5, 0.5), (2.5, 0.5), (2.2, 1.5)]
    n = 12
    m = workcell.Model()
    solids.revolve(m, "r", Surface(outer, [hole]), n=n)
    mesh = check_solid(m, "r")
    assert mesh.euler_number == 0  # two nested tori, each of Euler characteristic 0
    assert mesh.body_count == 2
    assert _rel(m.properties("r").volume, _revolve_volume(outer, n, holes=[hole])) < RTOL


@pytest.mark.parametrize(
    ("profile", "kwargs"),
    [
        ([(-0.5, 0.0), (1.0, 0.0), (1.0, 1.0)], {}),  # crosses the axis
        ([(-1e-6, 0.0), (1.0, 0.0), (1.0, 1.0)], {"angle": 1.0}),
        (PROFILE, {"angle": 0.0}),
        (PROFILE, {"angle": -1.0}),
        (PROFILE, {"angle": 7.0}),
        (PROFILE, {"angle": float("nan")}),
        (PROFILE, {"n": 2}),
        (PROFILE, {"n": 0, "angle": 1.0}),
        (PROFILE, {"n": 4.5}),
        (PROFILE, {"n": True}),
    ],
)
def test_revolve_bad_inputs_raise_and_change_nothing(profile, kwargs):
    m = workcell.Model()
    solids.cube(m, "c", size=1.0)
    before = snapshot(m)
    with pytest.raises(GeometryError):
        solids.revolve(m, "r", profile, **kwargs)
    assert snapshot(m) == before
    assert not m.exists("r")


@settings(max_examples=20, deadline=None)
@given(
    # on the axis, or clear of it: radii below the weld tolerance (1e-9 x size) are not
    # resolvable features
    r0=st.one_of(st.just(0.0), st.floats(0.01, 2.0)),
    dr=st.floats(0.1, 2.0),
    z0=st.floats(-2.0, 2.0),
    dz=st.floats(0.1, 2.0),
    top=st.one_of(st.just(0.0), st.floats(0.01, 1.0)),
    n=st.integers(3, 24),
    partial=st.booleans(),
    frac=st.floats(0.05, 0.95),
)
def test_revolve_random(r0, dr, z0, dz, top, n, partial, frac):
    # a trapezoid (r0, z0)-(r0+dr, z0)-(r0+dr, z0+dz)-(r0 + top dr, z0+dz); r0 may be 0
    prof = [(r0, z0), (r0 + dr, z0), (r0 + dr, z0 + dz), (r0 + top * dr, z0 + dz)]
    angle = frac * 2 * np.pi if partial else 2 * np.pi
    m = workcell.Model()
    solids.revolve(m, "r", prof, n=n, angle=angle)
    mesh = m.world_mesh("r")
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert _rel(m.properties("r").volume, _revolve_volume(prof, n, angle)) < 1e-11


# ==================================================================== sweep along a PD curve


def test_sweep_straight_equals_extrude():
    s = Surface(MAIN, HOLES)
    m = workcell.Model()
    solids.extrude(m, "ex", s, height=1.3)
    assert solids.sweep(m, "sw", s, [(0, 0, 0), (0, 0, 1.3)]) == "sw"
    check_solid(m, "sw")
    pe, ps = m.properties("ex"), m.properties("sw")
    assert _rel(ps.volume, AREA_WITH_HOLES * 1.3) < RTOL
    assert _rel(ps.volume, pe.volume) < RTOL
    assert _rel(ps.area, pe.area) < RTOL
    np.testing.assert_allclose(ps.centroid, pe.centroid, atol=1e-12)
    np.testing.assert_allclose(ps.inertia, pe.inertia, atol=1e-12 * np.abs(pe.inertia).max())
    # same corner points
    key = lambda v: v[np.lexsort(np.round(v, 9).T[::-1])]  # noqa: E731
    np.testing.assert_allclose(
        key(np.asarray(m.world_mesh("sw").vertices)),
        key(np.asarray(m.world_mesh("ex").vertices)),
        atol=1e-14,
    )
    assert m.world_mesh("sw").euler_number == 2 - 2 * len(HOLES)


@settings(max_examples=20, deadline=None)
@given(
    start=st.tuples(_coord, _coord, _coord),
    d=st.tuples(_coord, _coord, _coord).filter(lambda v: np.linalg.norm(v) > 0.1),
    k=st.integers(2, 6),
)
def test_sweep_random_straight_line(start, d, k):
    # sections perpendicular to any straight path: a right prism of volume area x length
    s = Surface([(0, 0), (0.5, 0), (0.6, 0.4), (0.1, 0.3)])
    path = np.asarray(start) + np.linspace(0, 1, k)[:, None] * np.asarray(d)
    up = (1.0, 0.0, 0.0) if abs(d[0]) < 0.9 * np.linalg.norm(d) else (0.0, 1.0, 0.0)
    m = workcell.Model()
    solids.sweep(m, "sw", s, path, up=up)
    mesh = m.world_mesh("sw")
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert _rel(m.properties("sw").volume, s.area * np.linalg.norm(d)) < 1e-11


def _arc(R, N, angle=np.pi / 2):
    t = np.linspace(0.0, angle, N + 1)
    P = np.column_stack([R * np.cos(t), np.zeros_like(t), R * np.sin(t)])
    D = np.column_stack([-np.sin(t), np.zeros_like(t), np.cos(t)])
    return P, D


def test_sweep_quarter_circle_exact_with_tangents():
    # with exact tangents every section is the first one turned about the y axis: the
    # solid is the N-step revolve of the profile, V = N sin(angle/N) A R
    w, d, R = 0.2, 0.1, 1.0
    for N in (1, 4, 16):
        P, D = _arc(R, N)
        m = workcell.Model()
        solids.sweep(m, "sw", Surface.rectangle(w, d, center=True), P, directions=D, up=(0, 1, 0))
        check_solid(m, "sw")
        assert _rel(m.properties("sw").volume, N * np.sin(np.pi / (2 * N)) * w * d * R) < RTOL


def test_sweep_holed_asymmetric_profile_along_arc_exact():
    # section k is section 0 turned about the y axis; section 0 maps profile (u, v) to
    # (R - v, u, 0), so V = N sin(angle/N) A (R - v_bar) (v_bar: the profile's centroid y)
    main = [(-0.1, -0.05), (0.15, -0.05), (0.12, 0.08), (-0.1, 0.06)]
    hole = [(-0.05, -0.02), (0.05, -0.02), (0.0, 0.03)]
    poly = shapely.Polygon(main, [hole])
    R = 1.0
    for N in (3, 10):
        P, D = _arc(R, N)
        m = workcell.Model()
        solids.sweep(m, "sw", Surface(main, [hole]), P, directions=D, up=(0, 1, 0))
        mesh = check_solid(m, "sw")
        assert mesh.euler_number == 0  # one hole through the swept bar: genus 1
        expected = N * np.sin(np.pi / (2 * N)) * poly.area * (R - poly.centroid.y)
        assert _rel(m.properties("sw").volume, expected) < RTOL


def test_revolve_profile_orientation_does_not_matter():
    m = workcell.Model()
    solids.revolve(m, "ccw", PROFILE, n=7, angle=2.0)
    solids.revolve(m, "cw", PROFILE[::-1], n=7, angle=2.0)
    check_solid(m, "cw")
    assert _rel(m.properties("cw").volume, m.properties("ccw").volume) < RTOL
    assert _rel(m.properties("cw").volume, _revolve_volume(PROFILE, 7, 2.0)) < RTOL


@pytest.mark.parametrize("tangents", [True, False])
def test_sweep_quarter_circle_converges_to_pappus_second_order(tangents):
    w, d, R = 0.2, 0.1, 1.0
    pappus = w * d * R * np.pi / 2
    errors = []
    for N in (8, 16, 32, 64):
        P, D = _arc(R, N)
        m = workcell.Model()
        solids.sweep(
            m,
            "sw",
            Surface.rectangle(w, d, center=True),
            P,
            directions=D if tangents else None,
            up=(0, 1, 0),
        )
        assert m.validity("sw").ok
        errors.append(m.properties("sw").volume - pappus)
    errors = np.abs(errors)
    assert errors[-1] < 2e-4 * pappus
    ratios = errors[1:] / errors[:-1]
    np.testing.assert_allclose(ratios, 0.25, atol=0.03)


@pytest.mark.parametrize("k", [2, 3, 7])
def test_sweep_linear_taper_is_frustum(k):
    h, s0, s1 = 2.0, 1.0, 0.4
    path = np.column_stack([np.zeros(k), np.zeros(k), np.linspace(0, h, k)])
    scales = np.linspace(s0, s1, k)
    m = workcell.Model()
    solids.sweep(m, "fr", Surface.rectangle(1.0, 1.0, center=True), path, scales=scales)
    check_solid(m, "fr")
    a1, a2 = s0**2, s1**2
    assert _rel(m.properties("fr").volume, h / 3 * (a1 + a2 + np.sqrt(a1 * a2))) < RTOL
    # a corner-anchored square scales about its corner: an oblique frustum, same volume
    solids.sweep(m, "fr2", Surface.rectangle(1.0, 1.0), path, scales=scales)
    check_solid(m, "fr2")
    assert _rel(m.properties("fr2").volume, h / 3 * (a1 + a2 + np.sqrt(a1 * a2))) < RTOL


@settings(max_examples=20, deadline=None)
@given(
    w=st.floats(0.1, 3.0),
    d=st.floats(0.1, 3.0),
    h=st.floats(0.1, 3.0),
    sx=st.tuples(st.floats(0.1, 3.0), st.floats(0.1, 3.0)),
    sy=st.tuples(st.floats(0.1, 3.0), st.floats(0.1, 3.0)),
)
def test_sweep_anisotropic_taper_prismatoid(w, d, h, sx, sy):
    # rectangle w x d scaled linearly from (sx0, sy0) to (sx1, sy1): a prismatoid,
    # V = h/6 (A0 + 4 Am + A1) with the mid-section at the mean scales
    k = 3
    path = np.column_stack([np.zeros(k), np.zeros(k), np.linspace(0, h, k)])
    scales = np.column_stack([np.linspace(*sx, k), np.linspace(*sy, k)])
    m = workcell.Model()
    solids.sweep(m, "pz", Surface.rectangle(w, d, center=True), path, scales=scales)
    mesh = m.world_mesh("pz")
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    a0 = w * d * sx[0] * sy[0]
    a1 = w * d * sx[1] * sy[1]
    am = w * d * (sx[0] + sx[1]) / 2 * (sy[0] + sy[1]) / 2
    assert _rel(m.properties("pz").volume, h / 6 * (a0 + 4 * am + a1)) < 1e-11


def test_sweep_of_existing_surface_shares_it():
    m = workcell.Model()
    m.create("surface", "prof", Surface.rectangle(0.2, 0.1, center=True))
    P, D = _arc(1.0, 6)
    solids.sweep(m, "sw", "prof", P, directions=D, up=(0, 1, 0))
    assert m.pointed_by("prof") == 2


@pytest.mark.parametrize(
    ("path", "kwargs"),
    [
        ([(0, 0, 0)], {}),  # one point
        ([(0, 0), (0, 1)], {}),  # 2-D points
        ([(0, 0, 0), (0, 0, float("nan"))], {}),
        ([(0, 0, 0), (0, 0, 0), (0, 0, 1)], {}),  # a repeated point: zero direction
        ([(0, 0, 0), (0, 0, 1)], {"directions": [(0, 0, 1)]}),  # wrong shape
        ([(0, 0, 0), (0, 0, 1)], {"directions": [(0, 0, 1), (0, 0, 0)]}),
        ([(0, 0, 0), (0, 0, 1)], {"scales": [1.0, -1.0]}),
        ([(0, 0, 0), (0, 0, 1)], {"scales": [1.0, 0.0]}),
        ([(0, 0, 0), (0, 0, 1)], {"scales": [1.0, 1.0, 1.0]}),
        ([(0, 0, 0), (0, 0, 1)], {"scales": [1.0, float("nan")]}),
        ([(0, 0, 0), (0, 0, 1)], {"up": (0.0, 0.0, 2.0)}),  # up along the path
    ],
)
def test_sweep_bad_inputs_raise_and_change_nothing(path, kwargs):
    m = workcell.Model()
    solids.cube(m, "c", size=1.0)
    before = snapshot(m)
    with pytest.raises(GeometryError):
        solids.sweep(m, "sw", Surface.rectangle(1.0, 1.0), path, **kwargs)
    assert snapshot(m) == before
    assert not m.exists("sw")


def test_every_sweep_places_its_surfaces_front_side_out():
    m = workcell.Model()
    s = Surface(MAIN, HOLES)
    solids.extrude(m, "up", s, height=0.7)
    solids.extrude(m, "down", s, direction=(0.2, 0.1, -0.5))
    solids.revolve(m, "full", PROFILE, n=9)
    solids.revolve(m, "part", PROFILE, n=5, angle=2.0)
    solids.revolve(m, "axis", [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 2.0)], n=8, angle=1.0)
    P, D = _arc(1.0, 6)
    solids.sweep(m, "arc", Surface(MAIN, HOLES), P * 10, directions=D, up=(0, 1, 0))
    path = np.column_stack([np.zeros(3), np.zeros(3), np.linspace(0, 2, 3)])
    solids.sweep(m, "taper", Surface.rectangle(1, 1), path, scales=[1.0, 0.7, 0.4])
    for name in ("up", "down", "full", "part", "axis", "arc", "taper"):
        mesh = assembled_as_placed(m, name)
        assert mesh.is_watertight, name
        assert mesh.is_winding_consistent, name
        assert mesh.volume > 0, name
        assert _rel(mesh.volume, m.properties(name).volume) < 1e-9, name


def test_sweeps_placed_by_rigid_transform_keep_volume():
    m = workcell.Model()
    solids.extrude(m, "ex", Surface(MAIN, HOLES), direction=(0.1, 0.2, 0.9))
    solids.revolve(m, "rv", PROFILE, n=9, angle=2.5)
    P, D = _arc(1.0, 8)
    solids.sweep(m, "sw", Surface.rectangle(0.2, 0.1, center=True), P, directions=D, up=(0, 1, 0))
    T = spatial.euler([0.4, 0.2, -1.0], translation=(10.0, -3.0, 2.0))
    for b in ("ex", "rv", "sw"):
        m.create("object", f"{b}_o")
        m.attach(f"{b}_o", b, T)
        assert _rel(m.properties(f"{b}_o").volume, m.properties(b).volume) < 1e-12
        assert m.validity(f"{b}_o").ok
