"""Tests of the boolean (CSG) blocks: union, difference, intersection.

Expected values: exact volumes of axis-aligned box overlaps, the exact n-gon prism, and
the same booleans computed independently with manifold3d's own primitives.
"""

from __future__ import annotations

import contextlib

import manifold3d
import numpy as np
import pytest
from helpers import check_solid, ngon_area
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import workcell
from workcell import solids, spatial
from workcell.errors import GeometryError, ModelError
from workcell.modeller.surface import Surface

RTOL = 1e-12


def _rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


@pytest.fixture
def two_cubes():
    m = workcell.Model()
    solids.cube(m, "a", size=1.0)
    m.copy("a", "b", spatial.translation(0.5, 0.0, 0.0))
    return m


# ==================================================================== boxes, exact


@pytest.mark.parametrize(
    ("op", "volume", "x_range"),
    [
        ("union", 1.5, (0.0, 1.5)),
        ("intersection", 0.5, (0.5, 1.0)),
        ("difference", 0.5, (0.0, 0.5)),
    ],
)
def test_two_offset_boxes(two_cubes, op, volume, x_range):
    m = two_cubes
    assert getattr(solids, op)(m, "r", "a", "b") == "r"
    mesh = check_solid(m, "r")
    p = m.properties("r")
    assert _rel(p.volume, volume) < RTOL
    x0, x1 = x_range
    w = x1 - x0
    # every result is the box [x0, x1] x [0, 1] x [0, 1]
    assert _rel(p.area, 2 * (w + w + 1)) < RTOL
    np.testing.assert_allclose(p.centroid, [(x0 + x1) / 2, 0.5, 0.5], atol=1e-12)
    np.testing.assert_allclose(p.inertia, w / 12 * np.diag([2.0, w * w + 1, w * w + 1]), atol=1e-12)
    np.testing.assert_allclose(mesh.bounds, [[x0, 0, 0], [x1, 1, 1]], atol=1e-12)
    assert mesh.euler_number == 2
    assert m.info("r").boolean == op


@pytest.mark.parametrize(
    ("op", "volume"), [("union", 1.5), ("intersection", 0.5), ("difference", 0.5)]
)
def test_operand_transforms_are_applied(op, volume):
    m = workcell.Model()
    solids.cube(m, "a", size=1.0)
    getattr(solids, op)(m, "r", "a", "a", transforms=[None, spatial.translation(0.5, 0, 0)])
    check_solid(m, "r")
    assert _rel(m.properties("r").volume, volume) < RTOL
    assert m.pointed_by("a") == 2


def test_non_rigid_and_reflected_operand_transforms():
    m = workcell.Model()
    solids.cube(m, "a", size=1.0)
    # a cube stretched 2x along x, unioned with its mirror image in x = 0: [-2, 2] x [0,1]^2
    S = spatial.scaling(2.0, 1.0, 1.0)
    solids.union(m, "u", "a", "a", transforms=[S, spatial.scaling(-1.0, 1.0, 1.0) @ S])
    mesh = check_solid(m, "u")
    assert _rel(m.properties("u").volume, 4.0) < RTOL
    np.testing.assert_allclose(mesh.bounds, [[-2, 0, 0], [2, 1, 1]], atol=1e-12)
    # the mirror alone minus a rotated copy: [-1, 0] x [0, 1]^2 minus the same turned 90 deg
    # about z, i.e. [-1, 0] x [-1, 0] x [0,1]: they only touch, nothing is removed
    solids.difference(
        m, "d", "a", "a", transforms=[spatial.scaling(-1.0, 1.0, 1.0), spatial.rot_z(np.pi)]
    )
    check_solid(m, "d")
    assert _rel(m.properties("d").volume, 1.0) < 1e-12


