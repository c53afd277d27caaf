"""Tests of the primitive solids (thesis §3): cube, box, cylinder, sphere, ellipsoid, cone, torus.

Every expected number comes from outside the code under test: closed forms of the exact
polyhedra, scipy's ConvexHull of independently computed vertices, trimesh's own mass
properties and revolve.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from helpers import assembled_as_placed, check_solid, ngon_area, snapshot
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull

import workcell
from workcell import solids, spatial
from workcell.errors import GeometryError, ModelError

RTOL = 1e-12


def _rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


def _check_mass_properties(model, name, rtol=1e-9):
    """model.properties agrees with trimesh's mass properties of the same world mesh."""
    mesh = model.world_mesh(name)
    tm = trimesh.Trimesh(np.array(mesh.vertices), np.array(mesh.faces), process=False)
    ref = tm.mass_properties
    p = model.properties(name)
    size = float(np.ptp(mesh.vertices, axis=0).max())
    assert _rel(p.volume, ref["volume"]) < rtol
    assert _rel(p.area, tm.area) < rtol
    np.testing.assert_allclose(p.centroid, ref["center_mass"], rtol=0, atol=rtol * size)
    np.testing.assert_allclose(
        p.first_moments, p.volume * np.asarray(ref["center_mass"]), rtol=0, atol=rtol * size**4
    )
    scale = np.abs(ref["inertia"]).max()
    np.testing.assert_allclose(p.inertia, ref["inertia"], rtol=0, atol=rtol * scale)
    return p


# ==================================================================== cube and box


@pytest.mark.parametrize("size", [1.0, 0.25, 3.7])
def test_cube_volume_inertia_centroid(size):
    m = workcell.Model()
    assert solids.cube(m, "c", size=size) == "c"
    check_solid(m, "c")
    p = _check_mass_properties(m, "c")
    assert _rel(p.volume, size**3) < RTOL
    assert _rel(p.area, 6 * size**2) < RTOL
    np.testing.assert_allclose(p.centroid, [size / 2] * 3, rtol=RTOL)
    np.testing.assert_allclose(p.inertia, np.eye(3) * size**5 / 6, rtol=0, atol=1e-12 * size**5)


