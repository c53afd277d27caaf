"""The vendors' rotation conventions against formulas written here from their definitions:
KUKA A, B, C (Z, Y', X''), FANUC W, P, R (fixed X, Y, Z), ABB quaternions (w, x, y, z),
UR rotation vectors; random rotations and the gimbal-lock cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from progframes import Rx, Ry, Rz, quat_matrix, rodrigues

from workcell.robotprog.fanuc import wpr
from workcell.robotprog.rotations import (
    from_kuka_frame,
    from_rotvec,
    from_zyx,
    quat_wxyz,
    rotvec,
    to_kuka_frame,
    zyx,
)


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    return quat_matrix(*q)


angles = st.floats(-179.9, 179.9)


@settings(max_examples=200, deadline=None)
@given(angles, st.floats(-89.9, 89.9), angles)
def test_zyx_is_z_then_new_y_then_newest_x(a: float, b: float, c: float) -> None:
    R = Rz(math.radians(a)) @ Ry(math.radians(b)) @ Rx(math.radians(c))
    assert np.allclose(from_zyx(a, b, c)[:3, :3], R, atol=1e-14)
    A, B, C = zyx(R)
    assert np.allclose([A, B, C], [a, b, c], atol=1e-7)


@settings(max_examples=200, deadline=None)
@given(angles, angles, angles)
def test_wpr_rotates_about_fixed_x_then_y_then_z(w: float, p: float, r: float) -> None:
    # fixed axes: first W about X, then P about the fixed Y, then R about the fixed Z
    R = Rz(math.radians(r)) @ Ry(math.radians(p)) @ Rx(math.radians(w))
    W, P, RR = wpr(R)
    again = Rz(math.radians(RR)) @ Ry(math.radians(P)) @ Rx(math.radians(W))
    assert np.allclose(again, R, atol=1e-12)
    if abs(p) < 89.9:
        assert np.allclose([W, P, RR], [w, p, r], atol=1e-7)


@pytest.mark.parametrize("b", [90.0, -90.0])
@pytest.mark.parametrize(
    ("a", "c"), [(0.0, 0.0), (30.0, 0.0), (0.0, 45.0), (20.0, -70.0), (170.0, 150.0)]
)
def test_gimbal_lock_gives_the_same_matrix(a: float, b: float, c: float) -> None:
    R = Rz(math.radians(a)) @ Ry(math.radians(b)) @ Rx(math.radians(c))
    A, B, C = zyx(R)
    assert pytest.approx(b, abs=1e-9) == B
    assert C == 0.0
    assert np.allclose(
        Rz(math.radians(A)) @ Ry(math.radians(B)) @ Rx(math.radians(C)), R, atol=1e-12
    )


def test_quaternions_are_w_first_and_match_the_textbook_matrix() -> None:
    rng = np.random.default_rng(1)
    for _ in range(200):
        R = random_rotation(rng)
        q = quat_wxyz(R)
        assert q[0] >= 0
        assert abs(np.linalg.norm(q) - 1) < 1e-12
        assert np.allclose(quat_matrix(*q), R, atol=1e-12)
    # a half turn about z: (0, 0, 0, 1); 90 deg about x: (cos 45, sin 45, 0, 0)
    assert np.allclose(quat_wxyz(Rz(math.pi)), [0, 0, 0, 1], atol=1e-12)
    assert np.allclose(quat_wxyz(Rx(math.pi / 2)), [math.sqrt(0.5), math.sqrt(0.5), 0, 0])


def test_rotation_vectors_are_axis_times_angle() -> None:
    rng = np.random.default_rng(2)
    for _ in range(200):
        R = random_rotation(rng)
        v = rotvec(R)
        assert np.linalg.norm(v) <= math.pi + 1e-12
        assert np.allclose(rodrigues(v), R, atol=1e-12)
        assert np.allclose(from_rotvec(v)[:3, :3], R, atol=1e-12)
    # the tool pointing down (a half turn about x): (pi, 0, 0); identity: zeros
    assert np.allclose(np.abs(rotvec(Rx(math.pi))), [math.pi, 0, 0], atol=1e-12)
    assert np.allclose(rotvec(np.eye(3)), 0.0)
    # near a half turn the axis is still right
    R = rodrigues(np.array([0.0, 1.0, 1.0]) / math.sqrt(2) * (math.pi - 1e-9))
    assert np.allclose(rodrigues(rotvec(R)), R, atol=1e-12)


def test_kuka_tool_frames_have_x_out_of_the_tool() -> None:
    # ROS tool0 pointing straight down, y along the base's y (the flange of a KUKA at its
    # home A2 -90, A3 90, A5 90): KUKA's flange x points down: A 0, B 90, C 0
    down = np.diag([-1.0, 1.0, -1.0, 1.0])
    k = to_kuka_frame(down)
    assert np.allclose(k[:3, 0], [0, 0, -1])  # KUKA's x (the tool's axis) points down
    assert np.allclose(k[:3, 1], [0, 1, 0])
    A, B, C = zyx(k)
    assert pytest.approx((0.0, 90.0, 0.0), abs=1e-9) == (A, B, C)
    assert np.allclose(from_kuka_frame(k), down)
