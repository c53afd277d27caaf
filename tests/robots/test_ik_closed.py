"""Closed-form IK of the Pumas (the OPW family) against checks from outside the solver.

- Round trips: ``Robot.fk`` (the project's general DH chain, itself tested against the
  thesis formulation and MuJoCo) of every returned q reproduces the target pose.
- Configuration letters: derived here from the link frames of ``Robot.link_frames``
  (which side of the joint 1 axis the wrist centre lies, whether the elbow lies above the
  shoulder-wrist line) and from the sign of sin(q5), following Corke's ``ikine6s``.
- Joint limits: brute force over 2 pi shifts, and ``Robot.wrap_to_limits``.
- Reach: the workspace of the wrist centre computed by hand from the DH table: between
  the spheres about the shoulder of radii sqrt((L -+ a2)^2 + d3^2), L = sqrt(a3^2 + d4^2),
  and outside the cylinder of radius |d3| about the joint 1 axis.
- The single-pose path (Python floats) against the batched one (numpy), its joint
  wrapping against ``Robot.wrap_batch`` to the bit, its FK check against ``Robot.fk``.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from workcell import spatial
from workcell.errors import GeometryError, KinematicsError
from workcell.robots import Joint, Robot, ik_closed, puma260, puma560
from workcell.robots.ik_closed import CONFIGS, config_of, ik_all, ik_batch, ik_report
from workcell.robots.ik_wrap import rows_of

P560 = puma560(geometry=False)
P260 = puma260(geometry=False)
MOUNTED = P560.with_(
    name="puma560_mounted",
    base=spatial.translation(1.2, -0.4, 0.8) @ spatial.rot_z(0.7) @ spatial.rot_x(0.3),
    tool=spatial.translation(0.02, -0.01, 0.12) @ spatial.rot_y(0.4),
)
ROBOTS = {"puma560": P560, "puma260": P260, "mounted": MOUNTED}
TWO_PI = 2 * np.pi


def with_dh(joint, **changes):
    """The joint rebuilt from its DH row with some DH entries (or the convention) changed."""
    row = {**dataclasses.asdict(joint.dh), **changes}
    return Joint.from_dh(joint.name, **row, limits=joint.limits, max_speed=joint.max_speed)


def wrapped(a):
    """Angle differences wrapped to [-pi, pi)."""
    return (np.asarray(a) + np.pi) % TWO_PI - np.pi


def joint_vectors(robot):
    """Hypothesis strategy: joint vectors (rad) inside the robot's limits."""
    return st.tuples(
        *[
            st.floats(lo, hi, allow_nan=False)
            for lo, hi in zip(robot.lower, robot.upper, strict=True)
        ]
    ).map(np.array)


def arm_plane(robot, q):
    """Shoulder-relative wrist centre w and elbow e in the arm plane (x1, y1), from frames."""
    F = robot.link_frames(q)
    o1, x1, y1 = F[1][:3, 3], F[1][:3, 0], F[1][:3, 1]
    # y1 is the base z axis ("up" for the elbow letter)
    np.testing.assert_allclose(y1, F[0][:3, 2], atol=1e-12)
    w, e = F[4][:3, 3] - o1, F[2][:3, 3] - o1
    return np.array([w @ x1, w @ y1]), np.array([e @ x1, e @ y1])


def geometric_config(robot, q):
    """Corke's letters from geometry: r if the wrist centre is on the +x1 side of the joint 1
    axis; u if the elbow is above the shoulder-wrist line; n if sin(theta5) < 0."""
    w, e = arm_plane(robot, q)
    arm = "r" if w[0] >= 0 else "l"
    above = (e[1] - w[1] * e[0] / w[0]) > 0  # elbow height over the line at the elbow's x
    wrist = "n" if np.sin(q[4] + robot.joints[4].dh.offset) < 0 else "f"
    return arm + ("u" if above else "d") + wrist