def test_cube_is_one_square_pointed_to_six_times():
    m = workcell.Model()
    solids.cube(m, "cube1", size=1.0)
    surfaces = [s for s in m.list("surface") if s.startswith("cube1.")]
    assert len(surfaces) == 1
    assert m.pointed_by(surfaces[0]) == 6
    assert m.surface(surfaces[0]).area == pytest.approx(1.0, rel=RTOL)
    assert m.info("cube1").n_relations == 6
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    v = np.array(m.world_mesh("cube1").vertices)
    assert len(v) == 8
    np.testing.assert_allclose(v[np.lexsort(v.T[::-1])], corners, atol=1e-15)
    # the thesis's face planes: y=0, y=1, x=0, x=1, z=0, z=1, each once
    planes = set()
    for rel in m.relations("cube1"):
        pts = spatial.transform_points(rel.transform, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
        axis = int(np.flatnonzero(np.ptp(pts, axis=0) < 1e-12)[0])
        planes.add((axis, round(float(pts[0, axis]), 12)))
    assert planes == {(a, v) for a in range(3) for v in (0.0, 1.0)}


def test_box_parallelepiped_three_ways():
    a, b, c = 2.0, 3.0, 1.5
    expected_inertia = 9.0 / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    m = workcell.Model()
    solids.box(m, "box", size=(a, b, c))
    solids.cube(m, "cube1", size=1.0)
    # a copy of cube1 at block level with the scaling applied
    m.copy("cube1", "para", spatial.scaling(a, b, c))
    # an object with one TB scaling the unit cube
    m.create("object", "para_obj")
    m.attach("para_obj", "cube1", spatial.scaling(a, b, c))
    for name in ("box", "para", "para_obj"):
        p = _check_mass_properties(m, name)
        assert _rel(p.volume, 9.0) < RTOL, name
        assert _rel(p.area, 2 * (a * b + b * c + a * c)) < RTOL, name
        np.testing.assert_allclose(p.centroid, [a / 2, b / 2, c / 2], rtol=RTOL)
        np.testing.assert_allclose(p.inertia, expected_inertia, rtol=0, atol=1e-12 * 9)
    check_solid(m, "box")
    check_solid(m, "para")
    assert m.validity("para_obj").ok
    # the copy and the object share cube1's square: 6 (cube1) + 6 (para) pointers
    assert m.pointed_by("cube1.square") == 12
    assert m.pointed_by("cube1") == 1


# ==================================================================== cylinder


def _cylinder_expect(r, h, n):
    base = ngon_area(n, r)
    vol = base * h
    area = 2 * base + n * 2 * r * np.sin(np.pi / n) * h
    izz = vol * r**2 * (2 + np.cos(2 * np.pi / n)) / 6
    ixx = izz / 2 + vol * h**2 / 12  # a regular n-gon's area moments are isotropic
    return vol, area, np.diag([ixx, ixx, izz])


def _check_cylinder(m, name, r, h, n):
    mesh = check_solid(m, name)
    p = _check_mass_properties(m, name)
    vol, area, inertia = _cylinder_expect(r, h, n)
    assert _rel(p.volume, vol) < 1e-11
    assert _rel(p.area, area) < 1e-11
    np.testing.assert_allclose(p.centroid, [0, 0, h / 2], rtol=0, atol=1e-12 * max(r, h))
    np.testing.assert_allclose(p.inertia, inertia, rtol=0, atol=1e-11 * np.abs(inertia).max())
    v = np.array(mesh.vertices)
    assert len(v) == 2 * n
    np.testing.assert_allclose(np.hypot(v[:, 0], v[:, 1]), r, rtol=1e-12)
    z = np.sort(np.unique(np.round(v[:, 2] / h, 12)))
    np.testing.assert_array_equal(z, [0.0, 1.0])
    assert np.isclose(v[:, 2].min(), 0.0, atol=1e-15)


@pytest.mark.parametrize(("r", "h", "n"), [(0.5, 2.0, 3), (0.5, 2.0, 8), (1.3, 0.2, 64)])
def test_cylinder_exact_prism(r, h, n):
    m = workcell.Model()
    solids.cylinder(m, "cy", radius=r, height=h, n=n)
    _check_cylinder(m, "cy", r, h, n)


def test_cylinder_thesis_construction():
    r, h, n = 0.7, 1.9, 9
    theta = 2 * np.pi / n
    m = workcell.Model()
    solids.cylinder(m, "cy", radius=r, height=h, n=n)
    mine = [s for s in m.list("surface") if s.startswith("cy.")]
    assert len(mine) == 2
    square = [s for s in mine if len(m.surface(s).main) == 4]
    gon = [s for s in mine if len(m.surface(s).main) == n]
    assert len(square) == 1
    assert len(gon) == 1
    sq = m.surface(square[0])
    assert sq.area == pytest.approx(1.0, rel=RTOL)
    assert not sq.holes
    np.testing.assert_allclose(np.sort(sq.main, axis=0), [[0, 0], [0, 0], [1, 1], [1, 1]])
    g = m.surface(gon[0])
    np.testing.assert_allclose(np.hypot(*g.main.T), r, rtol=1e-12)
    rels = m.relations("cy")
    assert len(rels) == n + 2
    assert m.pointed_by(square[0]) == n
    assert m.pointed_by(gon[0]) == 2
    # facet i: unit square scaled (l, h), at (-r sin(i theta), r cos(i theta), 0)
    l_facet = r * np.sqrt(2 * (1 - np.cos(theta)))
    sides = [rel.transform for rel in rels if rel.target == square[0]]
    starts = {
        (round(-r * np.sin(i * theta), 12), round(r * np.cos(i * theta), 12)) for i in range(n)
    }
    got = set()
    for T in sides:
        assert np.linalg.norm(T[:3, 0]) == pytest.approx(l_facet, rel=1e-12)
        np.testing.assert_allclose(T[:3, 1], [0, 0, h], atol=1e-15)
        assert abs(T[2, 3]) < 1e-15
        got.add((round(T[0, 3], 12) + 0.0, round(T[1, 3], 12) + 0.0))
    assert got == {(x + 0.0, y + 0.0) for x, y in starts}


@settings(max_examples=25, deadline=None)
@given(
    r=st.floats(0.01, 20.0),
    h=st.floats(0.01, 20.0),
    n=st.integers(3, 48),
)
def test_cylinder_random(r, h, n):
    m = workcell.Model()
    solids.cylinder(m, "cy", radius=r, height=h, n=n)
    _check_cylinder(m, "cy", r, h, n)


# ==================================================================== sphere and ellipsoid


def _sphere_vertices(r, m, n):
    """The sphere's corner points, independently: latitudes j pi/(2n), longitudes k 2pi/m."""
    alpha, beta = np.pi / (2 * n), 2 * np.pi / m
    pts = [(0.0, 0.0, r), (0.0, 0.0, -r)]
    for j in range(-(n - 1), n):
        phi = j * alpha
        for k in range(m):
            lam = k * beta
            pts.append(
                (r * np.cos(phi) * np.cos(lam), r * np.cos(phi) * np.sin(lam), r * np.sin(phi))
            )
    return np.array(pts)


def _sorted_rows(v):
    v = np.asarray(v)
    return v[np.lexsort(np.round(v, 9).T[::-1])]


@pytest.mark.parametrize(("r", "m_", "n"), [(1.0, 8, 3), (0.3, 16, 8), (2.5, 5, 1), (1.7, 3, 2)])
def test_sphere_against_convex_hull(r, m_, n):
    m = workcell.Model()
    assert solids.sphere(m, "s", radius=r, m=m_, n=n) == "s"
    mesh = check_solid(m, "s")
    p = _check_mass_properties(m, "s")
    ref = _sphere_vertices(r, m_, n)
    v = np.array(mesh.vertices)
    assert len(v) == len(ref)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), r, rtol=1e-12)
    np.testing.assert_allclose(_sorted_rows(v), _sorted_rows(ref), rtol=0, atol=1e-12 * r)
    hull = ConvexHull(ref)
    assert _rel(p.volume, hull.volume) < RTOL
    assert _rel(p.area, hull.area) < RTOL
    np.testing.assert_allclose(p.centroid, 0.0, atol=1e-12 * r)


