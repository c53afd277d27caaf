"""Tests of workcell.modeller.surface: planar polygons with holes (thesis §2, the 2-D level).

Independent values: analytic areas, and shapely (GEOS) for areas, orientation and validity.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from shapely.geometry import LinearRing, Polygon

from workcell.errors import GeometryError, WorkcellError
from workcell.modeller.contours import strictly_convex
from workcell.modeller.surface import Surface

UNIT_SQUARE = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
BOWTIE = [(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)]


def _square(x0, y0, side):
    return [(x0, y0), (x0 + side, y0), (x0 + side, y0 + side), (x0, y0 + side)]


def _ngon_area(n, r):
    return 0.5 * n * r * r * math.sin(2 * math.pi / n)


def _shapely_polygon(s: Surface) -> Polygon:
    return Polygon(s.main, [h for h in s.holes])


def _tri_areas(s: Surface):
    V, F = s.triangulate()
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return 0.5 * (
        (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    )


def _edge_counts(F):
    counts: dict[tuple[int, int], int] = {}
    for f in F.tolist():
        for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
            key = (min(a, b), max(a, b))
            counts[key] = counts.get(key, 0) + 1
    return counts


def _assert_conforming(s: Surface):
    """Every contour edge is an edge of exactly one triangle, every other edge of two."""
    V, F = s.triangulate()
    index = {tuple(v): i for i, v in enumerate(V.tolist())}
    starts, ends = s.edges()
    contour = {
        tuple(sorted((index[tuple(a)], index[tuple(b)])))
        for a, b in zip(starts.tolist(), ends.tolist(), strict=True)
    }
    counts = _edge_counts(F)
    assert {e for e, k in counts.items() if k == 1} == contour
    assert all(k in (1, 2) for k in counts.values())
    assert len(F) == s.n_edges + 2 * len(s.holes) - 2  # Euler, every vertex used


def _assert_triangulation_exact(s: Surface, rel=1e-9):
    """Triangles are CCW, their areas sum to the area, and their union is the polygon."""
    _assert_conforming(s)
    V, F = s.triangulate()
    areas = _tri_areas(s)
    assert (areas > 0).all(), "every triangle must be counter-clockwise seen from +z"
    poly = _shapely_polygon(s)
    assert areas.sum() == pytest.approx(poly.area, rel=rel, abs=1e-15)
    union = shapely.union_all([Polygon(V[f]) for f in F])
    assert poly.symmetric_difference(union).area <= rel * max(poly.area, 1e-12)


# ============================================================== constructors and areas
class TestConstructors:
    @pytest.mark.parametrize(("w", "h"), [(1.0, 1.0), (2.0, 0.5), (1e-3, 7.0), (123.0, 0.25)])
    def test_rectangle_area_and_corners(self, w, h):
        s = Surface.rectangle(w, h)
        assert s.area == pytest.approx(w * h, rel=1e-12)
        assert np.allclose(s.main.min(axis=0), [0, 0])
        assert np.allclose(s.main.max(axis=0), [w, h])
        c = Surface.rectangle(w, h, center=True)
        assert c.area == pytest.approx(w * h, rel=1e-12)
        assert np.allclose(c.main.min(axis=0), [-w / 2, -h / 2])
        assert np.allclose(c.main.max(axis=0), [w / 2, h / 2])

    @pytest.mark.parametrize("n", [3, 4, 5, 6, 7, 12, 100])
    @pytest.mark.parametrize("r", [0.1, 1.0, 3.5])
    def test_regular_polygon_area_is_analytic(self, n, r):
        s = Surface.regular_polygon(n, r)
        assert len(s.main) == n
        assert s.area == pytest.approx(_ngon_area(n, r), rel=1e-12)
        assert np.allclose(np.hypot(*s.main.T), r, rtol=1e-14)

    def test_regular_polygon_centre_and_phase(self):
        s = Surface.regular_polygon(4, 2.0, center=(5.0, -1.0), phase=math.pi / 4)
        assert s.area == pytest.approx(8.0, rel=1e-12)  # square of diagonal 4
        assert np.allclose(s.main[0], [5 + math.sqrt(2), -1 + math.sqrt(2)])
        assert np.allclose(np.hypot(s.main[:, 0] - 5, s.main[:, 1] + 1), 2.0)

    @pytest.mark.parametrize("n", [8, 32, 360])
    def test_circle_is_inscribed_ngon(self, n):
        s = Surface.circle(0.5, n, center=(1.0, 2.0))
        assert s.area == pytest.approx(_ngon_area(n, 0.5), rel=1e-12)
        assert s.area < math.pi * 0.25
        assert np.allclose(np.hypot(s.main[:, 0] - 1, s.main[:, 1] - 2), 0.5)

    def test_circle_converges_to_pi_r2(self):
        assert Surface.circle(2.0, 4096).area == pytest.approx(4 * math.pi, rel=1e-5)

    def test_from_points_with_holes_subtracts_area(self):
        outer = _square(0, 0, 4)
        holes = [_square(0.5, 0.5, 1), _square(2, 2, 1.5)]
        s = Surface.from_points(outer, holes)
        assert s.area == pytest.approx(16 - 1 - 2.25, rel=1e-12)
        assert s.area == pytest.approx(_shapely_polygon(s).area, rel=1e-12)
        assert len(s.holes) == 2
        assert s.n_edges == 12
        assert s.perimeter == pytest.approx(16 + 4 + 6, rel=1e-12)

    def test_ngon_hole_in_ngon(self):
        s = Surface(Surface.regular_polygon(6, 2.0).main, [Surface.circle(1.0, 24).main])
        assert s.area == pytest.approx(_ngon_area(6, 2.0) - _ngon_area(24, 1.0), rel=1e-12)

    @pytest.mark.parametrize(
        ("n", "r"), [(2, 1.0), (0, 1.0), (3.5, 1.0), (5, 0.0), (5, -1.0), (5, math.nan)]
    )
    def test_bad_polygon_parameters(self, n, r):
        with pytest.raises(GeometryError, match="'p'"):
            Surface.regular_polygon(n, r, name="p")

    def test_contours_are_read_only(self):
        s = Surface(UNIT_SQUARE, [_square(0.25, 0.25, 0.5)])
        with pytest.raises(ValueError, match="read-only"):
            s.main[0, 0] = 5.0
        with pytest.raises(ValueError, match="read-only"):
            s.holes[0][0, 0] = 5.0

    def test_input_array_is_not_aliased(self):
        pts = np.array(UNIT_SQUARE)
        s = Surface(pts)
        pts[0] = (-10, -10)
        assert s.area == pytest.approx(1.0)


# ============================================================== normalisation
class TestNormalisation:
    @pytest.mark.parametrize("main_ccw", [True, False])
    @pytest.mark.parametrize("hole_ccw", [True, False])
    def test_main_ccw_holes_cw_whatever_the_input(self, main_ccw, hole_ccw):
        outer = _square(0, 0, 3)
        hole = _square(1, 1, 1)
        if not main_ccw:
            outer = outer[::-1]
        if not hole_ccw:
            hole = hole[::-1]
        s = Surface(outer, [hole])
        assert LinearRing(s.main).is_ccw
        assert not LinearRing(s.holes[0]).is_ccw
        assert s.area == pytest.approx(8.0, rel=1e-12)
        starts, ends = s.edges()
        # material to the left of every edge: the midpoint nudged left lies in the polygon
        poly = _shapely_polygon(s)
        d = ends - starts
        left = np.column_stack([-d[:, 1], d[:, 0]]) / np.linalg.norm(d, axis=1)[:, None]
        probes = 0.5 * (starts + ends) + 1e-6 * left
        assert shapely.contains_xy(poly, probes[:, 0], probes[:, 1]).all()

    def test_closing_point_dropped(self):
        s = Surface([*UNIT_SQUARE, UNIT_SQUARE[0]])
        assert len(s.main) == 4
        assert s.area == pytest.approx(1.0)

    def test_repeated_points_dropped(self):
        pts = [(0, 0), (0, 0), (1, 0), (1, 0), (1, 0), (1, 1), (0, 1), (0, 1)]
        s = Surface(pts)
        assert s.main.tolist() == [[0, 0], [1, 0], [1, 1], [0, 1]]

    @pytest.mark.parametrize(
        "pts",
        [
            [(0, 0), (1, 0), (1, 1), (0, 1), (0, 0), (0, 0)],  # closing point given twice
            [(0, 0), (1, 0), (1, 1), (0, 1), (0, 1), (0, 0)],  # repeat, then the closing point
            [(0, 0), (0, 0), (1, 0), (1, 1), (0, 1), (0, 0)],  # repeat at the start, closed
        ],
    )
    def test_repeated_and_closing_points_together(self, pts):
        s = Surface(pts)
        assert s.main.tolist() == [[0, 0], [1, 0], [1, 1], [0, 1]]

    def test_hole_closing_point_dropped(self):
        h = _square(1, 1, 1)
        s = Surface(_square(0, 0, 3), [[*h, h[0], h[0]]])
        assert len(s.holes[0]) == 4

    def test_triangle_from_closed_four_points(self):
        s = Surface([(0, 0), (2, 0), (0, 2), (0, 0)])
        assert len(s.main) == 3
        assert s.area == pytest.approx(2.0)


# ============================================================== triangulation
class TestTriangulation:
    @pytest.mark.parametrize(
        "surface",
        [
            Surface(UNIT_SQUARE),
            Surface(UNIT_SQUARE[::-1]),
            Surface.regular_polygon(7, 1.3),
            Surface.circle(2.0, 64),
            Surface(_square(0, 0, 4), [_square(0.5, 0.5, 1), _square(2, 2, 1.5)]),
            Surface([(0, 0), (4, 0), (4, 1), (1, 1), (1, 3), (4, 3), (4, 4), (0, 4)]),  # C shape
            Surface([(0, 0), (1, 0), (2, 0), (3, 0), (3, 2), (0, 2)]),  # collinear vertices
            Surface(_square(0, 0, 5), [_square(1, 1, 1), _square(3, 1, 1)]),  # aligned holes
            Surface(
                [(0, 0), (6, 0), (6, 6), (0, 6)],
                [_square(1, 1, 1)[::-1], _square(3, 1, 1), _square(1, 3, 1), _square(3, 3, 2)],
            ),
        ],
        ids=[
            "square",
            "square-cw",
            "heptagon",
            "circle",
            "two-holes",
            "c-shape",
            "collinear",
            "aligned-holes",
            "four-holes",
        ],
    )
    def test_covers_exactly_the_area(self, surface):
        _assert_triangulation_exact(surface)
        assert surface.area == pytest.approx(_shapely_polygon(surface).area, rel=1e-12)

    def test_triangulation_is_cached_and_read_only(self):
        s = Surface.regular_polygon(9, 1.0)
        V1, F1 = s.triangulate()
        V2, F2 = s.triangulate()
        assert V1 is V2
        assert F1 is F2
        with pytest.raises(ValueError, match="read-only"):
            F1[0, 0] = 0


# ============================================================== refusals
class TestRefusals:
    @pytest.mark.parametrize(
        ("main", "holes", "needles"),
        [
            ([(0, 0), (1, 0)], [], ["main contour", "at least 3"]),
            ([(0, 0), (1, 0), (1, 0), (0, 0)], [], ["main contour", "at least 3"]),
            ([], [], ["main contour"]),
            ([(0, 0), (1, 1), (2, 2)], [], ["main contour", "zero area"]),
            ([(0, 0), (1, 0), (2, 0), (3, 0)], [], ["main contour", "zero area"]),
            (BOWTIE, [], ["main contour", "not simple"]),
            ([(0, 0), (2, 0), (2, 2), (1, -1), (0, 2)], [], ["main contour", "not simple"]),
            ([(0, 0), (2, 0), (2, 2), (1, 0), (0, 2)], [], ["main contour", "not simple"]),
            (_square(0, 0, 4), [_square(5, 5, 1)], ["hole 0", "outside"]),
            (_square(0, 0, 4), [_square(3, 1, 2)], ["hole 0", "crosses"]),
            (_square(0, 0, 4), [_square(0, 1, 1)], ["hole 0", "touches"]),
            (_square(0, 0, 4), [[(0, 0), (1, 2), (2, 1)]], ["hole 0", "touches"]),
            (_square(0, 0, 4), [_square(-1, -1, 6)], ["hole 0"]),
            (
                _square(0, 0, 4),
                [_square(1, 1, 1), _square(1.5, 1.5, 1)],
                ["holes 0 and 1", "overlap"],
            ),
            (_square(0, 0, 4), [_square(1, 1, 1), _square(2, 1, 1)], ["holes 0 and 1", "touch"]),
            (_square(0, 0, 4), [_square(1, 1, 1), _square(2, 2, 1)], ["holes 0 and 1", "touch"]),
            (_square(0, 0, 9), [_square(1, 1, 6), _square(2, 2, 1)], ["holes 0 and 1"]),
            (_square(0, 0, 4), [_square(1, 1, 1), BOWTIE], ["hole 1", "not simple"]),
            (_square(0, 0, 4), [[(1, 1), (2, 2)]], ["hole 0", "at least 3"]),
            (_square(0, 0, 4), [[(1, 1), (2, 2), (3, 3)]], ["hole 0", "zero area"]),
            ([(0, 0), (1, 0), (math.nan, 1)], [], ["main contour", "non-finite"]),
            ([(0, 0), (math.inf, 0), (1, 1)], [], ["main contour", "non-finite"]),
            (_square(0, 0, 4), [[(1, 1), (2, 1), (1, -math.inf)]], ["hole 0", "non-finite"]),
            ([(0, 0, 0), (1, 0, 0), (1, 1, 0)], [], ["main contour", "shape"]),
            ([0, 1, 2, 3], [], ["main contour", "shape"]),
            ([[(0, 0), (1, 0), (1, 1)]], [], ["main contour", "shape"]),
            ([(0, 0), (1, 0, 2), (1, 1)], [], ["main contour"]),
            ([("a", "b"), (1, 0), (1, 1)], [], ["main contour"]),
            (_square(0, 0, 4), [(1, 1)], ["hole 0", "shape"]),
        ],
    )
    def test_invalid_input_names_contour_and_reason(self, main, holes, needles):
        with pytest.raises(GeometryError) as info:
            Surface(main, holes, name="plate")
        msg = str(info.value)
        assert "'plate'" in msg
        for needle in needles:
            assert needle in msg, f"{needle!r} not in {msg!r}"

    def test_huge_integer_coordinate_is_a_geometry_error(self):
        with pytest.raises(GeometryError, match="main contour"):
            Surface([(0, 0), (10**400, 0), (1, 1)])

    def test_errors_are_workcell_errors(self):
        assert issubclass(GeometryError, WorkcellError)

    def test_pentagram_is_refused(self):
        # all five turns have the same sign, but the contour winds twice
        ang = math.pi / 2 + 2 * math.pi * np.arange(5) / 5
        star = np.column_stack([np.cos(ang), np.sin(ang)])[[0, 2, 4, 1, 3]]
        e = np.roll(star, -1, axis=0) - star
        turns = e[:, 0] * np.roll(e[:, 1], -1) - e[:, 1] * np.roll(e[:, 0], -1)
        assert (turns > 0).all() or (turns < 0).all()  # the fast path cannot use the turn signs
        assert not LinearRing(star).is_simple
        assert not strictly_convex(star)
        with pytest.raises(GeometryError, match="not simple"):
            Surface(star)
        with pytest.raises(GeometryError, match="hole 0"):
            Surface(_square(-3, -3, 6), [star])

    @pytest.mark.parametrize("k", [7, 9])
    def test_heptagram_winding_twice_and_three_times_refused(self, k):
        for step in range(2, (k - 1) // 2 + 1):
            ang = 2 * math.pi * step * np.arange(k) / k
            star = np.column_stack([np.cos(ang), np.sin(ang)])
            assert not strictly_convex(star)
            with pytest.raises(GeometryError, match="not simple"):
                Surface(star)


# ============================================================== transforms and io
class TestTransformed:
    @given(
        a=st.floats(-3, 3),
        b=st.floats(-3, 3),
        c=st.floats(-3, 3),
        d=st.floats(-3, 3),
        tx=st.floats(-10, 10),
        ty=st.floats(-10, 10),
        as3=st.booleans(),
    )
    @settings(max_examples=60, deadline=None)
    def test_area_scales_by_abs_det(self, a, b, c, d, tx, ty, as3):
        det = a * d - b * c
        assume(abs(det) > 1e-2)
        s = Surface(
            _square(0, 0, 4), [_square(1, 1, 1), Surface.circle(0.5, 9, center=(3, 3)).main]
        )
        M = [[a, b, tx], [c, d, ty]] + ([[0, 0, 1]] if as3 else [])
        t = s.transformed(M, name="moved")
        assert t.name == "moved"
        assert t.area == pytest.approx(abs(det) * s.area, rel=1e-9)
        assert t.area == pytest.approx(_shapely_polygon(t).area, rel=1e-9)
        assert LinearRing(t.main).is_ccw
        assert not any(LinearRing(h).is_ccw for h in t.holes)
        # the first main point maps to A p + t, or (after a reflection) is still a main point
        mapped = s.main @ np.array([[a, b], [c, d]]).T + [tx, ty]
        assert {tuple(np.round(p, 9)) for p in mapped} == {tuple(np.round(p, 9)) for p in t.main}

    def test_rotation_keeps_area(self):
        th = 0.3
        R = [[math.cos(th), -math.sin(th), 1.0], [math.sin(th), math.cos(th), 2.0]]
        s = Surface.regular_polygon(5, 1.0).transformed(R)
        assert s.area == pytest.approx(_ngon_area(5, 1.0), rel=1e-12)

    @pytest.mark.parametrize(
        "M",
        [
            [[1, 0], [0, 1]],
            [[1, 0, 0, 0], [0, 1, 0, 0]],
            np.eye(4),
            [[1, 2, 0], [2, 4, 0]],
            [[0, 0, 0], [0, 0, 0]],
            [[1, 0, 0], [0, 1, 0], [1, 1, 1]],  # projective: last row must be 0 0 1
            [[1, 0, 0], [0, 1, 0], [0, 0, 2]],
        ],
    )
    def test_bad_maps_refused(self, M):
        with pytest.raises(GeometryError):
            Surface(UNIT_SQUARE).transformed(M)


def test_dict_round_trip_is_exact():
    s = Surface([(0.1, 0.2), (1 / 3, 0.0), (1.0, 1e-300 + 1.0), (0.0, 0.7)], [])
    s2 = Surface.from_dict(s.to_dict(), name="again")
    assert s2.same_geometry(s)
    h = Surface(_square(0, 0, 3), [_square(1, 1, 1)])
    assert Surface.from_dict(h.to_dict()).same_geometry(h)
    assert not h.same_geometry(s)
    with pytest.raises(GeometryError, match="'main'"):
        Surface.from_dict({"holes": []})
    with pytest.raises(GeometryError, match="not simple"):
        Surface.from_dict({"main": BOWTIE, "holes": []})


# ============================================================== properties (hypothesis)
@st.composite
def star_polygons(draw, max_points=14):
    """Star-shaped about the origin: strictly increasing angles, positive radii."""
    n = draw(st.integers(3, max_points))
    gaps = np.array(draw(st.lists(st.floats(0.05, 1.0), min_size=n, max_size=n)))
    ang = np.cumsum(gaps) / gaps.sum() * 2 * math.pi
    assume(np.max(np.diff(np.r_[ang, ang[0] + 2 * math.pi])) < math.pi * 0.95)
    r = np.array(draw(st.lists(st.floats(0.2, 3.0), min_size=n, max_size=n)))
    pts = np.column_stack([r * np.cos(ang), r * np.sin(ang)])
    if draw(st.booleans()):
        pts = pts[::-1]
    return pts


@given(star_polygons(), st.floats(-5, 5), st.floats(-5, 5))
@settings(max_examples=80, deadline=None)
def test_star_polygons_accepted_and_area_matches_shapely(pts, dx, dy):
    pts = pts + np.array([dx, dy])
    poly = Polygon(pts)
    assume(poly.is_valid)  # guards against rounding-level degeneracy only
    s = Surface(pts)
    assert s.area == pytest.approx(poly.area, rel=1e-9)
    assert LinearRing(s.main).is_ccw
    _assert_triangulation_exact(s)


@given(star_polygons(max_points=10), st.floats(0.1, 0.45))
@settings(max_examples=40, deadline=None)
def test_star_with_scaled_hole(pts, k):
    # a copy scaled about the star centre by k < 1/2... is inside when the star is
    # star-shaped about the origin and the hole is k times every radius
    hole = pts * k
    s = Surface(pts, [hole])
    assert s.area == pytest.approx((1 - k * k) * Polygon(pts).area, rel=1e-9)
    assert s.area == pytest.approx(_shapely_polygon(s).area, rel=1e-9)
    _assert_triangulation_exact(s)


def _shapely_says_valid(pts) -> bool:
    p = np.asarray(pts, dtype=float)
    try:
        poly = Polygon(p)
    except (ValueError, shapely.errors.GEOSException):
        return False
    return poly.is_valid and poly.area > 0


@given(st.lists(st.tuples(st.integers(0, 3), st.integers(0, 3)), min_size=3, max_size=8))
@settings(max_examples=300, deadline=None)
def test_grid_polygons_refused_iff_shapely_invalid(pts):
    """Integer points on a 4x4 grid give every degenerate case: spikes, touches, collinear."""
    valid = _shapely_says_valid(pts)
    if valid:
        s = Surface(pts)
        assert s.area == pytest.approx(Polygon(pts).area, rel=1e-12)
        _assert_triangulation_exact(s)
    else:
        with pytest.raises(GeometryError, match="main contour"):
            Surface(pts)


@given(st.lists(st.tuples(st.integers(1, 4), st.integers(1, 4)), min_size=3, max_size=6))
@settings(max_examples=150, deadline=None)
def test_grid_holes_refused_iff_shapely_invalid(hole):
    outer = _square(0, 0, 5)
    valid = _shapely_says_valid(hole) and Polygon(outer, [hole]).is_valid
    if valid:
        s = Surface(outer, [hole])
        assert s.area == pytest.approx(Polygon(outer, [hole]).area, rel=1e-12)
        _assert_triangulation_exact(s)
    else:
        with pytest.raises(GeometryError, match="hole 0"):
            Surface(outer, [hole])


@given(
    st.lists(
        st.tuples(st.floats(-1, 1, width=32), st.floats(-1, 1, width=32)), min_size=3, max_size=9
    )
)
@settings(max_examples=300, deadline=None)
def test_convex_fast_path_implies_simple(pts):
    p = np.asarray(pts, dtype=np.float64)
    keep = np.r_[True, np.any(np.diff(p, axis=0) != 0, axis=1)]
    p = p[keep]
    if len(p) > 1 and np.array_equal(p[0], p[-1]):
        p = p[:-1]
    assume(len(p) >= 3)
    if strictly_convex(p):
        assert LinearRing(p).is_simple
        assert Polygon(p).is_valid


@given(st.lists(st.floats(0, 2 * math.pi), min_size=3, max_size=12, unique=True))
@settings(max_examples=150, deadline=None)
def test_convex_fast_path_accepts_convex_polygons(angles):
    a = np.sort(np.asarray(angles))
    gaps = np.diff(np.r_[a, a[0] + 2 * math.pi])
    assume(gaps.min() > 1e-3 and gaps.max() < math.pi - 1e-3)
    p = np.column_stack([np.cos(a), np.sin(a)])
    assert LinearRing(p).is_simple
    assert strictly_convex(p)
    assert strictly_convex(p[::-1])
    assert Surface(p).area == pytest.approx(Polygon(p).area, rel=1e-9)


@given(
    k=st.integers(5, 15),
    winds=st.integers(2, 4),
    r=st.floats(0.5, 2.0),
    reverse=st.booleans(),
)
@settings(max_examples=60, deadline=None)
def test_convex_fast_path_refuses_polygons_winding_several_times(k, winds, r, reverse):
    assume(math.gcd(k, winds) == 1 and k > 2 * winds)
    ang = 2 * math.pi * winds * np.arange(k) / k
    p = r * np.column_stack([np.cos(ang), np.sin(ang)])
    if reverse:
        p = p[::-1]
    assert not LinearRing(p).is_simple
    assert not strictly_convex(p)
    with pytest.raises(GeometryError, match="not simple"):
        Surface(p)


def test_convex_fast_path_refuses_a_spike():
    # found by hypothesis: all turns have one sign, but one of them doubles back (~pi)
    spike = np.array([(0.0, 0.0), (0.0, -1.0), (-4.77e-37, 0.0), (1.0, 0.0), (-1.0, -1.0)])
    assert not LinearRing(spike).is_simple
    assert not strictly_convex(spike)


def test_convex_many_agrees_with_the_constructor():
    from workcell import GeometryError, Surface

    square = [(0, 0), (1, 0), (1, 1), (0, 1)]
    cw_quad = [(0, 0), (0, 2), (3, 2), (3, 0)]  # clockwise: normalised to counter-clockwise
    l_shape = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]  # not convex: full constructor
    pole = [(0, 0), (1, 0), (0.5, 1), (0.5, 1)]  # repeated point: full constructor drops it
    stack = [square, cw_quad]
    got = Surface.convex_many(np.array(stack, dtype=float), ["a", "b"])
    for s, pts in zip(got, stack, strict=True):
        ref = Surface(pts)
        np.testing.assert_array_equal(s.main, ref.main)
        assert s.area == pytest.approx(ref.area)
    got = Surface.convex_many(np.array([l_shape]), ["l"])
    assert got[0].area == pytest.approx(3.0)
    got = Surface.convex_many(np.array([pole]), ["p"])
    assert len(got[0].main) == 3
    with pytest.raises(GeometryError, match=r"'bow'.*not simple"):
        Surface.convex_many(np.array([[(0, 0), (1, 1), (1, 0), (0, 1)]], dtype=float), ["bow"])
