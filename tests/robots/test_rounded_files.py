"""Closed forms of robot files that round their numbers, against numbers from outside the code.

- The ROS Puma 560 URDF that rtb-data ships (pi/2 written as 1.570796325: its axes are
  1.8e-9 rad off), through yourdfpy (an independent URDF FK), against the library
  Puma 560 (Corke's DH table, the project's exact OPW path) rebuilt with the file's
  numbers, joint for joint, and against the library Puma 560 itself (letters).
- Library arms whose joint frames are tilted and shifted by random amounts within the
  tolerated rounding (hypothesis): the robot's own chain FK (``Robot.fk``) of every
  returned q is the target within 1e-10, and the generating q is among the solutions.

The convention difference found between the file and the library Puma 560 (documented
in README's robot-file section): the file's joint values are the library's plus
(0, 0, pi, -pi, 0, 0) (its zero pose has the forearm hanging down and the wrist turned
half a turn; every joint turns the same way); its base frame is the library's; its last
link is the library's frame 6 moved 0.0558 m along z (a flange). Its numbers: d1 0.6718,
d3 0.1501, d4 0.4331 m (Corke: 0.67183, 0.15005, 0.4318) and Corke's 0.0203 m forearm
offset a3 placed on the upper arm instead (an upper arm of hypot(0.4318, 0.0203) m
tilted by atan2(0.0203, 0.4318) = 2.69 deg, the way the library's Puma 260 absorbs its
elbow drop).
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from robot_files import RTB, urdf_fk

from workcell import spatial
from workcell.robots import Robot, from_urdf, get, puma560
from workcell.robots.axes import ANGLE_TOL, OFFSET_TOL
from workcell.robots.chain import joints_from_table
from workcell.robots.ik_closed import config_of, family_model, ik_batch, ik_report
from workcell.robots.ik_refine import REFINE_TOL

PUMA_FILE = "unimation_puma560_description/urdf/puma560_robot.urdf"
needs_rtb = pytest.mark.skipif(RTB is None, reason="rtb-data (a test dependency) is missing")
TWO_PI = 2 * np.pi
FILE_FROM_LIBRARY = np.array([0.0, 0.0, np.pi, -np.pi, 0.0, 0.0])  # q_file = q_library + this
ELBOW_TILT = math.degrees(math.atan2(0.0203, 0.4318))  # 2.69 deg


def wrapped(a):
    return (np.asarray(a) + np.pi) % TWO_PI - np.pi


def library_puma_with_the_files_numbers() -> Robot:
    """Corke's Puma 560 DH structure (the library's) with the numbers the ROS file uses."""
    rows = [
        (0.0, 0.6718, 90.0, 0.0),
        (math.hypot(0.4318, 0.0203), 0.0, 0.0, -ELBOW_TILT),
        (0.0, 0.1501, -90.0, ELBOW_TILT),
        (0.0, 0.4331, 90.0, 0.0),
        (0.0, 0.0, -90.0, 0.0),
        (0.0, 0.0, 0.0, 0.0),
    ]
    return puma560(geometry=False).with_(
        name="puma560_file_numbers",
        joints=joints_from_table(rows, [(-360, 360)] * 6),
        tool=spatial.translation(0, 0, 0.0558),
    )


@pytest.fixture(scope="module")
def ros_puma():
    with warnings.catch_warnings():  # the file's missing visual meshes
        warnings.simplefilter("ignore")
        return from_urdf(RTB / PUMA_FILE, geometry=False)


def file_fk(Q):
    """The file's link7 in its root link1, by yourdfpy (not the project's URDF reader)."""
    return urdf_fk(RTB / PUMA_FILE, [f"j{i}" for i in range(1, 7)], Q, "link7", "link1")


@needs_rtb
def test_the_ros_puma560_file_is_an_opw_arm_refined_on_its_own_chain(ros_puma):
    assert ros_puma.ik_family == "opw"
    m = family_model(ros_puma)
    assert 1e-9 < m.deviation < 1e-7
    assert not m.exact
    rng = np.random.default_rng(11)
    Q = rng.uniform(ros_puma.lower, ros_puma.upper, (60, 6))
    np.testing.assert_allclose(ros_puma.fk_batch(Q), file_fk(Q), atol=1e-12)
    for q, T in zip(Q, file_fk(Q), strict=True):
        sols, reason = ik_report(ros_puma, T)
        assert len(sols) == 8, reason
        for s in sols:
            assert s.method == "closed-form, refined"
            assert s.position_error <= REFINE_TOL
            assert s.orientation_error <= REFINE_TOL
            D = file_fk([s.q])[0] - T  # the residual, measured by yourdfpy
            assert np.linalg.norm(D[:3, 3]) <= 2 * REFINE_TOL
            assert np.abs(D[:3, :3]).max() <= 2 * REFINE_TOL
        assert min(np.abs(wrapped(s.q - q)).max() for s in sols) < 1e-6


@needs_rtb
def test_the_convention_difference_to_the_library_puma(ros_puma):
    lib = library_puma_with_the_files_numbers()
    rng = np.random.default_rng(12)
    Q = rng.uniform(-np.pi, np.pi, (100, 6))
    # the file's FK (yourdfpy) is the library structure's at the mapped joint values,
    # to the file's rounding
    np.testing.assert_allclose(file_fk(Q + FILE_FROM_LIBRARY), lib.fk_batch(Q), atol=1e-8)
    assert family_model(lib).exact


@needs_rtb
def test_its_closed_form_is_the_library_pumas_joint_for_joint(ros_puma):
    """The same letters and, to the file's rounding, the same joint values: the rounding
    moves the tool by up to ~5e-9 (m and rotation entries: the two models' FK differ by
    4.3e-9), so a solution moves by up to that over the Jacobian's smallest singular
    value sigma; 2e-8 / sigma is asserted. Near a singularity (sigma below 1e-3) that
    linear bound no longer holds (a fold's branches split by ~sqrt of the rounding) and
    only the letters are compared."""
    lib = library_puma_with_the_files_numbers()

    def sigma(q):
        return np.linalg.svd(lib.jacobian(q), compute_uv=False)[-1]

    def conditioned(q):
        return sigma(q) > 1e-3

    rng = np.random.default_rng(13)
    compared = 0
    for q in rng.uniform(-np.pi, np.pi, (200, 6)):
        T = lib.fk(q)
        mine = {s.config: s.q for s in ros_puma.ik_closed_form(T)}
        ref = {s.config: s.q for s in lib.ik_closed_form(T)}
        assert set(mine) == set(ref)
        for k, q_ref in ref.items():
            if conditioned(q_ref):
                compared += 1
                D = np.abs(wrapped(mine[k] - FILE_FROM_LIBRARY - q_ref)).max()
                assert 2e-8 / sigma(q_ref) > D, k
    assert compared > 1400  # of 1600
    # ik_batch, slot for slot
    Q = rng.uniform(-np.pi, np.pi, (300, 6))
    S_file, _ = ik_batch(ros_puma, lib.fk_batch(Q))
    S_lib, _ = ik_batch(lib, lib.fk_batch(Q))
    assert (np.isnan(S_file) == np.isnan(S_lib)).all()
    ok = ~np.isnan(S_lib[..., 0])
    sig = np.array([sigma(q) for q in S_lib[ok]])
    D = np.abs(wrapped(S_file[ok] - FILE_FROM_LIBRARY - S_lib[ok])).max(axis=1)
    good = sig > 1e-3
    assert good.sum() > 0.85 * len(good)
    assert (D[good] < 2e-8 / sig[good]).all()


@needs_rtb
def test_its_letters_are_the_library_puma560s(ros_puma):
    """Corke's Puma 560 itself: the same joint values have the same letters, except where
    the elbow is within the 2.69 deg the file moved (the boundary of u and d moves)."""
    lib = puma560(geometry=False)
    rng = np.random.default_rng(14)
    Q = rng.uniform(lib.lower, lib.upper, (1500, 6))
    differ = 0
    for q in Q:
        a, b = config_of(lib, q), config_of(ros_puma, q + FILE_FROM_LIBRARY)
        near_boundary = abs(math.degrees(q[2]) + 90.0) <= ELBOW_TILT
        if a != b:
            differ += 1
            assert near_boundary, (a, b, np.degrees(q))
            assert a[0] + a[2] == b[0] + b[2]  # only the elbow letter
        elif not near_boundary:
            assert a == b
    assert differ < 0.05 * len(Q)


@needs_rtb
def test_a_singular_wrist_of_the_file_still_has_its_solutions(ros_puma):
    for q in ([0.3, 0.2, -0.4, 0.5, 0.0, 0.2], np.zeros(6), [0.1, -0.3, 0.4, 1.0, 1e-7, -0.5]):
        q = np.array(q)
        T = ros_puma.fk(q)
        sols, _ = ik_report(ros_puma, T)
        # at a straight wrist n and f meet: the arm and elbow letters say which is q's
        mine = [s for s in sols if s.config[:2] == config_of(ros_puma, q)[:2]]
        assert mine
        assert all(s.singular for s in mine)
        for s in sols:
            D = ros_puma.fk(s.q) - T
            assert np.linalg.norm(D[:3, 3]) <= REFINE_TOL + 1e-15
            assert np.abs(D[:3, :3]).max() <= REFINE_TOL


# ---------------------------------------------------------------- rounded library arms
def rounded(robot: Robot, tilts, shifts) -> Robot:
    """The robot with each joint's origin tilted (rad, about x then y) and shifted (m)."""
    joints = []
    for j, (ax, ay), s in zip(robot.joints, tilts, shifts, strict=True):
        origin = j.origin @ spatial.translation(*s) @ spatial.rot_x(ax) @ spatial.rot_y(ay)
        joints.append(dataclasses.replace(j, origin=origin))
    return robot.with_(name=f"{robot.name}_rounded", joints=tuple(joints))


@settings(max_examples=12, deadline=None)
@given(
    name=st.sampled_from(["puma560", "kuka_kr6_r700", "ur5e", "abb_irb140"]),
    seed=st.integers(0, 2**31),
    scale=st.floats(0.05, 0.9),
)
def test_arms_within_the_rounding_keep_their_family_and_exact_solutions(name, seed, scale):
    exact = get(name, geometry=False)
    rng = np.random.default_rng(seed)
    # tilts up to scale * ANGLE_TOL / 2 per axis (two axes tilt by their sum), shifts
    # up to scale * OFFSET_TOL / 2 per coordinate
    tilts = rng.uniform(-1, 1, (6, 2)) * scale * ANGLE_TOL / 4
    shifts = rng.uniform(-1, 1, (6, 3)) * scale * OFFSET_TOL / 4
    robot = rounded(exact, tilts, shifts)
    assert robot.ik_family == exact.ik_family
    Q = rng.uniform(robot.lower, robot.upper, (25, 6))
    # near a singularity the rounding itself moves the solutions (a fold's two branches
    # split by ~sqrt of it): there only "exact or absent" is checked
    conditioned = [np.linalg.svd(robot.jacobian(q), compute_uv=False)[-1] > 1e-3 for q in Q]
    Ts = robot.fk_batch(Q)
    for q, T, good in zip(Q, Ts, conditioned, strict=True):
        sols = robot.ik_closed_form(T, q)
        if good:  # the generating q, nearest first
            assert sols
            assert np.abs(wrapped(sols[0].q - q)).max() < 1e-5
        for s in sols:
            D = robot.fk(s.q) - T
            assert np.linalg.norm(D[:3, 3]) <= 1.01 * REFINE_TOL
            assert np.abs(D[:3, :3]).max() <= 1.01 * REFINE_TOL
    S, _ = ik_batch(robot, Ts)
    ok = ~np.isnan(S[..., 0])
    D = robot.fk_batch(S[ok]) - Ts[np.nonzero(ok)[0]]
    assert np.linalg.norm(D[:, :3, 3], axis=1).max() <= 1.01 * REFINE_TOL
    assert np.abs(D[:, :3, :3]).max() <= 1.01 * REFINE_TOL
    gap = np.nan_to_num(np.abs(wrapped(S - Q[:, None])).max(axis=-1), nan=np.inf)
    assert (gap.min(axis=1)[conditioned] < 1e-5).all()  # the generating q is in the batch too


def test_arms_beyond_the_rounding_have_no_family_and_say_why():
    exact = get("kuka_kr6_r700", geometry=False)
    j = list(exact.joints)
    j[3] = dataclasses.replace(j[3], origin=j[3].origin @ spatial.rot_z(1e-4))  # 100x
    robot = exact.with_(joints=tuple(j))
    assert robot.ik_family is None
    with pytest.raises(Exception, match=r"axes 3 and 4 are not perpendicular \(0\.0001 rad off\)"):
        robot.ik_closed_form(robot.fk(np.zeros(6)))
    shifts = np.zeros((6, 3))
    shifts[4, 1] = 1e-5  # axis 5 misses axis 4 by 10 um
    assert rounded(exact, np.zeros((6, 2)), shifts).ik_family is None


def test_batched_pose_jacobians_are_the_finite_differences_of_fk():
    from workcell.robots.ik_refine import pose_jacobians

    robot = get("kuka_kr6_r700", geometry=False)
    Q = np.random.default_rng(15).uniform(robot.lower, robot.upper, (10, 6))
    T, J = pose_jacobians(robot, Q)
    np.testing.assert_allclose(T, robot.fk_batch(Q), atol=1e-14)
    h = 1e-6
    for q, Jq in zip(Q, J, strict=True):
        for i in range(6):
            dq = np.zeros(6)
            dq[i] = h
            Tp, Tm = robot.fk(q + dq), robot.fk(q - dq)
            np.testing.assert_allclose(Jq[:3, i], (Tp[:3, 3] - Tm[:3, 3]) / (2 * h), atol=1e-8)
            W = (Tp[:3, :3] - Tm[:3, :3]) / (2 * h) @ robot.fk(q)[:3, :3].T  # [w]x
            np.testing.assert_allclose(Jq[3:, i], [W[2, 1], W[0, 2], W[1, 0]], atol=1e-8)