def arm_margin(robot, q):
    """How far the arm is from the l/r and u/d boundaries (dimensionless; 0 on one)."""
    w, e = arm_plane(robot, q)
    cross = abs(w[0] * e[1] - w[1] * e[0]) / (np.linalg.norm(w) * np.linalg.norm(e))
    side = abs(w[0]) / np.linalg.norm(w)
    return min(cross, side)


def margin(robot, q):
    """How far q is from every configuration boundary (dimensionless; 0 on one)."""
    return min(arm_margin(robot, q), abs(np.sin(q[4] + robot.joints[4].dh.offset)))


def has_in_limit_equivalent(robot, q):
    """Brute force: every joint has some q_j + 2 pi k (|k| <= 3) within its limits."""
    k = np.arange(-3, 4)[:, None]
    shifted = q[None, :] + TWO_PI * k
    inside = (shifted >= robot.lower - 1e-9) & (shifted <= robot.upper + 1e-9)
    return bool(inside.any(axis=0).all())


# ---------------------------------------------------------------- round trips
@pytest.mark.parametrize("name", list(ROBOTS))
@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_fk_of_every_solution_is_the_target(name, data):
    robot = ROBOTS[name]
    q = data.draw(joint_vectors(robot))
    T = robot.fk(q)
    sols = robot.ik_closed_form(T)
    assert sols
    for s in sols:
        assert np.abs(robot.fk(s.q) - T).max() < 1e-10
        dp, dr = spatial.pose_error(robot.fk(s.q), T)
        assert s.position_error < 1e-10
        assert s.orientation_error < 1e-10
        assert abs(s.position_error - dp) < 1e-12
        assert abs(s.orientation_error - dr) < 1e-7  # scipy's angle of a ~1e-15 rotation
        assert (s.method, s.iterations) == ("closed-form", 0)
        assert s.success == s.within_limits
        assert s.success == (s.reason == "")
    qs = np.array([s.q for s in sols])
    D = np.abs(wrapped(qs[:, None] - qs[None])).max(axis=-1)
    assert (D[~np.eye(len(sols), dtype=bool)] > 1e-9).all(), "duplicate solutions"


@pytest.mark.parametrize("name", list(ROBOTS))
@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_generating_q_is_found_with_its_geometric_config(name, data):
    robot = ROBOTS[name]
    q = data.draw(joint_vectors(robot))
    assume(margin(robot, q) > 1e-3)
    sols = ik_all(robot, robot.fk(q))
    assert len(sols) == 8  # a generic reachable pose of a Puma has 8 solutions
    gap = [np.abs(wrapped(s.q - q)).max() for s in sols]
    match = sols[int(np.argmin(gap))]
    assert min(gap) < 1e-8
    assert match.config == geometric_config(robot, q)
    assert match.within_limits  # q itself is within the limits
    # every solution's letters describe its own geometry, and all 8 differ
    assert sorted(s.config for s in sols) == sorted(CONFIGS)
    for s in sols:
        if margin(robot, s.q) > 1e-6:
            assert s.config == geometric_config(robot, s.q)
            assert config_of(robot, s.q) == s.config
    assert config_of(robot, q) == geometric_config(robot, q)


def test_qn_has_eight_solutions_and_is_right_arm_elbow_up():
    # Corke's nominal pose qn = (0, 45, 180, 0, 45, 0) deg (stored with q3 = -180 deg); the
    # toolbox recovers it with ikine6s(T, 'ru'): right arm, elbow up; q5 = +45 deg means
    # sin(theta5) > 0, the wrist letter f (ikine6s gives sin(theta5) < 0 for an explicit n)
    qn = P560.pose("qn")
    sols = ik_all(P560, P560.fk(qn))
    assert len(sols) == 8
    assert {s.config for s in sols} == set(CONFIGS)
    by_config = {s.config: s for s in sols}
    np.testing.assert_allclose(wrapped(by_config["ruf"].q - qn), 0.0, atol=1e-12)
    # its wrist twin: (q4 + pi, -q5, q6 + pi)
    twin = qn + np.array([0, 0, 0, np.pi, -2 * qn[4], np.pi])
    np.testing.assert_allclose(wrapped(by_config["run"].q - twin), 0.0, atol=1e-12)
    # the zero pose is right-armed in Corke's convention ("a righty for Paul"), with the
    # elbow below the line from the shoulder to the wrist centre
    w, e = arm_plane(P560, np.zeros(6))
    assert w[0] > 0
    assert e[1] < w[1] * e[0] / w[0]
    assert config_of(P560, np.zeros(6)) == "rdn"
    assert config_of(P560, qn) == "ruf"