def test_sphere_octahedron_closed_form():
    # m = 4 slices, n = 1 face per half slice: the regular octahedron, V = 4 r^3 / 3
    r = 1.25
    m = workcell.Model()
    solids.sphere(m, "oct", radius=r, m=4, n=1)
    p = _check_mass_properties(m, "oct")
    assert _rel(p.volume, 4 * r**3 / 3) < RTOL
    assert _rel(p.area, 8 * np.sqrt(3) / 4 * (np.sqrt(2) * r) ** 2) < RTOL
    # octahedron |x|+|y|+|z| <= r: I = V * 2 r^2 / 10 about every axis
    np.testing.assert_allclose(p.inertia, np.eye(3) * p.volume * r**2 / 5, atol=1e-12)


@pytest.mark.parametrize(("m_", "n"), [(8, 3), (12, 5), (3, 1)])
def test_sphere_structure(m_, n):
    m = workcell.Model()
    solids.sphere(m, "s", radius=1.0, m=m_, n=n)
    assert m.info("s").n_relations == 2 * n * m_
    mine = [s for s in m.list("surface") if s.startswith("s.")]
    assert len(mine) == n  # n distinct surfaces per half slice
    for s in mine:
        assert m.pointed_by(s) == 2 * m_
    # n - 1 quadrilaterals and, at the pole, a triangle (n = 1: the triangle only)
    sides = sorted(len(m.surface(s).main) for s in mine)
    assert sides == [3] + [4] * (n - 1)


@settings(max_examples=20, deadline=None)
@given(r=st.floats(0.05, 10.0), m_=st.integers(3, 24), n=st.integers(1, 10))
def test_sphere_random(r, m_, n):
    m = workcell.Model()
    solids.sphere(m, "s", radius=r, m=m_, n=n)
    mesh = m.world_mesh("s")
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    hull = ConvexHull(_sphere_vertices(r, m_, n))
    p = m.properties("s")
    assert _rel(p.volume, hull.volume) < 1e-11
    assert _rel(p.area, hull.area) < 1e-11
    np.testing.assert_allclose(np.linalg.norm(mesh.vertices, axis=1), r, rtol=1e-12)