@settings(max_examples=25, deadline=None)
@given(
    size_a=st.tuples(*[st.floats(0.2, 3.0)] * 3),
    size_b=st.tuples(*[st.floats(0.2, 3.0)] * 3),
    offset=st.tuples(*[st.floats(-2.0, 2.0)] * 3),
)
def test_random_box_pairs(size_a, size_b, offset):
    a, b, t = np.array(size_a), np.array(size_b), np.array(offset)
    gap = np.minimum(a, t + b) - np.maximum(0.0, t)  # per-axis overlap (negative: apart)
    assume(np.all(np.abs(gap) > 1e-3))  # touching boxes have no robust result to compare
    overlap = np.clip(gap, 0.0, None)
    inter = float(np.prod(overlap))
    va, vb = float(np.prod(a)), float(np.prod(b))
    m = workcell.Model()
    solids.box(m, "A", size=a)
    solids.box(m, "B", size=b)
    T = [None, spatial.translation(*t)]
    solids.union(m, "u", "A", "B", transforms=T)
    tol = 1e-12 * (va + vb)
    assert abs(m.properties("u").volume - (va + vb - inter)) < tol
    if va - inter < 1e-9:  # A inside B: empty (refused), or a sliver where faces nearly meet
        with contextlib.suppress(GeometryError):
            solids.difference(m, "d", "A", "B", transforms=T)
    else:
        solids.difference(m, "d", "A", "B", transforms=T)
    names = ("u", "d") if m.exists("d") else ("u",)
    if m.exists("d"):
        assert abs(m.properties("d").volume - (va - inter)) < tol
    for name in names:
        mesh = m.world_mesh(name)
        if name == "d" and va - inter < 1e-9:
            continue  # A (all but a sliver, if faces nearly coincide) inside B: volume only
        assert mesh.is_watertight
        assert mesh.is_winding_consistent
    if inter > 0:
        solids.intersection(m, "i", "A", "B", transforms=T)
        assert abs(m.properties("i").volume - inter) < tol
        assert m.world_mesh("i").is_watertight


def test_empty_booleans_are_refused_where_they_are_created():
    m = workcell.Model()
    solids.cube(m, "a", size=1.0)
    before = m.to_dict()
    with pytest.raises(GeometryError, match="'i' is empty: the intersection of a, a"):
        solids.intersection(m, "i", "a", "a", transforms=[None, spatial.translation(3, 0, 0)])
    with pytest.raises(GeometryError, match="'d' is empty: the difference"):
        solids.difference(m, "d", "a", "a")  # two equal blocks
    assert m.to_dict() == before  # nothing left behind


# ==================================================================== box minus cylinder


def _manifold_box_minus_cylinder(size, r, h, n, at):
    box = manifold3d.Manifold.cube(list(size))
    cyl = manifold3d.Manifold.cylinder(h, r, r, n).translate(list(at))
    return (box - cyl).volume()


@pytest.mark.parametrize("n", [6, 16, 33])
def test_box_minus_cylinder_through_hole(n):
    r = 0.5
    m = workcell.Model()
    solids.box(m, "b", size=(2.0, 2.0, 1.0))
    solids.cylinder(m, "c", radius=r, height=3.0, n=n)
    solids.difference(m, "d", "b", "c", transforms=[None, spatial.translation(1.0, 1.0, -1.0)])
    mesh = check_solid(m, "d")
    exact = 4.0 - ngon_area(n, r) * 1.0
    p = m.properties("d")
    assert _rel(p.volume, exact) < RTOL
    assert _rel(p.volume, _manifold_box_minus_cylinder((2, 2, 1), r, 3.0, n, (1, 1, -1))) < 1e-12
    # area: the box minus two n-gons, plus the n side rectangles of the hole
    area = 2 * (4 + 2 + 2) - 2 * ngon_area(n, r) + n * 2 * r * np.sin(np.pi / n) * 1.0
    assert _rel(p.area, area) < 1e-12
    assert mesh.euler_number == 0  # a through hole: genus 1
    np.testing.assert_allclose(p.centroid, [1.0, 1.0, 0.5], atol=1e-12)


def test_box_minus_blind_hole():
    r, n, depth = 0.4, 12, 0.3
    m = workcell.Model()
    solids.box(m, "b", size=(2.0, 2.0, 1.0))
    solids.cylinder(m, "c", radius=r, height=1.0, n=n)
    solids.difference(
        m, "d", "b", "c", transforms=[None, spatial.translation(1.0, 1.0, 1.0 - depth)]
    )
    mesh = check_solid(m, "d")
    assert mesh.euler_number == 2
    assert _rel(m.properties("d").volume, 4.0 - ngon_area(n, r) * depth) < RTOL