# ---------------------------------------------------------------- joint limits
@pytest.mark.parametrize("robot", [P560, P260], ids=["puma560", "puma260"])
def test_within_limits_flags_and_representatives(robot):
    rng = np.random.default_rng(7)
    seen = {True: 0, False: 0}
    for _ in range(150):
        q = rng.uniform(robot.lower, robot.upper)
        q_current = rng.uniform(robot.lower, robot.upper) if rng.random() < 0.5 else None
        for s in ik_all(robot, robot.fk(q), q_current):
            seen[s.within_limits] += 1
            assert s.within_limits == has_in_limit_equivalent(robot, s.q)
            if s.within_limits:
                assert robot.within_limits(s.q)
                near = s.q if q_current is None else q_current
                expected = robot.wrap_to_limits(s.q, near=near)
                np.testing.assert_allclose(s.q, expected, atol=1e-12)
            else:
                assert not s.success
                assert "limits" in s.reason
                assert robot.wrap_to_limits(s.q) is None
                assert np.all((s.q > -np.pi - 1e-12) & (s.q <= np.pi + 1e-12))
    assert seen[True]  # both kinds occur in this sample
    assert seen[False]


def test_puma260_nearest_representative_of_wide_joint4():
    # joint 4 of the 260 spans -194 .. 384 deg: 10 deg has the equivalent 370 deg
    q = np.radians([10.0, 20.0, -100.0, 10.0, 40.0, 30.0])
    T = P260.fk(q)
    near = np.radians([10.0, 20.0, -100.0, 350.0, 40.0, 30.0])
    best = ik_all(P260, T, near)[0]
    np.testing.assert_allclose(best.q, q + np.array([0, 0, 0, TWO_PI, 0, 0]), atol=1e-10)
    plain = [s for s in ik_all(P260, T) if np.abs(wrapped(s.q - q)).max() < 1e-9]
    np.testing.assert_allclose(plain[0].q, q, atol=1e-10)


# ---------------------------------------------------------------- ordering
@pytest.mark.parametrize("name", list(ROBOTS))
def test_order_nearest_to_q_current_first(name):
    robot = ROBOTS[name]
    rng = np.random.default_rng(3)
    tested = 0
    for _ in range(30):
        q = rng.uniform(robot.lower + 0.05, robot.upper - 0.05)
        if margin(robot, q) < 0.1:  # other branches lie >= ~0.2 rad away
            continue
        tested += 1
        q_current = q + rng.uniform(-0.01, 0.01, 6)
        sols = ik_all(robot, robot.fk(q), q_current)
        np.testing.assert_allclose(sols[0].q, q, atol=1e-8)
        keys = [(not s.within_limits, np.abs(s.q - q_current).max()) for s in sols]
        assert keys == sorted(keys)
        # no q_current: within limits first, then the fixed order lun, luf, ldn, ...
        plain = ik_all(robot, robot.fk(q))
        keys = [(not s.within_limits, CONFIGS.index(s.config)) for s in plain]
        assert keys == sorted(keys)
    assert tested >= 10


