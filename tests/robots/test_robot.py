"""Robot definition and forward kinematics against independent numbers."""

from __future__ import annotations

from types import SimpleNamespace

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from workcell import spatial
from workcell.errors import JointLimitError, KinematicsError
from workcell.robots import Joint, Robot, puma260, puma560
from workcell.robots.mjcf import kinematic_model

P560 = puma560(geometry=False)
A2_260 = 0.0254 * np.hypot(7.8, 0.75)  # DESIGN.md: exact a2 (m) and offset delta (deg)
DELTA_260 = np.degrees(np.arctan2(0.75, 7.8))
P260 = puma260(geometry=False)


def thesis_fk(robot, q):
    """The thesis's formulation (§4.2): Q = Q1...Qn, r = sum Q1..Q(i-1) a_i, with
    Q_i = [[c th, -s th c al, s th s al], [s th, c th c al, -c th s al], [0, s al, c al]],
    a_i = (a c th, a s th, b). Standard DH, revolute joints; base and tool applied outside."""
    Q, r = np.eye(3), np.zeros(3)
    for j, qi in zip(robot.joints, q, strict=True):
        row = j.dh
        th, al = qi + row.offset, row.alpha
        ai = np.array([row.a * np.cos(th), row.a * np.sin(th), row.d])
        r = r + Q @ ai
        Q = Q @ np.array(
            [
                [np.cos(th), -np.sin(th) * np.cos(al), np.sin(th) * np.sin(al)],
                [np.sin(th), np.cos(th) * np.cos(al), -np.cos(th) * np.sin(al)],
                [0.0, np.sin(al), np.cos(al)],
            ]
        )
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = Q, r
    return robot.base @ T @ robot.tool


def test_puma560_named_poses_match_published_values():
    # Corke, Robotics Toolbox: fkine(qz) = transl(0.4521, -0.15005, 0.4318 + d1), identity rotation
    T = P560.fk(P560.pose("qz"))
    np.testing.assert_allclose(T[:3, 3], [0.4318 + 0.0203, -0.15005, 0.67183 + 0.4318], atol=1e-12)
    np.testing.assert_allclose(T[:3, :3], np.eye(3), atol=1e-12)
    # qr: arm straight up: x = a3, z = d1 + a2 + d4
    T = P560.fk(P560.pose("qr"))
    np.testing.assert_allclose(T[:3, 3], [0.0203, -0.15005, 0.67183 + 0.4318 + 0.4318], atol=1e-12)
    np.testing.assert_allclose(T[:3, :3], np.eye(3), atol=1e-12)
    # qs: straight and horizontal: forearm along +x, tool z along +x
    T = P560.fk(P560.pose("qs"))
    np.testing.assert_allclose(T[:3, 3], [0.4318 + 0.4318, -0.15005, 0.67183 - 0.0203], atol=1e-12)
    np.testing.assert_allclose(T[:3, 2], [1.0, 0.0, 0.0], atol=1e-12)


def test_puma260_zero_pose_by_hand():
    # q = 0: theta2 = -delta, theta3 = +delta: the elbow drop cancels, forearm and flange
    # point up from the elbow; the elbow lies 7.8 in forward and 0.75 in below the shoulder
    T = P260.fk(np.zeros(6))
    elbow = 0.0254 * np.array([7.8, 0.0, 0.3302 / 0.0254 - 0.75])
    expected = elbow + np.array([0.0, -0.12446, 0.2032 + 0.05588])
    np.testing.assert_allclose(T[:3, 3], expected, atol=1e-12)
    np.testing.assert_allclose(T[:3, :3], np.eye(3), atol=1e-12)


@given(st.integers(0, 2**32 - 1))
@settings(max_examples=40, deadline=None)
def test_fk_matches_thesis_formulation(seed):
    rng = np.random.default_rng(seed)
    base = spatial.euler(rng.uniform(-3, 3, 3), translation=rng.uniform(-1, 1, 3))
    tool = spatial.euler(rng.uniform(-3, 3, 3), translation=rng.uniform(-0.2, 0.2, 3))
    for robot in (P560, P260, P560.with_(base=base, tool=tool)):
        q = rng.uniform(robot.lower, robot.upper)
        np.testing.assert_allclose(robot.fk(q), thesis_fk(robot, q), atol=1e-12)