@pytest.mark.parametrize("radii", [(1.0, 2.0, 3.0), (0.2, 0.2, 5.0), (3.0, 0.5, 1.0)])
def test_ellipsoid_is_scaled_sphere(radii):
    r, m_, n = 0.8, 10, 4
    a, b, c = radii
    m = workcell.Model()
    solids.sphere(m, "s", radius=r, m=m_, n=n)
    assert solids.ellipsoid(m, "e", radii=radii, m=m_, n=n) == "e"
    check_solid(m, "e")
    p = _check_mass_properties(m, "e")
    ps = m.properties("s")
    assert _rel(p.volume, ps.volume * a * b * c / r**3) < RTOL
    ref = _sphere_vertices(1.0, m_, n) * [a, b, c]
    hull = ConvexHull(ref)
    assert _rel(p.volume, hull.volume) < RTOL
    assert _rel(p.area, hull.area) < RTOL
    v = np.array(m.world_mesh("e").vertices)
    np.testing.assert_allclose(np.sum((v / [a, b, c]) ** 2, axis=1), 1.0, rtol=1e-12)
    # the thesis's way: the sphere attached with unequal scaling in an object
    m.create("object", "eo")
    m.attach("eo", "s", spatial.scaling(a / r, b / r, c / r))
    assert _rel(m.properties("eo").volume, p.volume) < RTOL
    np.testing.assert_allclose(m.properties("eo").inertia, p.inertia, atol=1e-12 * a * b * c)


# ==================================================================== cone and torus


@pytest.mark.parametrize(("r", "h", "n"), [(1.0, 2.0, 16), (0.5, 0.1, 3), (2.0, 3.0, 40)])
def test_cone_exact_pyramid(r, h, n):
    m = workcell.Model()
    assert solids.cone(m, "co", radius=r, height=h, n=n) == "co"
    mesh = check_solid(m, "co")
    p = _check_mass_properties(m, "co")
    base = ngon_area(n, r)
    vol = base * h / 3
    slant = np.sqrt(h**2 + (r * np.cos(np.pi / n)) ** 2)
    area = base + n * r * np.sin(np.pi / n) * slant
    izz = vol * r**2 * (2 + np.cos(2 * np.pi / n)) / 10  # integral of the base J (1-z/h)^4
    assert _rel(p.volume, vol) < 1e-11
    assert _rel(p.area, area) < 1e-11
    np.testing.assert_allclose(p.centroid, [0, 0, h / 4], atol=1e-12 * max(r, h))
    assert _rel(p.inertia[2, 2], izz) < 1e-11
    v = np.array(mesh.vertices)
    assert len(v) == n + 2  # base ring, base centre, apex
    ring = v[(np.abs(v[:, 2]) < 1e-12) & (np.hypot(v[:, 0], v[:, 1]) > 1e-9)]
    assert len(ring) == n
    np.testing.assert_allclose(np.hypot(ring[:, 0], ring[:, 1]), r, rtol=1e-12)
    assert np.isclose(v[:, 2].max(), h, rtol=1e-14)


def _torus_profile(R, rho, n):
    t = 2 * np.pi * np.arange(n) / n
    return np.column_stack([R + rho * np.cos(t), rho * np.sin(t)])


@pytest.mark.parametrize(("R", "rho", "m_", "n"), [(1.0, 0.25, 16, 8), (2.0, 1.5, 5, 3)])
def test_torus_exact_and_vs_trimesh(R, rho, m_, n):
    m = workcell.Model()
    assert solids.torus(m, "t", major_radius=R, minor_radius=rho, m=m_, n=n) == "t"
    mesh = check_solid(m, "t")
    p = _check_mass_properties(m, "t")
    # exact m-step revolve of a polygon: V = m sin(2 pi/m) * (area * centroid radius)
    vol = m_ * np.sin(2 * np.pi / m_) * ngon_area(n, rho) * R
    assert _rel(p.volume, vol) < 1e-11
    prof = _torus_profile(R, rho, n)
    ref = trimesh.creation.revolve(np.vstack([prof, prof[:1]]), sections=m_)
    assert _rel(p.volume, ref.volume) < 1e-9
    assert _rel(p.area, ref.area) < 1e-9
    assert mesh.euler_number == 0  # genus 1
    np.testing.assert_allclose(p.centroid, 0.0, atol=1e-12 * R)
    assert len(mesh.vertices) == m_ * n