# ---------------------------------------------------------------- wrist singularity
@pytest.mark.parametrize("name", list(ROBOTS))
def test_aligned_wrist_takes_q4_from_q_current(name):
    # q5 = 0 aligns the axes of joints 4 and 6 on the generating arm/elbow branch only (the
    # other branches see the wrist from another forearm direction): that branch gives one
    # solution (its wrist twin is the same pose), the other three branches give two each
    robot = ROBOTS[name]
    rng = np.random.default_rng(11)
    tested = 0
    for _ in range(20):
        q = rng.uniform(robot.lower, robot.upper)
        q[4] = 0.0
        if arm_margin(robot, q) < 1e-3:
            continue
        tested += 1
        T = robot.fk(q)
        q_current = rng.uniform(robot.lower, robot.upper)
        for qc, q4 in ((None, 0.0), (q_current, q_current[3])):
            sols = ik_all(robot, T, qc)
            assert len(sols) == 7
            singular = [s for s in sols if s.singular]
            assert len(singular) == 1
            s = singular[0]
            assert s.config[2] == "n"
            assert s.config == geometric_config(robot, q)[:2] + "n"
            np.testing.assert_allclose(wrapped(s.q[:3] - q[:3]), 0.0, atol=1e-9)
            assert abs(np.sin(s.q[4])) < 1e-12
            if s.within_limits:
                assert wrapped(s.q[3] - q4) == pytest.approx(0.0, abs=1e-12)
            for s in sols:
                assert np.abs(robot.fk(s.q) - T).max() < 1e-10
    assert tested >= 15


def test_puma260_zero_pose_is_singular_and_exact():
    T = P260.fk(np.zeros(6))
    sols, reason = ik_report(P260, T)
    assert reason == ""
    zero = [s for s in sols if np.abs(wrapped(s.q)).max() < 1e-10]
    assert len(zero) == 1
    assert zero[0].singular
    assert zero[0].success
    assert zero[0].config == "rdn"  # the elbow lies below the shoulder-wrist line
    # the forearm is vertical on the ld branch too: two aligned branches, two bent ones
    assert sorted(s.config for s in sols if s.singular) == ["ldn", "rdn"]
    assert len(sols) == 6
    for s in sols:
        assert np.abs(P260.fk(s.q) - T).max() < 1e-10


def test_near_singular_wrist_is_flagged_and_exact():
    q = P560.pose("qn").copy()
    q[4] = 1e-8  # |sin q5| < 1e-6 but the wrist axes are not aligned
    T = P560.fk(q)
    sols = ik_all(P560, T)
    assert len(sols) == 8
    flagged = [s for s in sols if s.singular]
    assert sorted(s.config for s in flagged) == ["ruf", "run"]  # the generating branch
    for s in sols:
        assert np.abs(P560.fk(s.q) - T).max() < 1e-10
    assert min(np.abs(wrapped(s.q - q)).max() for s in flagged) < 1e-6


# ---------------------------------------------------------------- reach
def reach_radii(robot):
    """Inner and outer radii (m) of the wrist-centre workspace about the shoulder, by hand."""
    j = [jt.dh for jt in robot.joints]
    a2, a3, d3, d4 = j[1].a, j[2].a, j[2].d, j[3].d
    L = math.hypot(a3, d4)
    return math.hypot(L - a2, d3), math.hypot(a2 + L, d3)


def pose_with_wrist_centre(robot, p_wc, R=None):
    """Tool pose in the base-reference frame whose wrist centre (frame 6 origin) is p_wc,
    given in frame 0 of the DH chain."""
    T6 = np.eye(4)
    T6[:3, :3] = np.eye(3) if R is None else R
    T6[:3, 3] = p_wc
    return robot.base @ T6 @ robot.tool


