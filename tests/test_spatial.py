"""Tests for workcell.spatial: property tests (hypothesis), hand-computed numbers, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from workcell import spatial as sp
from workcell.errors import GeometryError

SETTINGS = settings(max_examples=60)  # (not a profile: loading one changes every module's)

angles = st.floats(-2 * math.pi, 2 * math.pi, allow_nan=False, allow_infinity=False)
coords = st.floats(-10.0, 10.0, allow_nan=False, allow_infinity=False)
vec3 = st.tuples(coords, coords, coords).map(np.array)
unit = st.floats(-1.0, 1.0, allow_nan=False, allow_infinity=False)
quats = st.tuples(unit, unit, unit, unit).map(np.array).filter(lambda q: np.linalg.norm(q) > 0.1)
seqs = st.sampled_from(["xyz", "zyx", "xzx", "XYZ", "ZYX", "ZXZ", "yxz", "YZY"])
scales = st.floats(0.1, 10.0).flatmap(lambda m: st.sampled_from([m, -m]))


@st.composite
def rigid_transforms(draw: st.DrawFn) -> np.ndarray:
    return sp.matrix_from_quat(draw(quats), draw(vec3))


def assert_rotation(T: np.ndarray) -> None:
    assert T.shape == (4, 4)
    assert T.dtype == np.float64
    R = T[:3, :3]
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_array_equal(T[3], [0, 0, 0, 1])
    assert sp.is_rigid(T)


def test_all_names_resolve():
    for name in sp.__all__:
        assert callable(getattr(sp, name)), name


# --- orthonormality of every rotation constructor ------------------------------------


@SETTINGS
@given(angles)
def test_axis_rotations_are_orthonormal(a):
    for f in (sp.rot_x, sp.rot_y, sp.rot_z):
        assert_rotation(f(a))


@SETTINGS
@given(st.tuples(angles, angles, angles), seqs, vec3)
def test_euler_is_orthonormal(a, seq, t):
    T = sp.euler(a, seq, translation=t)
    assert_rotation(T)
    np.testing.assert_array_equal(T[:3, 3], t)


@SETTINGS
@given(vec3, angles, vec3)
def test_axis_angle_is_orthonormal(axis, a, p):
    assume(np.linalg.norm(axis) > 1e-3)
    assert_rotation(sp.axis_angle(axis, a, p))


@SETTINGS
@given(st.tuples(angles, angles, angles), vec3)
def test_srt_unit_scale_is_orthonormal(r, t):
    assert_rotation(sp.srt(1.0, r, t))


@SETTINGS
@given(quats, vec3)
def test_matrix_from_quat_is_orthonormal(q, t):
    assert_rotation(sp.matrix_from_quat(q, t))


@SETTINGS
@given(vec3, vec3, vec3)
def test_frame_from_points_is_orthonormal(o, a, b):
    u, v = a - o, b - o
    assume(np.linalg.norm(np.cross(u, v)) > 1e-3 * max(1.0, np.linalg.norm(u) * np.linalg.norm(v)))
    F = sp.frame_from_points(o, a, b)
    assert_rotation(F)
    np.testing.assert_array_equal(F[:3, 3], o)
    # x axis toward a, b in the local xy plane with positive y
    local_a = sp.transform_points(sp.invert(F), a)
    local_b = sp.transform_points(sp.invert(F), b)
    np.testing.assert_allclose(local_a[1:], 0, atol=1e-9)
    assert local_a[0] > 0
    assert abs(local_b[2]) < 1e-9
    assert local_b[1] > 0


# --- round trips ------------------------------------------------------------------------


@SETTINGS
@given(quats)
def test_quat_matrix_round_trip(q):
    qn = q / np.linalg.norm(q)
    back = sp.quat_from_matrix(sp.matrix_from_quat(q))
    assert back[0] >= 0
    assert np.linalg.norm(back) == pytest.approx(1.0)
    assert min(np.abs(back - qn).max(), np.abs(back + qn).max()) < 1e-9


@SETTINGS
@given(rigid_transforms())
def test_matrix_quat_round_trip(T):
    pos, q = sp.pos_quat_from_pose(T)
    np.testing.assert_allclose(sp.pose_from_pos_quat(pos, q), T, atol=1e-12)
    R_only = sp.matrix_from_quat(sp.quat_from_matrix(T[:3, :3]))
    np.testing.assert_allclose(R_only[:3, :3], T[:3, :3], atol=1e-12)
    np.testing.assert_array_equal(R_only[:3, 3], 0)


@SETTINGS
@given(rigid_transforms())
def test_invert_rigid(T):
    np.testing.assert_allclose(sp.invert(T) @ T, np.eye(4), atol=1e-12)
    np.testing.assert_allclose(T @ sp.invert(T), np.eye(4), atol=1e-12)
    np.testing.assert_array_equal(sp.invert(T)[:3, :3], T[:3, :3].T)


@SETTINGS
@given(st.tuples(scales, scales, scales), st.tuples(angles, angles, angles), vec3)
def test_invert_affine(s, r, t):
    T = sp.srt(s, r, t)
    assert sp.is_affine(T)
    assert not sp.is_rigid(T) or np.allclose(np.abs(s), 1)
    np.testing.assert_allclose(sp.invert(T) @ T, np.eye(4), atol=1e-9)
    np.testing.assert_array_equal(sp.invert(T)[3], [0, 0, 0, 1])


@SETTINGS
@given(rigid_transforms(), vec3, vec3, vec3)
def test_from_point_pairs_recovers_transform(T, p0, p1, p2):
    P = np.array([p0, p1, p2])
    u, v = p1 - p0, p2 - p0
    assume(min(np.linalg.norm(u), np.linalg.norm(v)) > 1e-2)
    assume(np.linalg.norm(np.cross(u, v)) > 1e-2 * np.linalg.norm(u) * np.linalg.norm(v))
    Q = sp.transform_points(T, P)
    found = sp.from_point_pairs(P, Q)
    assert sp.is_rigid(found)
    np.testing.assert_allclose(found, T, atol=1e-8)
    np.testing.assert_allclose(sp.transform_points(found, P), Q, atol=1e-8)


@SETTINGS
@given(st.tuples(angles, angles, angles), vec3)
def test_euler_xyz_extrinsic_matches_srt(r, t):
    np.testing.assert_allclose(sp.euler(r, "xyz", translation=t), sp.srt(1, r, t), atol=1e-12)


@SETTINGS
@given(st.tuples(angles, angles, angles))
def test_euler_intrinsic_is_moving_axes(r):
    a, b, c = r
    expected = sp.rot_x(a) @ sp.rot_y(b) @ sp.rot_z(c)
    np.testing.assert_allclose(sp.euler(r, "XYZ"), expected, atol=1e-12)
    deg = np.rad2deg(r)
    np.testing.assert_allclose(sp.euler(deg, "XYZ", degrees=True), expected, atol=1e-12)


@SETTINGS
@given(quats, st.lists(quats, min_size=1, max_size=5))
def test_quat_order_round_trip(q, qs):
    np.testing.assert_array_equal(sp.xyzw_to_wxyz(sp.wxyz_to_xyzw(q)), q)
    np.testing.assert_array_equal(sp.wxyz_to_xyzw(q), [q[1], q[2], q[3], q[0]])
    Q = np.array(qs)
    np.testing.assert_array_equal(sp.wxyz_to_xyzw(sp.xyzw_to_wxyz(Q)), Q)
    np.testing.assert_array_equal(sp.xyzw_to_wxyz(Q)[:, 0], Q[:, 3])


@SETTINGS
@given(vec3, angles, vec3, vec3)
def test_axis_angle_fixes_point_and_matches_rodrigues(axis, theta, p, v):
    assume(np.linalg.norm(axis) > 1e-3)
    T = sp.axis_angle(axis, theta, p)
    np.testing.assert_allclose(sp.transform_points(T, p), p, atol=1e-12)
    k = axis / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    R = np.eye(3) + math.sin(theta) * K + (1 - math.cos(theta)) * K @ K
    np.testing.assert_allclose(sp.transform_points(T, v), p + R @ (v - p), atol=1e-9)


@SETTINGS
@given(vec3, st.floats(0.0, math.pi), vec3)
def test_rotation_angle_and_pose_error(axis, theta, t):
    assume(np.linalg.norm(axis) > 1e-3)
    A = sp.matrix_from_quat([0.3, -0.2, 0.9, 0.1], t)
    B = A @ sp.translation(3, 4, 0) @ sp.axis_angle(axis, theta)
    assert sp.rotation_angle(sp.axis_angle(axis, theta)) == pytest.approx(theta, abs=1e-9)
    dist, ang = sp.pose_error(A, B)
    assert dist == pytest.approx(5.0)
    assert ang == pytest.approx(theta, abs=1e-9)


# --- independent, hand-computed numbers -------------------------------------------------


def test_rot_z_quarter_turn_is_exact():
    np.testing.assert_array_equal(sp.transform_points(sp.rot_z(math.pi / 2), [1, 0, 0]), [0, 1, 0])
    np.testing.assert_array_equal(sp.transform_points(sp.rot_x(math.pi / 2), [0, 1, 0]), [0, 0, 1])
    np.testing.assert_array_equal(sp.transform_points(sp.rot_y(math.pi / 2), [0, 0, 1]), [1, 0, 0])


def test_thesis_cube_rows():
    # unit square in the xy plane, placed six times by the thesis's SRT rows
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    row = sp.srt(rotation=(90, 0, 0), translation=(0, 1, 0), degrees=True)
    np.testing.assert_array_equal(sp.transform_points(row, [0, 1, 0]), [0, 1, 1])
    rows = {  # SRT row -> (axis held fixed, its value)
        ((90, 0, 0), (0, 0, 0)): (1, 0.0),
        ((90, 0, 0), (0, 1, 0)): (1, 1.0),
        ((0, -90, 0), (0, 0, 0)): (0, 0.0),
        ((0, -90, 0), (1, 0, 0)): (0, 1.0),
        ((0, 0, 0), (0, 0, 0)): (2, 0.0),
        ((0, 0, 0), (0, 0, 1)): (2, 1.0),
    }
    faces = set()
    for (r, t), (axis, value) in rows.items():
        pts = sp.transform_points(sp.srt(1, r, t, degrees=True), square)
        np.testing.assert_array_equal(pts[:, axis], value)
        assert set(np.unique(pts)) <= {0.0, 1.0}
        faces.add(frozenset(map(tuple, pts)))
    assert len(faces) == 6
    corners = set().union(*faces)
    assert corners == {(x, y, z) for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)}
    # R_y=-90 maps x to z: (1,0,0) -> (0,0,1)
    np.testing.assert_array_equal(sp.transform_points(sp.rot_y(-math.pi / 2), [1, 0, 0]), [0, 0, 1])


def test_srt_order():
    # scale first, then rotate: (1,1,1) -S(2,3,4)-> (2,3,4) -Rz 90-> (-3,2,4) -T-> (-2,2,4)
    M = sp.srt((2, 3, 4), (0, 0, math.pi / 2), (1, 0, 0))
    np.testing.assert_allclose(sp.transform_points(M, [1, 1, 1]), [-2, 2, 4], atol=1e-15)
    # x rotation before z: (1,0,0) -Rx-> (1,0,0) -Rz-> (0,1,0)
    M = sp.srt(1, (90, 0, 90), degrees=True)
    np.testing.assert_array_equal(sp.transform_points(M, [1, 0, 0]), [0, 1, 0])
    np.testing.assert_array_equal(sp.srt(2.5), np.diag([2.5, 2.5, 2.5, 1]))


def test_simple_constructors():
    np.testing.assert_array_equal(sp.identity(), np.eye(4))
    np.testing.assert_array_equal(sp.translation(1, 2, 3)[:3, 3], [1, 2, 3])
    np.testing.assert_array_equal(sp.translation(z=2)[:3, 3], [0, 0, 2])
    np.testing.assert_array_equal(sp.scaling(2), np.diag([2, 2, 2, 1]))
    np.testing.assert_array_equal(sp.scaling(2, 3, -1), np.diag([2, 3, -1, 1]))
    c, s = math.cos(0.3), math.sin(0.3)
    np.testing.assert_allclose(sp.rot_x(0.3)[1:3, 1:3], [[c, -s], [s, c]])
    np.testing.assert_allclose(sp.rot_y(0.3)[[0, 2]][:, [0, 2]], [[c, s], [-s, c]])


def test_frame_from_points_by_hand():
    F = sp.frame_from_points([1, 2, 3], [1, 2, 5], [0, 2, 3])
    # x = +z, y = -x, z = x cross y = (0,0,1) x (-1,0,0) = (0,-1,0)
    np.testing.assert_allclose(F[:3, :3], [[0, -1, 0], [0, 0, -1], [1, 0, 0]], atol=1e-15)
    np.testing.assert_array_equal(F[:3, 3], [1, 2, 3])


def test_from_point_pairs_by_hand():
    start = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    end = np.array([[5, 0, 0], [5, 1, 0], [4, 0, 0]], float)  # Rz(90) then T(5,0,0)
    T = sp.from_point_pairs(start, end)
    np.testing.assert_allclose(T, sp.translation(5, 0, 0) @ sp.rot_z(math.pi / 2), atol=1e-15)


def test_quaternions_by_hand():
    h = math.sqrt(0.5)
    np.testing.assert_allclose(sp.quat_from_matrix(sp.rot_z(math.pi / 2)), [h, 0, 0, h])
    np.testing.assert_allclose(sp.quat_from_matrix(sp.rot_x(-math.pi / 2)), [h, -h, 0, 0])
    np.testing.assert_allclose(np.abs(sp.quat_from_matrix(sp.rot_x(math.pi))), [0, 1, 0, 0])
    np.testing.assert_allclose(
        sp.matrix_from_quat([2, 0, 0, 0], [1, 2, 3]), sp.translation(1, 2, 3)
    )
    np.testing.assert_allclose(sp.matrix_from_quat([h, 0, 0, h]), sp.rot_z(math.pi / 2), atol=1e-15)
    # rerun order
    np.testing.assert_array_equal(sp.wxyz_to_xyzw([1, 2, 3, 4]), [2, 3, 4, 1])
    np.testing.assert_array_equal(sp.xyzw_to_wxyz([2, 3, 4, 1]), [1, 2, 3, 4])


def test_compose_and_transform():
    A, B = sp.translation(1, 0, 0), sp.rot_z(math.pi / 2)
    np.testing.assert_array_equal(sp.compose(), np.eye(4))
    np.testing.assert_array_equal(sp.compose(A), A)
    np.testing.assert_array_equal(sp.compose(A, B), A @ B)
    np.testing.assert_array_equal(sp.compose(A, B, A), A @ B @ A)
    M = sp.compose(A, B)
    np.testing.assert_array_equal(sp.transform_points(M, [1, 0, 0]), [1, 1, 0])
    pts = sp.transform_points(M, [[1, 0, 0], [0, 0, 0]])
    assert pts.shape == (2, 3)
    np.testing.assert_array_equal(pts, [[1, 1, 0], [1, 0, 0]])
    np.testing.assert_array_equal(sp.transform_vectors(M, [1, 0, 0]), [0, 1, 0])
    np.testing.assert_array_equal(sp.transform_vectors(M, [[1, 0, 0]]), [[0, 1, 0]])
    assert sp.rotation_angle(sp.identity()) == 0.0
    assert sp.pose_error(A, A) == (0.0, 0.0)


def test_as_transform_accepts_and_copies():
    raw = [[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3]]
    M = sp.as_transform(raw)
    assert M.dtype == np.float64
    np.testing.assert_array_equal(M, sp.translation(1, 2, 3))
    src = sp.scaling(2)
    out = sp.as_transform(src)
    out[0, 0] = 7
    assert src[0, 0] == 2
    np.testing.assert_array_equal(sp.as_transform(sp.rot_x(0.4), rigid=True), sp.rot_x(0.4))


def test_predicates():
    assert sp.is_rigid(sp.rot_x(1.0) @ sp.translation(1, 2, 3))
    assert not sp.is_rigid(sp.scaling(2))
    assert not sp.is_rigid(sp.scaling(1, 1, -1))  # reflection
    assert sp.is_affine(sp.scaling(1, 1, -1))
    assert not sp.is_affine(np.diag([1, 1, 0, 1]))
    bad = np.eye(4)
    bad[3, 0] = 0.5
    assert not sp.is_affine(bad)
    assert not sp.is_rigid(bad)
    assert not sp.is_affine(np.full((4, 4), np.nan))
    assert not sp.is_rigid(np.eye(3))


# --- errors -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("matrix", "reason"),
    [
        (np.diag([1.0, 0.0, 1.0, 1.0]), "singular"),
        (np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]]), "last row"),
        (np.where(np.eye(4) == 1, np.nan, 0.0), "non-finite"),
        (np.eye(3), "shape"),
    ],
)
def test_as_transform_errors_name_the_transform(matrix, reason):
    with pytest.raises(GeometryError, match=f"'ts3'.*{reason}"):
        sp.as_transform(matrix, name="ts3")


def test_as_transform_rigid_errors():
    with pytest.raises(GeometryError, match=r"'ts3' is not rigid: R\^T R differs from I by 3"):
        sp.as_transform(sp.scaling(1.0, 1.0, 1.015), rigid=True, name="ts3")
    with pytest.raises(GeometryError, match=r"'tb1' is not rigid: det"):
        sp.as_transform(sp.scaling(1, 1, -1), rigid=True, name="tb1")
    sp.as_transform(sp.scaling(1.0, 1.0, 1.015), name="ts3")  # fine when not rigid


def test_geometry_errors():
    with pytest.raises(GeometryError, match="collinear"):
        sp.frame_from_points([0, 0, 0], [1, 1, 1], [2, 2, 2])
    with pytest.raises(GeometryError, match="coincident"):
        sp.frame_from_points([1, 1, 1], [1, 1, 1], [0, 1, 0])
    with pytest.raises(GeometryError, match="collinear"):
        sp.from_point_pairs([[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 0, 0], [0, 1, 0], [0, 2, 0]])
    with pytest.raises(GeometryError, match="not rigid"):
        sp.from_point_pairs(np.eye(3), 2 * np.eye(3))
    with pytest.raises(GeometryError, match="axis"):
        sp.axis_angle([0, 0, 0], 1.0)
    with pytest.raises(GeometryError, match="quaternion"):
        sp.matrix_from_quat([0, 0, 0, 0])
    with pytest.raises(GeometryError, match="non-zero"):
        sp.scaling(1, 0, 1)
    with pytest.raises(GeometryError, match="non-zero"):
        sp.srt(0)
    with pytest.raises(GeometryError, match="finite"):
        sp.rot_x(float("nan"))
    with pytest.raises(GeometryError, match="finite"):
        sp.translation(float("inf"))
    with pytest.raises(GeometryError, match="Euler"):
        sp.euler((1, 2, 3), "xyx-")
    with pytest.raises(GeometryError, match="Euler"):
        sp.euler((1, 2, 3), "xYz")
    with pytest.raises(GeometryError, match="angles"):
        sp.euler((1, 2), "xyz")
    with pytest.raises(GeometryError, match="not a rotation"):
        sp.quat_from_matrix(sp.scaling(2))
    with pytest.raises(GeometryError, match="not a rotation"):
        sp.quat_from_matrix(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(GeometryError, match="shape"):
        sp.transform_points(np.eye(4), [1, 2])
    with pytest.raises(GeometryError, match="shape"):
        sp.wxyz_to_xyzw([1, 2, 3])
    with pytest.raises(GeometryError, match="singular"):
        sp.invert(np.diag([1, 1, 0, 1]))