def test_three_operands():
    r, n = 0.3, 10
    m = workcell.Model()
    solids.box(m, "b", size=(3.0, 1.0, 1.0))
    solids.cylinder(m, "c", radius=r, height=2.0, n=n)
    T = [None, spatial.translation(0.75, 0.5, -0.5), spatial.translation(2.25, 0.5, -0.5)]
    solids.difference(m, "d", "b", "c", "c", transforms=T)
    mesh = check_solid(m, "d")
    assert mesh.euler_number == -2  # two through holes
    assert _rel(m.properties("d").volume, 3.0 - 2 * ngon_area(n, r)) < RTOL
    solids.cube(m, "q", size=1.0)
    Tq = [None, spatial.translation(1, 0, 0), spatial.translation(2, 0, 0)]
    solids.union(m, "u", "q", "q", "q", transforms=Tq)
    check_solid(m, "u")
    assert _rel(m.properties("u").volume, 3.0) < RTOL
    Ti = [None, spatial.translation(0.5, 0, 0), spatial.translation(0.25, 0.5, 0)]
    solids.intersection(m, "i", "q", "q", "q", transforms=Ti)
    assert _rel(m.properties("i").volume, 0.5 * 0.5 * 1.0) < RTOL


def test_far_from_origin_matches_origin():
    r, n = 0.5, 24
    m = workcell.Model()
    solids.box(m, "b", size=(2.0, 2.0, 1.0))
    solids.cylinder(m, "c", radius=r, height=3.0, n=n)
    for name, x in (("near", 0.0), ("far", 1000.0)):
        solids.difference(
            m,
            name,
            "b",
            "c",
            transforms=[spatial.translation(x, 0, 0), spatial.translation(x + 1.0, 1.0, -1.0)],
        )
        check_solid(m, name)
    near, far = m.properties("near"), m.properties("far")
    exact = 4.0 - ngon_area(n, r)
    assert _rel(near.volume, exact) < 1e-12
    assert _rel(far.volume, near.volume) < 1e-9
    assert _rel(far.area, near.area) < 1e-9
    np.testing.assert_allclose(far.centroid - [1000.0, 0, 0], near.centroid, atol=1e-9)
    np.testing.assert_allclose(far.inertia, near.inertia, atol=1e-9 * np.abs(near.inertia).max())


def test_boolean_of_boolean():
    m = workcell.Model()
    solids.cube(m, "a", size=1.0)
    solids.union(m, "u", "a", "a", transforms=[None, spatial.translation(1, 0, 0)])  # 2 x 1 x 1
    solids.difference(m, "d", "u", "a", transforms=[None, spatial.translation(0.5, 0.5, 0.5)])
    check_solid(m, "d")
    assert _rel(m.properties("d").volume, 2.0 - 0.5 * 0.5 * 0.5 * 2) < RTOL
    m.set_transform("u", "op2", spatial.translation(0.5, 0, 0))  # inner union now 1.5 long
    # removed part: [0.5, 1.5] x [0.5, 1] x [0.5, 1] within [0, 1.5] x [0, 1]^2
    assert _rel(m.properties("d").volume, 1.5 - 1.0 * 0.25) < RTOL


# ==================================================================== datamodel behaviour


def test_boolean_keeps_its_operands_alive(two_cubes):
    m = two_cubes
    solids.union(m, "u", "a", "b")
    assert m.pointed_by("a") == 1
    assert m.pointed_by("b") == 1
    for operand in ("a", "b"):
        with pytest.raises(ModelError):
            m.remove(operand)
    assert m.exists("a")
    assert m.exists("b")
    with pytest.raises(ModelError):  # a boolean keeps at least two operands
        m.detach("u", "op1")
    assert _rel(m.properties("u").volume, 1.5) < RTOL
    m.remove("u")
    assert m.pointed_by("a") == 0
    m.remove("b")
    assert not m.exists("b")


def test_set_transform_on_boolean_relation_invalidates(two_cubes):
    m = two_cubes
    solids.union(m, "u", "a", "b")
    mesh0 = m.world_mesh("u")
    assert _rel(m.properties("u").volume, 1.5) < RTOL
    m.set_transform("u", "op2", spatial.translation(-0.75, 0.0, 0.0))  # b now at x = -0.25
    assert m.world_mesh("u") is not mesh0
    assert _rel(m.properties("u").volume, 1.25) < RTOL
    np.testing.assert_allclose(m.world_mesh("u").bounds, [[-0.25, 0, 0], [1, 1, 1]], atol=1e-12)