@pytest.mark.parametrize("name", list(ROBOTS))
def test_reach_boundaries(name):
    robot = ROBOTS[name]
    d1, d3 = robot.joints[0].dh.d, robot.joints[2].dh.d
    inner, outer = reach_radii(robot)
    # along theta1 = 0 the shoulder offset points along -y: the wrist centre at
    # (rho, -d3, d1) lies at sqrt(rho^2 + d3^2) from the shoulder
    cases = [
        (math.sqrt(outer**2 - d3**2) * (1 - 1e-6), 8, ""),
        (math.sqrt(outer**2 - d3**2) * (1 + 1e-6), 0, "beyond the arm's reach"),
        (math.sqrt(inner**2 - d3**2) * (1 + 1e-3), 8, ""),
        (math.sqrt(inner**2 - d3**2) * (1 - 1e-3), 0, "minimum reach"),
    ]
    for rho, n_expected, words in cases:
        T = pose_with_wrist_centre(robot, [rho, -d3, d1])
        sols, reason = ik_report(robot, T)
        assert len(sols) == n_expected
        assert words in reason
        for s in sols:
            assert np.abs(robot.fk(s.q) - T).max() < 1e-9


@pytest.mark.parametrize("name", list(ROBOTS))
def test_unreachable_poses_give_empty_list_and_reason(name):
    robot = ROBOTS[name]
    d1 = robot.joints[0].dh.d
    far = pose_with_wrist_centre(robot, [2.0, 0.0, d1])
    assert ik_all(robot, far) == []
    assert robot.ik_closed_form(far) == []
    sols, reason = ik_report(robot, far)
    assert sols == []
    assert "reach" in reason
    # on the joint 1 axis, inside the shoulder-offset cylinder of radius |d3|
    axis = pose_with_wrist_centre(robot, [0.0, 0.0, d1 + 0.2])
    sols, reason = ik_report(robot, axis)
    assert sols == []
    assert "cylinder" in reason
    Q, valid = ik_batch(robot, np.stack([far, axis]))
    assert np.isnan(Q).all()
    assert not valid.any()


def test_zero_shoulder_offset_wrist_on_the_axis():
    # a Puma-like arm with d3 = a3 = 0: a wrist centre on the joint 1 axis leaves q1 free
    joints = list(P560.joints)
    joints[2] = with_dh(joints[2], a=0.0, d=0.0)
    robot = Robot(name="no_offset", joints=tuple(joints))
    assert robot.ik_family == "opw"
    q = np.array([0.0, np.pi / 3, -np.pi / 6, 0.2, 0.5, -0.3])  # a2 cos q2 = d4 sin(q2 + q3)
    T = robot.fk(q)
    assert np.hypot(*robot.link_frames(q)[4][:2, 3]) < 1e-12
    q_current = np.array([0.3, 0.0, 0.0, 0.0, 0.0, 0.0])
    sols = ik_all(robot, T, q_current)
    assert sols
    assert any(abs(wrapped(s.q[0] - 0.3)) < 1e-12 for s in sols)
    for s in sols:
        assert s.singular
        assert np.abs(robot.fk(s.q) - T).max() < 1e-10


# ---------------------------------------------------------------- batch
@pytest.mark.parametrize("name", list(ROBOTS))
def test_batch_equals_single(name):
    robot = ROBOTS[name]
    rng = np.random.default_rng(5)
    Q0 = rng.uniform(robot.lower, robot.upper, size=(120, 6))
    Q0[::7, 4] = 0.0  # aligned wrists
    Ts = list(robot.fk_batch(Q0))
    for _ in range(40):  # arbitrary poses, many out of reach
        R = spatial.matrix_from_quat(rng.normal(size=4), rng.uniform(-1.2, 1.2, 3))
        Ts.append(robot.base @ R @ robot.tool)
    Ts = np.array(Ts)
    for q_current in (None, rng.uniform(robot.lower, robot.upper)):
        Q, valid = ik_batch(robot, Ts, q_current)
        assert Q.shape == (len(Ts), 8, 6)
        assert valid.shape == (len(Ts), 8)
        for n, T in enumerate(Ts):
            sols = ik_all(robot, T, q_current)
            present = ~np.isnan(Q[n]).any(axis=1)
            assert {s.config for s in sols} == {
                c for c, p in zip(CONFIGS, present, strict=True) if p
            }
            for s in sols:
                k = CONFIGS.index(s.config)
                if s.within_limits:
                    np.testing.assert_allclose(Q[n, k], s.q, atol=1e-11)
                else:  # left in (-pi, pi]: +-pi may come out either way by rounding
                    d = np.angle(np.exp(1j * (Q[n, k] - s.q)))
                    np.testing.assert_allclose(d, 0.0, atol=1e-11)
                assert valid[n, k] == s.within_limits