@settings(max_examples=15, deadline=None)
@given(
    R=st.floats(0.5, 5.0),
    frac=st.floats(0.05, 0.95),
    m_=st.integers(3, 24),
    n=st.integers(3, 12),
)
def test_torus_random(R, frac, m_, n):
    rho = frac * R
    m = workcell.Model()
    solids.torus(m, "t", major_radius=R, minor_radius=rho, m=m_, n=n)
    mesh = m.world_mesh("t")
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    vol = m_ * np.sin(2 * np.pi / m_) * ngon_area(n, rho) * R
    assert _rel(m.properties("t").volume, vol) < 1e-10


# ==================================================================== all solids


def _build_all(m):
    solids.cube(m, "cube", size=0.7)
    solids.box(m, "box", size=(0.3, 0.8, 1.1))
    solids.cylinder(m, "cyl", radius=0.4, height=1.2, n=11)
    solids.sphere(m, "sph", radius=0.6, m=9, n=4)
    solids.ellipsoid(m, "ell", radii=(0.5, 0.9, 0.3), m=7, n=3)
    solids.cone(m, "cone", radius=0.5, height=0.9, n=13)
    solids.torus(m, "tor", major_radius=1.0, minor_radius=0.3, m=10, n=6)
    return ["cube", "box", "cyl", "sph", "ell", "cone", "tor"]


def test_every_solid_is_valid_and_matches_trimesh_mass_properties():
    m = workcell.Model()
    for name in _build_all(m):
        check_solid(m, name)
        _check_mass_properties(m, name)
        assert m.level_of(name) == "block"


def test_every_solid_placed_by_a_rigid_transform_keeps_its_properties():
    m = workcell.Model()
    T = spatial.euler([0.3, -1.1, 2.0], translation=(4.0, -2.0, 0.5))
    for name in _build_all(m):
        obj = f"{name}_o"
        m.create("object", obj)
        m.attach(obj, name, T)
        p0, p1 = m.properties(name), m.properties(obj)
        assert _rel(p1.volume, p0.volume) < 1e-12
        assert _rel(p1.area, p0.area) < 1e-12
        np.testing.assert_allclose(
            p1.centroid, spatial.transform_points(T, p0.centroid), atol=1e-12
        )
        R = T[:3, :3]
        np.testing.assert_allclose(p1.inertia, R @ p0.inertia @ R.T, atol=1e-12)
        _check_mass_properties(m, obj)


def _front_normal(T):
    """Direction of a placed surface's front (local +z): normals map by the inverse transpose."""
    n = np.linalg.inv(T[:3, :3]).T @ [0.0, 0.0, 1.0]
    return n / np.linalg.norm(n)


def test_every_solid_places_its_surfaces_front_side_out():
    m = workcell.Model()
    for name in _build_all(m):
        mesh = assembled_as_placed(m, name)
        assert mesh.is_watertight, name
        assert mesh.is_winding_consistent, name
        assert mesh.volume > 0, name
        assert _rel(mesh.volume, m.properties(name).volume) < 1e-9, name


@pytest.mark.parametrize("name", ["cube", "box", "cyl", "sph", "ell", "cone"])
def test_convex_solid_faces_point_away_from_centre(name):
    m = workcell.Model()
    _build_all(m)
    centre = m.properties(name).centroid
    for rel in m.relations(name):
        main = m.surface(rel.target).main
        c2 = np.mean(main, axis=0)  # inside a convex face
        c = spatial.transform_points(rel.transform, [c2[0], c2[1], 0.0])
        assert _front_normal(rel.transform) @ (c - centre) > 0, rel.name


def test_torus_faces_point_away_from_the_core_circle():
    R = 1.0
    m = workcell.Model()
    solids.torus(m, "t", major_radius=R, minor_radius=0.3, m=10, n=6)
    for rel in m.relations("t"):
        c2 = np.mean(m.surface(rel.target).main, axis=0)
        c = spatial.transform_points(rel.transform, [c2[0], c2[1], 0.0])
        core = R * np.array([c[0], c[1], 0.0]) / np.hypot(c[0], c[1])
        assert _front_normal(rel.transform) @ (c - core) > 0, rel.name


# ==================================================================== validation