def test_fk_batch_equals_single_and_frames():
    rng = np.random.default_rng(3)
    Q = rng.uniform(P560.lower, P560.upper, (50, 6))
    TB = P560.fk_batch(Q)
    for q, T in zip(Q, TB, strict=True):
        np.testing.assert_allclose(T, P560.fk(q), atol=1e-14)
        F = P560.link_frames(q)
        np.testing.assert_allclose(F[-1] @ P560.tool, T, atol=1e-14)
        np.testing.assert_allclose(F[0], P560.base)


def _site_pose(m, d, q):
    d.qpos[:] = q
    mujoco.mj_kinematics(m, d)
    T = np.eye(4)
    T[:3, :3] = d.site_xmat[m.site("tool").id].reshape(3, 3)
    T[:3, 3] = d.site_xpos[m.site("tool").id]
    return T


MIXED_ROWS = [
    dict(name="a", a=0.1, alpha=0.3, d=0.2, offset=0.1),
    dict(name="b", kind="prismatic", a=0.2, alpha=-0.5, theta=0.4, offset=0.05, limits=(0.0, 0.5)),
    dict(name="c", a=0.3, alpha=1.0, d=0.1, limits=(-2.0, 2.0)),
]
MIXED = [Joint.from_dh(**row) for row in MIXED_ROWS]
MIXED_MOD = [Joint.from_dh(**row, convention="modified") for row in MIXED_ROWS]


@pytest.mark.parametrize(
    "robot",
    [
        P560,
        P260,
        P560.with_(base=spatial.euler([0.1, 0.2, 0.3], translation=(1, 2, 3))),
        Robot("mixed_std", MIXED, tool=spatial.translation(0, 0.1, 0.2)),
        Robot("mixed_mod", MIXED_MOD, tool=spatial.translation(0, 0, 0.1)),
    ],
    ids=lambda r: r.name,
)
def test_mujoco_model_agrees_with_numpy_fk(robot):
    m = kinematic_model(robot)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(7)
    for _ in range(200):
        q = rng.uniform(robot.lower, robot.upper)
        np.testing.assert_allclose(_site_pose(m, d, q), robot.fk(q), atol=1e-9)


def test_modified_dh_is_craig_convention():
    # Craig: T_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i), written out here
    r = Robot("mod", MIXED_MOD)
    q = np.array([0.3, 0.2, -0.7])
    T = np.eye(4)
    for row, qi in zip(MIXED_ROWS, q, strict=True):
        j = SimpleNamespace(**{"theta": 0.0, "offset": 0.0, "d": 0.0, "kind": "revolute", **row})
        th = j.theta if j.kind == "prismatic" else qi + j.offset
        dd = qi + j.offset if j.kind == "prismatic" else j.d
        T = T @ spatial.rot_x(j.alpha) @ spatial.translation(j.a, 0, 0)
        T = T @ spatial.rot_z(th) @ spatial.translation(0, 0, dd)
    np.testing.assert_allclose(r.fk(q), T, atol=1e-14)


@pytest.mark.parametrize("robot", [P560, Robot("mixed_mod", MIXED_MOD)], ids=str)
def test_jacobian_matches_finite_differences(robot):
    rng = np.random.default_rng(11)
    for _ in range(10):
        q = rng.uniform(robot.lower + 0.01, robot.upper - 0.01)
        J = robot.jacobian(q)
        h = 1e-6
        for i in range(robot.dof):
            dq = np.zeros(robot.dof)
            dq[i] = h
            Tp, Tm = robot.fk(q + dq), robot.fk(q - dq)
            np.testing.assert_allclose(J[:3, i], (Tp[:3, 3] - Tm[:3, 3]) / (2 * h), atol=1e-8)
            dR = (Tp[:3, :3] - Tm[:3, :3]) / (2 * h) @ robot.fk(q)[:3, :3].T
            w = np.array([dR[2, 1], dR[0, 2], dR[1, 0]])
            np.testing.assert_allclose(J[3:, i], w, atol=1e-8)