def test_batch_fk_round_trip_and_single_pose():
    rng = np.random.default_rng(9)
    q = rng.uniform(P260.lower, P260.upper, size=(500, 6))
    Ts = P260.fk_batch(q)
    Q, _ = ik_batch(P260, Ts)
    rows, slots = np.nonzero(~np.isnan(Q).any(axis=-1))
    err = np.abs(P260.fk_batch(Q[rows, slots]) - Ts[rows]).max()
    assert err < 1e-10
    Q1, _ = ik_batch(P260, Ts[0])
    assert Q1.shape == (1, 8, 6)
    np.testing.assert_array_equal(Q1[0], Q[0])


# ---------------------------------------------------------------- errors
def test_refuses_robots_without_a_family_and_bad_input():
    joints = list(P560.joints)
    joints[3] = with_dh(joints[3], a=0.05)  # axes 4 and 5 now miss each other by 5 cm
    bent = Robot(name="bent", joints=tuple(joints))
    assert bent.ik_family is None
    with pytest.raises(KinematicsError, match=r"no closed-form IK.*miss each other by 50 mm"):
        ik_all(bent, P560.fk(np.zeros(6)))
    with pytest.raises(KinematicsError, match="no closed-form"):
        bent.ik_closed_form(np.eye(4))
    with pytest.raises(GeometryError, match="4x4"):
        ik_all(P560, np.eye(3))
    with pytest.raises(GeometryError, match="non-finite"):
        ik_all(P560, np.full((4, 4), np.nan))
    skew = P560.fk(np.zeros(6))
    skew[0, 0] = 1.1
    with pytest.raises(GeometryError, match="not rigid"):
        ik_all(P560, skew)
    with pytest.raises(GeometryError, match="not rigid"):
        ik_batch(P560, skew[None])
    with pytest.raises(KinematicsError, match="q_current"):
        ik_all(P560, P560.fk(np.zeros(6)), np.zeros(5))
    with pytest.raises(KinematicsError, match="q_current"):
        ik_batch(P560, P560.fk(np.zeros(6))[None], np.zeros((2, 6)))
    with pytest.raises(KinematicsError, match="6 finite"):
        config_of(P560, np.zeros(5))


def test_changed_base_and_tool_are_seen():
    # the solver caches per robot; robots are immutable, and a robot with other frames is
    # a new robot that must be solved afresh
    robot = P560.with_(name="moving")
    q = P560.pose("qn")
    assert ik_all(robot, robot.fk(q))
    with pytest.raises(dataclasses.FrozenInstanceError):
        robot.base = spatial.translation(0.3, 0.1, 0.0)
    robot = robot.with_(
        base=spatial.translation(0.3, 0.1, 0.0) @ spatial.rot_z(1.0),
        tool=spatial.translation(0.0, 0.0, 0.2),
    )
    T = robot.fk(q)
    sols = ik_all(robot, T)
    assert len(sols) == 8
    for s in sols:
        assert np.abs(robot.fk(s.q) - T).max() < 1e-10


def test_all_solutions_outside_limits_are_reported():
    # a 260 whose joint 5 may only move within 1 deg of 60 deg; a pose at q5 = 0.5 rad
    joints = list(P260.joints)
    lim = (math.radians(59.5), math.radians(60.5))
    joints[4] = replace(joints[4], limits=lim)
    robot = P260.with_(joints=tuple(joints))
    q = np.array([0.1, 0.2, -1.0, 0.3, 0.5, 0.4])
    sols, reason = ik_report(robot, robot.fk(q))
    assert len(sols) == 8
    assert not any(s.within_limits or s.success for s in sols)
    assert "joint limits" in reason
    assert all(re.search(r"joints? [\d, ]*\b5\b", s.reason) for s in sols)