def test_modified_operand_invalidates_boolean(two_cubes):
    m = two_cubes
    solids.intersection(m, "i", "a", "b")
    solids.cube(m, "other", size=1.0)
    other_mesh = m.world_mesh("other")
    assert _rel(m.properties("i").volume, 0.5) < RTOL
    mesh0 = m.world_mesh("i")
    # stretch operand b to 3 units along y by rewriting each of its face relations
    S = spatial.scaling(1.0, 3.0, 1.0)
    for rel in m.relations("b"):
        m.set_transform("b", rel.name, S @ rel.transform)
    assert m.world_mesh("i") is not mesh0
    assert _rel(m.properties("b").volume, 3.0) < RTOL
    # b = [0.5, 1.5] x [0, 3] x [0, 1]: the intersection with a is still [0.5, 1] x [0,1]^2
    assert _rel(m.properties("i").volume, 0.5) < RTOL
    solids.union(m, "u", "a", "b")
    assert _rel(m.properties("u").volume, 1.0 + 3.0 - 0.5) < RTOL
    # move b by changing its relations again: the union follows
    for rel in m.relations("b"):
        m.set_transform("b", rel.name, spatial.translation(2.0, 0, 0) @ rel.transform)
    assert _rel(m.properties("u").volume, 1.0 + 3.0) < RTOL
    assert m.properties("i").volume == pytest.approx(0.0, abs=1e-12)
    assert m.world_mesh("other") is other_mesh  # an unrelated block keeps its cache


def test_set_surface_on_operand_surface_invalidates(two_cubes):
    m = two_cubes
    solids.difference(m, "d", "a", "b")
    assert _rel(m.properties("d").volume, 0.5) < RTOL
    square = m.surface("a.square")
    # a square with a hole makes both operands open boxes: the boolean must now refuse
    holed = Surface(square.main, [[(0.4, 0.4), (0.6, 0.4), (0.6, 0.6), (0.4, 0.6)]])
    m.set_surface("a.square", holed)
    with pytest.raises(GeometryError):
        m.world_mesh("d")
    # put the square back (as a new, equal Surface): the boolean is valid again
    m.set_surface("a.square", Surface([(0, 0), (1, 0), (1, 1), (0, 1)]))
    check_solid(m, "d")
    assert _rel(m.properties("d").volume, 0.5) < RTOL


def test_open_operand_is_refused_with_geometry_error():
    m = workcell.Model()
    solids.cube(m, "a", size=1.0)
    m.create("surface", "sq", Surface.rectangle(1.0, 1.0))
    m.create("block", "plate")
    m.attach("plate", "sq")
    before = m.to_dict()
    with pytest.raises(GeometryError, match="operand 2"):  # evaluated when created
        solids.union(m, "u", "a", "plate")
    assert m.to_dict() == before
    m.create_boolean("u", "union", ["a", "plate"])  # the datamodel itself is lazy
    with pytest.raises(GeometryError, match="operand 2"):
        m.world_mesh("u")


@pytest.mark.parametrize(
    ("call", "error"),
    [
        (lambda m: solids.union(m, "u", "a"), ModelError),  # one operand
        (lambda m: solids.union(m, "u", "a", "obj"), ModelError),  # an object
        (lambda m: solids.union(m, "u", "a", "nope"), ModelError),
        (lambda m: solids.union(m, "a", "a", "a"), ModelError),  # name taken
        (lambda m: solids.union(m, "u", "a", "a", transforms=[None]), ModelError),
        (
            lambda m: solids.union(m, "u", "a", "a", transforms=[None, np.zeros((4, 4))]),
            GeometryError,
        ),
    ],
)
def test_bad_boolean_requests_change_nothing(call, error):
    m = workcell.Model()
    solids.cube(m, "a", size=1.0)
    m.create("object", "obj")
    m.attach("obj", "a")
    before = m.list()
    pb = m.pointed_by("a")
    with pytest.raises(error):
        call(m)
    assert m.list() == before
    assert m.pointed_by("a") == pb