def test_limits_and_wrapping():
    lo, hi = (
        np.radians([-160, -45, -225, -110, -100, -266]),
        np.radians([160, 225, 45, 170, 100, 266]),
    )
    np.testing.assert_allclose(P560.lower, lo)
    np.testing.assert_allclose(P560.upper, hi)
    q = np.radians([0, 0, 180, 0, 0, 0])  # q3 = 180 deg is out; -180 deg is its in-limit twin
    assert not P560.within_limits(q)
    w = P560.wrap_to_limits(q)
    np.testing.assert_allclose(w, np.radians([0, 0, -180, 0, 0, 0]))
    np.testing.assert_allclose(P560.fk(w), P560.fk(q), atol=1e-12)
    # q6 has two in-limit twins (range 532 deg): the one nearest to `near` is chosen
    q = np.radians([0, 0, 0, 0, 0, 100])
    np.testing.assert_allclose(
        P560.wrap_to_limits(q, near=np.radians([0, 0, 0, 0, 0, -200]))[5], np.radians(-260)
    )
    assert P560.wrap_to_limits(np.radians([170, 0, 0, 0, 0, 0])) is None  # q1 range is only 320 deg
    with pytest.raises(JointLimitError, match=r"joint 1 \('j1'\) = 170 deg"):
        P560.check_limits(np.radians([170, 0, 0, 0, 0, 0]))


def test_invalid_definitions_raise():
    with pytest.raises(KinematicsError, match="limits"):
        Joint("x", limits=(1.0, -1.0))
    with pytest.raises(KinematicsError, match="kind"):
        Joint("x", kind="spherical")
    for what in ("max_speed", "max_acceleration", "max_jerk"):
        for bad in (0.0, -1.0, float("nan")):
            with pytest.raises(KinematicsError, match=what):
                Joint("x", **{what: bad})
    assert np.all(np.isinf(Robot("r", [Joint("a")]).max_jerks))
    with pytest.raises(KinematicsError, match="repeat"):
        Robot("r", [Joint("a"), Joint("a")])
    with pytest.raises(KinematicsError, match="6 finite"):
        P560.fk([0, 0, 0])
    with pytest.raises(KinematicsError, match="no pose 'nope'"):
        P560.pose("nope")
    with pytest.raises(KinematicsError, match="closed-form"):
        Robot("r", MIXED).ik_closed_form(np.eye(4))


def test_puma_tables_as_designed():
    # DESIGN.md tables, row by row (a, d, alpha deg, offset deg)
    rows560 = [
        (0, 0.67183, 90, 0),
        (0.4318, 0, 0, 0),
        (0.0203, 0.15005, -90, 0),
        (0, 0.4318, 90, 0),
        (0, 0, -90, 0),
        (0, 0, 0, 0),
    ]
    rows260 = [
        (0, 0.3302, 90, 0),
        (A2_260, 0, 0, -DELTA_260),
        (0, 0.12446, -90, DELTA_260),
        (0, 0.2032, 90, 0),
        (0, 0, -90, 0),
        (0, 0, 0, 0),
    ]
    for robot, rows in ((P560, rows560), (P260, rows260)):
        for j, (a, d, al, off) in zip(robot.joints, rows, strict=True):
            assert (j.dh.a, j.dh.d) == (a, d)
            assert np.degrees(j.dh.alpha) == pytest.approx(al)
            assert np.degrees(j.dh.offset) == pytest.approx(off, abs=1e-12)
    np.testing.assert_allclose(P260.tool, spatial.translation(0, 0, 0.05588))
    np.testing.assert_allclose(np.degrees(P260.max_speeds), [119, 119, 164, 577, 431, 397])
    np.testing.assert_allclose(np.degrees(P260.pose("home")), [0, 0, -90, 0, 90, 0])


def test_fk_batch_of_many_poses_crosses_chunks_exactly():
    rng = np.random.default_rng(9)
    Q = rng.uniform(P560.lower, P560.upper, (5000, 6))  # more than one internal chunk
    TB = P560.fk_batch(Q)
    for i in (0, 2047, 2048, 2049, 4095, 4096, 4999):
        np.testing.assert_allclose(TB[i], thesis_fk(P560, Q[i]), atol=1e-12)