# ---------------------------------------------------------------- the single-pose fast path
# ik_report works in Python floats: it wraps the joints itself (the same operations as
# Robot.wrap_batch) and checks every answer with the family's FK written out in floats.
# These tests hold both against the robot's own numpy paths.
TILTED_TOOL = P260.with_(
    name="puma260_tilted_tool",
    tool=spatial.translation(0.03, -0.02, 0.15) @ spatial.rot_x(0.5) @ spatial.rot_z(0.2),
)
FAST = {**ROBOTS, "tilted_tool": TILTED_TOOL}


def fk_errors_by_robot(robot, q, T):
    """Position (m) and orientation (rad, 2 asin(|dR|_F / sqrt(8))) errors of Robot.fk(q)."""
    D = robot.fk(q) - T
    dr = 2 * math.asin(min(1.0, np.linalg.norm(D[:3, :3]) / math.sqrt(8)))
    return np.linalg.norm(D[:3, 3]), dr


@pytest.mark.parametrize("name", list(FAST))
@settings(max_examples=80, deadline=None)
@given(data=st.data())
def test_single_pose_path_agrees_with_the_batch_path_and_robot_fk(name, data):
    robot = FAST[name]
    q = data.draw(joint_vectors(robot))
    T = robot.fk(q)
    kind = data.draw(st.sampled_from(["none", "near", "turns away"]))
    q_current = None
    if kind == "near":
        q_current = data.draw(joint_vectors(robot))
    elif kind == "turns away":  # far outside the limits: every joint needs its own k
        turns = data.draw(st.lists(st.integers(-3, 3), min_size=6, max_size=6))
        q_current = q + TWO_PI * np.array(turns) + 0.3
    sols, reason = ik_report(robot, T, q_current)
    Q, valid = ik_batch(robot, T, q_current)
    present = [c for c, row in zip(CONFIGS, Q[0], strict=True) if not np.isnan(row).any()]
    assert sorted(s.config for s in sols) == sorted(present)
    for s in sols:
        k = CONFIGS.index(s.config)
        assert s.within_limits == valid[0, k]
        # the two paths compute theta apart (math here, numpy there), to rounding, which
        # moves q4 and q6 by ~1e-16 / |sin theta5| near a singular wrist (both exact: see
        # the FK errors below); and a tie (an angle at +-pi, or half a turn from
        # q_current) may go either way
        tol = np.full(6, 1e-11)
        tol[[3, 5]] += 1e-14 / max(abs(math.sin(s.q[4] + robot.joints[4].dh.offset)), 1e-300)
        assert (np.abs(wrapped(s.q - Q[0, k])) <= tol).all()
        toward = Q[0, k] if q_current is None else wrapped(Q[0, k] - q_current)
        tie = np.abs(np.abs(toward) - np.pi) < 1e-9
        if s.within_limits:
            assert (np.abs(s.q - Q[0, k])[~tie] <= tol[~tie]).all()
        dp, dr = fk_errors_by_robot(robot, s.q, T)
        assert abs(s.position_error - dp) < 1e-12
        assert abs(s.orientation_error - dr) < 1e-12
    if q_current is None:
        keys = [(not s.within_limits, CONFIGS.index(s.config)) for s in sols]
    else:
        keys = [(not s.within_limits, np.abs(s.q - q_current).max()) for s in sols]
    assert keys == sorted(keys)
    assert (reason == "") == any(s.within_limits for s in sols)