@pytest.mark.parametrize(
    ("shape", "params"),
    [
        ("cube", {"size": -1.0}),
        ("cube", {"size": 0.0}),
        ("cube", {"size": float("nan")}),
        ("cube", {"size": "1"}),
        ("cube", {"size": True}),
        ("box", {"size": (1.0, -2.0, 1.0)}),
        ("box", {"size": (1.0, 2.0)}),
        ("box", {"size": (1.0, float("inf"), 1.0)}),
        ("box", {"size": ("a", 1.0, 1.0)}),
        ("cylinder", {"radius": -0.5, "height": 1.0, "n": 8}),
        ("cylinder", {"radius": 0.5, "height": 0.0, "n": 8}),
        ("cylinder", {"radius": 0.5, "height": 1.0, "n": 2}),
        ("cylinder", {"radius": 0.5, "height": 1.0, "n": 8.5}),
        ("cylinder", {"radius": 0.5, "height": 1.0, "n": True}),
        ("cylinder", {"radius": 0.5, "height": 1.0, "n": "8"}),
        ("sphere", {"radius": -1.0, "m": 8, "n": 4}),
        ("sphere", {"radius": 1.0, "m": 2, "n": 4}),
        ("sphere", {"radius": 1.0, "m": 8, "n": 0}),
        ("sphere", {"radius": 1.0, "m": 8, "n": 2.5}),
        ("ellipsoid", {"radii": (1.0, 0.0, 1.0), "m": 8, "n": 4}),
        ("ellipsoid", {"radii": (1.0, 1.0), "m": 8, "n": 4}),
        ("ellipsoid", {"radii": "abc", "m": 8, "n": 4}),
        ("cone", {"radius": -1.0, "height": 1.0, "n": 8}),
        ("cone", {"radius": 1.0, "height": 1.0, "n": 2}),
        ("cone", {"radius": 1.0, "height": 1.0, "n": 7.5}),
        ("torus", {"major_radius": 1.0, "minor_radius": 1.0, "m": 8, "n": 6}),
        ("torus", {"major_radius": 1.0, "minor_radius": 1.5, "m": 8, "n": 6}),
        ("torus", {"major_radius": -1.0, "minor_radius": 0.5, "m": 8, "n": 6}),
        ("torus", {"major_radius": 1.0, "minor_radius": 0.5, "m": 2, "n": 6}),
        ("torus", {"major_radius": 1.0, "minor_radius": 0.5, "m": 8, "n": 2}),
        ("torus", {"major_radius": 1.0, "minor_radius": 0.5, "m": 8.5, "n": 6}),
    ],
)
def test_bad_parameters_raise_and_change_nothing(shape, params):
    m = workcell.Model()
    solids.cube(m, "existing", size=1.0)
    before = snapshot(m)
    with pytest.raises(GeometryError):
        getattr(solids, shape)(m, "new", **params)
    assert snapshot(m) == before
    assert not m.exists("new")
    # the name is still free: the same call with good parameters works
    solids.cube(m, "new", size=1.0)
    assert m.exists("new")


@pytest.mark.parametrize("shape", ["cube", "cylinder", "sphere", "cone", "torus"])
def test_name_clash_is_refused_and_changes_nothing(shape):
    params = {
        "cube": {"size": 1.0},
        "cylinder": {"radius": 1.0, "height": 1.0, "n": 6},
        "sphere": {"radius": 1.0, "m": 6, "n": 2},
        "cone": {"radius": 1.0, "height": 1.0, "n": 6},
        "torus": {"major_radius": 1.0, "minor_radius": 0.3, "m": 6, "n": 4},
    }[shape]
    m = workcell.Model()
    getattr(solids, shape)(m, "x", **params)
    v0 = m.properties("x").volume
    before = snapshot(m)
    with pytest.raises(ModelError):
        getattr(solids, shape)(m, "x", **params)
    assert snapshot(m) == before
    assert m.properties("x").volume == v0


def test_public_facade_exports():
    for name in ("box", "cone", "cube", "cylinder", "ellipsoid", "sphere", "torus"):
        assert callable(getattr(workcell.solids, name))
    assert set(workcell.solids.__all__) >= {
        "box", "cone", "cube", "cylinder", "sphere", "torus", "extrude", "revolve", "sweep",
        "union", "difference", "intersection",
    }  # fmt: skip