@pytest.mark.parametrize("name", list(FAST))
def test_frame0_fk_check_matches_robot_fk_for_arbitrary_q(name):
    # the errors of arbitrary joint vectors against an unrelated target (so they are
    # large) match the errors of Robot.fk, for robots with a base, a tool translation
    # and a tool rotation
    robot = FAST[name]
    S = ik_closed._solver(robot)
    assert S.floats
    rng = np.random.default_rng(17)
    for _ in range(20):
        T = robot.fk(rng.uniform(robot.lower, robot.upper))
        rows = rng.uniform(-7.0, 7.0, size=(8, 6))
        rows[1, :3] = rows[0, :3]  # a wrist twin: shares the arm terms
        _, M = ik_closed._pose(robot, S, T)
        got = S.errors(S.model, rows.tolist(), M, S.t_end)
        for q, (dp, dr) in zip(rows, got, strict=True):
            want_p, want_r = fk_errors_by_robot(robot, q, T)
            assert dp == pytest.approx(want_p, rel=1e-12, abs=1e-13)
            assert dr == pytest.approx(want_r, rel=1e-9, abs=1e-12)


def test_near_rigid_base_errors_come_from_the_robot_chain():
    # a base rotation orthonormal only to ~5e-11 (Robot accepts 1e-9): FK(q) then misses T
    # by ~1e-11, and the reported errors must say so rather than the frame-0 rounding
    base = spatial.translation(0.4, 0.2, 0.1) @ spatial.rot_z(0.3)
    base[0, 1] += 5e-11
    robot = P560.with_(name="near_rigid", base=base)
    assert not ik_closed._solver(robot).floats
    T = robot.fk(robot.pose("qn"))
    sols = ik_all(robot, T)
    assert len(sols) == 8
    for s in sols:
        dp, dr = fk_errors_by_robot(robot, s.q, T)
        assert abs(s.position_error - dp) < 1e-15
        assert abs(s.orientation_error - dr) < 1e-15
    assert max(s.position_error for s in sols) > 1e-12  # the base's error is seen


EDGE_ANGLES = [0.0, -0.0, np.pi, -np.pi, np.nextafter(np.pi, 0), 2 * np.pi, -2 * np.pi, 1e-17]


@pytest.mark.parametrize("robot", [P560, P260], ids=["puma560", "puma260"])
@settings(max_examples=150, deadline=None)
@given(data=st.data())
def test_joint_rows_equal_wrap_batch_to_the_bit(robot, data):
    # the hand-written wrap of the single-pose path against Robot.wrap_batch, including
    # values exactly on the limits, at +-pi and half a turn from q_current (rint ties)
    S = ik_closed._solver(robot)
    signs, offs = np.array(S.signs), np.array(S.offs)
    edges = EDGE_ANGLES + robot.lower.tolist() + robot.upper.tolist()
    angle = st.one_of(st.floats(-13.0, 13.0), st.sampled_from(edges))
    q = np.array(data.draw(st.lists(angle, min_size=6, max_size=6)))
    theta = signs * q - offs  # OPW angles whose joint values are q (to rounding)
    Q = np.pi - np.mod(np.pi - signs * (theta + offs), TWO_PI)  # wrapped to (-pi, pi]
    near = None
    if data.draw(st.booleans()):
        near = np.array(data.draw(st.lists(angle, min_size=6, max_size=6)))
        if data.draw(st.booleans()):  # exactly half a turn away
            near = Q + np.pi * np.array(
                data.draw(st.lists(st.sampled_from([-1, 1]), min_size=6, max_size=6))
            )
    near_t = (None,) * 6 if near is None else tuple((near * (1.0 / TWO_PI)).tolist())
    Qs, rows, flags = rows_of(
        S.signs, S.offs, S.joints, [(0, tuple(theta.tolist()), False)], near_t
    )
    W, ok = robot.wrap_batch(Q, near)
    assert Qs[0] == Q.tolist()
    assert rows[0] == (W if ok.all() else Q).tolist()
    assert flags[0] == (None if ok.all() else tuple(ok.tolist()))
