"""Closed-form families read from the geometry, against numbers from outside the code.

- Published parameter sets, written out here: the KR 6 R700 sixx and IRB 2400/10 OPW sets
  (Brandstötter et al. 2014 / opw_kinematics), UR's DH tables of the UR3e/5e/10e.
- An independent OPW implementation: the Rust solver py-opw-kinematics (test-only), its
  FK and its IK solutions.
- The ROS-Industrial URDFs that rtb-data ships, through yourdfpy (an independent URDF FK).
- Round trips over thousands of random in-limit joint vectors: the generating q is
  among the closed-form solutions and every solution's FK is the target.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from robot_files import urdf_fk

from workcell import spatial
from workcell.robots import Joint, Robot, get, library
from workcell.robots.axes import axis_lines
from workcell.robots.chain import joints_from_table
from workcell.robots.ik_closed import CONFIGS, config_of, family_model, ik_all, ik_batch, ik_report
from workcell.robots.models import abb_irb140

TWO_PI = 2 * np.pi
CLOSED = [n for n in library()]  # every library robot has a closed-form family


def wrapped(a):
    return (np.asarray(a) + np.pi) % TWO_PI - np.pi


# ---------------------------------------------------------------- published parameters
OPW_PUBLISHED = {
    # a1, a2, b, c1, c2, c3, c4 (m); offsets (rad); signs
    "kuka_kr6_r700": (
        (0.025, -0.035, 0.0, 0.400, 0.315, 0.365, 0.080),
        (0, -np.pi / 2, 0, 0, 0, 0),
        (-1, 1, 1, -1, 1, -1),
    ),
    "abb_irb2400": (
        (0.100, -0.135, 0.0, 0.615, 0.705, 0.755, 0.085),
        (0, 0, -np.pi / 2, 0, 0, 0),
        (1, 1, 1, 1, 1, 1),
    ),
}


@pytest.mark.parametrize("name", list(OPW_PUBLISHED))
def test_opw_parameters_read_back_the_published_set(name):
    params, offsets, signs = OPW_PUBLISHED[name]
    robot = get(name, geometry=False)
    assert robot.ik_family == "opw"
    m = family_model(robot)
    got = [m.parameters()[k] for k in ("a1", "a2", "b", "c1", "c2", "c3", "c4")]
    np.testing.assert_allclose(got, params, atol=1e-12)
    np.testing.assert_allclose(wrapped(np.array(m.offsets) - offsets), 0.0, atol=1e-12)
    assert tuple(m.signs) == signs
    # the tool frame is the OPW flange: c4 along z, nothing else
    np.testing.assert_allclose(m.end, spatial.translation(0, 0, params[6]), atol=1e-12)


def rust_robot(name):
    from py_opw_kinematics import KinematicModel
    from py_opw_kinematics import Robot as RustRobot

    (a1, a2, b, c1, c2, c3, c4), offsets, signs = OPW_PUBLISHED[name]
    km = KinematicModel(
        a1=a1, a2=a2, b=b, c1=c1, c2=c2, c3=c3, c4=c4,
        offsets=tuple(offsets), flip_axes=tuple(s < 0 for s in signs),
    )  # fmt: skip
    return RustRobot(km, degrees=False)


@pytest.mark.parametrize("name", list(OPW_PUBLISHED))
def test_fk_and_ik_agree_with_the_rust_opw_solver(name):
    robot = get(name, geometry=False)
    rust = rust_robot(name)
    rng = np.random.default_rng(1)
    Q = rng.uniform(robot.lower, robot.upper, (200, 6))
    for q in Q:
        T = rust.forward(q).as_matrix()
        np.testing.assert_allclose(robot.fk(q), T, atol=1e-9)
    # every solution the Rust solver returns is one of ours (it filters some out)
    from scipy.spatial.transform import RigidTransform

    seen = 0
    for q in Q[:60]:
        T = robot.fk(q)
        ours = np.array([s.q for s in ik_all(robot, T)])
        for r in rust.inverse(RigidTransform.from_matrix(T)):
            seen += 1
            assert np.abs(wrapped(ours - np.asarray(r))).max(axis=1).min() < 1e-8
    assert seen > 100


UR_DH = {  # UR's published table: d1, a2, a3, d4, d5, d6 (m)
    "ur3e": (0.15185, -0.24355, -0.2132, 0.13105, 0.08535, 0.0921),
    "ur5e": (0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996),
    "ur10e": (0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655),
}


def ur_dh_fk(p, q):
    """UR's standard DH written out: T_i = Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)."""
    d1, a2, a3, d4, d5, d6 = p
    rows = [(d1, 0, np.pi / 2), (0, a2, 0), (0, a3, 0), (d4, 0, np.pi / 2), (d5, 0, -np.pi / 2)]
    rows.append((d6, 0, 0))
    T = np.eye(4)
    for qi, (d, a, al) in zip(q, rows, strict=True):
        c, s, ca, sa = np.cos(qi), np.sin(qi), np.cos(al), np.sin(al)
        T = T @ np.array(
            [[c, -s * ca, s * sa, a * c], [s, c * ca, -c * sa, a * s], [0, sa, ca, d], [0, 0, 0, 1]]
        )
    return T


@pytest.mark.parametrize("name", list(UR_DH))
def test_ur_arms_against_urs_published_dh(name):
    robot = get(name, geometry=False)
    assert robot.ik_family == "ur"
    m = family_model(robot)
    got = [m.parameters()[k] for k in ("d1", "a2", "a3", "d4", "d5", "d6")]
    np.testing.assert_allclose(got, UR_DH[name], atol=1e-12)
    np.testing.assert_allclose(m.offsets, 0.0, atol=1e-12)
    rng = np.random.default_rng(2)
    for q in rng.uniform(robot.lower, robot.upper, (100, 6)):
        np.testing.assert_allclose(robot.fk(q), ur_dh_fk(UR_DH[name], q), atol=1e-12)


# ---------------------------------------------------------------- round trips
@pytest.mark.slow
@pytest.mark.parametrize("name", CLOSED)
def test_thousands_of_random_poses_round_trip(name):
    robot = get(name, geometry=False)
    rng = np.random.default_rng(3)
    Q = rng.uniform(robot.lower, robot.upper, (2000, 6))
    Ts = robot.fk_batch(Q)
    S, valid = ik_batch(robot, Ts)
    have = ~np.isnan(S).any(axis=-1)
    rows, slots = np.nonzero(have)
    err = np.abs(robot.fk_batch(S[rows, slots]) - Ts[rows]).max()
    assert err < 1e-9
    gap = np.abs(wrapped(S - Q[:, None, :])).max(axis=-1)
    gap[~have] = np.inf
    assert (gap.min(axis=1) < 1e-7).all(), "a generating q was not found"
    # the generating q is within its limits: its slot is valid and has q's own letters
    k = gap.argmin(axis=1)
    assert valid[np.arange(len(Q)), k].all()
    for i in range(0, len(Q), 40):  # the single-pose path gives the same solutions
        sols = ik_all(robot, Ts[i])
        assert {s.config for s in sols} == {CONFIGS[j] for j in np.flatnonzero(have[i])}
        assert all(s.position_error < 1e-9 and s.orientation_error < 1e-9 for s in sols)
        assert config_of(robot, Q[i]) == CONFIGS[k[i]]


def straight_q5(robot):
    """The joint-5 value (nearest the middle of its limits) at which axes 4 and 6 are parallel,
    found here by scanning q5 through the robot's axis lines."""
    lo, hi = robot.joints[4].limits
    best = None
    for q5 in np.linspace(-np.pi, np.pi, 3601):
        q = np.zeros(6)
        q[4] = q5
        _, U = axis_lines(robot, q)
        if abs(abs(U[3] @ U[5]) - 1) < 1e-5:
            v = q5 + TWO_PI * round((0.5 * (lo + hi) - q5) / TWO_PI)
            if best is None or abs(v - 0.5 * (lo + hi)) < abs(best - 0.5 * (lo + hi)):
                best = v
    return best


@pytest.mark.parametrize("name", CLOSED)
def test_letters_split_the_eight_solutions_and_n_means_joint5_below_straight(name):
    robot = get(name, geometry=False)
    q5s = straight_q5(robot)
    rng = np.random.default_rng(4)
    full = 0
    for q in rng.uniform(robot.lower, robot.upper, (40, 6)):
        sols = ik_all(robot, robot.fk(q))
        configs = [s.config for s in sols]
        assert len(set(configs)) == len(configs)
        full += len(sols) == 8
        for s in sols:
            if abs(math.sin(s.q[4] - q5s)) > 1e-6:
                assert (s.config[2] == "n") == (math.sin(s.q[4] - q5s) < 0)
    assert full > 10


# ---------------------------------------------------------------- refused chains
def irb140_bent():
    """An IRB 140 whose sixth axis misses the fifth by 20 mm (as the rtb-data IRB 140 file)."""
    r = abb_irb140()
    j = list(r.joints)
    j[5] = Joint("j6", spatial.translation(0.065, 0, 0.02), (1, 0, 0), limits=j[5].limits)
    return r.with_(joints=tuple(j))


def test_non_opw_chains_are_refused_and_fall_back_to_numerical_ik():
    bent = irb140_bent()
    assert bent.ik_family is None
    with pytest.raises(Exception, match=r"axes 5 and 6 miss each other by 20 mm"):
        ik_all(bent, bent.fk(np.zeros(6)))
    rng = np.random.default_rng(5)
    for q in rng.uniform(bent.lower * 0.5, bent.upper * 0.5, (5, 6)):
        T = bent.fk(q)
        sol = bent.ik(T, q + 0.05)
        assert sol.success
        assert np.abs(bent.fk(sol.q) - T).max() < 1e-5
        assert sol.config is None
    far = spatial.translation(3.0, 0, 0)
    assert not bent.ik(far).success  # never a false success
    # a UR-like arm whose axes 1 and 2 miss each other: neither family
    rows = [(0.05, 0.1625, 90, 0), (-0.425, 0, 0, 0), (-0.3922, 0, 0, 0), (0, 0.1333, 90, 0)]
    rows += [(0, 0.0997, -90, 0), (0, 0.0996, 0, 0)]
    shifted = Robot("shifted_ur", joints_from_table(rows, [(-360, 360)] * 6))
    assert shifted.ik_family is None


def test_a_redundant_arm_has_no_closed_form_and_numerical_ik_holds_its_posture():
    # a 7-axis arm from the Panda-like modified DH table (an independent test chain)
    rows = [(0, 0.333, 0, 0), (0, 0, -90, 0), (0, 0.316, 90, 0), (0.0825, 0, 90, 0)]
    rows += [(-0.0825, 0.384, -90, 0), (0, 0, 90, 0), (0.088, 0, 90, 0)]
    lim = [(-166, 166), (-101, 101), (-166, 166), (-176, -4), (-166, 166), (-1, 215), (-166, 166)]
    joints = tuple(
        Joint.from_dh(
            f"j{i + 1}", a=a, d=d, alpha=math.radians(al), convention="modified",
            limits=(math.radians(lo), math.radians(hi)),
        )
        for i, ((a, d, al, _), (lo, hi)) in enumerate(zip(rows, lim, strict=True))
    )  # fmt: skip
    arm = Robot("seven", joints, tool=spatial.translation(0, 0, 0.107))
    assert arm.ik_family is None
    q0 = np.radians([0, -30, 0, -120, 0, 90, 45])
    rng = np.random.default_rng(6)
    for _ in range(5):
        q = q0 + rng.uniform(-0.4, 0.4, 7)
        T = arm.fk(q)
        sol = arm.ik(T, q0)
        assert sol.success
        assert np.abs(arm.fk(sol.q) - T).max() < 1e-5
        # posture preference: among the self-motion's solutions, sol.q is the nearest to
        # q0: the gradient of |q - q0|^2 / 2 has no component along the null space of J
        J = arm.jacobian(sol.q)
        null = np.linalg.svd(J)[2][-1]  # the 7th right singular vector: J null = 0
        assert np.abs(J @ null).max() < 1e-9
        gen, got = abs((q - q0) @ null), abs((sol.q - q0) @ null)
        assert got <= max(0.05 * gen, 4e-3)  # the generating q's component shrinks 20x


# ---------------------------------------------------------------- the ROS-Industrial files
RTB = None


def rtb_xacro() -> Path:
    import rtbdata

    return Path(rtbdata.__file__).parent / "xacro"


KUKA_JOINTS = [f"joint_a{i}" for i in range(1, 7)]


def test_kr16_matches_the_ros_industrial_urdf_through_yourdfpy():
    robot = get("kuka_kr16", geometry=False)
    path = rtb_xacro() / "kuka_description/kuka_kr16/urdf/kr16_2.urdf"
    rng = np.random.default_rng(8)
    Q = rng.uniform(robot.lower, robot.upper, (50, 6))
    np.testing.assert_allclose(robot.fk_batch(Q), urdf_fk(path, KUKA_JOINTS, Q), atol=1e-9)


def test_kr6_r700_matches_the_ros_industrial_xacro_through_xacrodoc_and_yourdfpy(tmp_path):
    from xacrodoc import XacroDoc, packages

    root = rtb_xacro() / "kuka_description"
    packages.update_package_cache(
        {"kuka_kr6_support": str(root / "kuka_kr6"), "kuka_resources": str(root / "kuka_resources")}
    )
    urdf = XacroDoc.from_file(root / "kuka_kr6/urdf/kr6r700sixx.xacro", resolve_packages=False)
    path = tmp_path / "kr6.urdf"
    path.write_text(urdf.to_urdf_string())
    robot = get("kuka_kr6_r700", geometry=False)
    rng = np.random.default_rng(9)
    Q = rng.uniform(robot.lower, robot.upper, (50, 6))
    np.testing.assert_allclose(robot.fk_batch(Q), urdf_fk(path, KUKA_JOINTS, Q), atol=1e-9)


@pytest.mark.parametrize("name", ["ur5e", "kuka_kr6_r700"])
def test_the_float_fk_check_measures_the_robots_own_errors(name):
    """The errors ik_report states come from the family's FK in floats: for arbitrary q
    against an unrelated target (large errors) they equal those of Robot.fk, with a
    mounted base and a tilted tool too."""
    from workcell.robots import ik_closed

    tool = spatial.translation(0.03, -0.02, 0.15) @ spatial.rot_x(0.5)
    robot = get(name, geometry=False)
    robot = robot.with_(
        base=spatial.translation(0.4, -0.2, 0.3) @ spatial.rot_z(0.7), tool=robot.tool @ tool
    )
    S = ik_closed._solver(robot)
    assert S.floats
    rng = np.random.default_rng(12)
    for _ in range(10):
        T = robot.fk(rng.uniform(robot.lower, robot.upper))
        qs = rng.uniform(-7.0, 7.0, size=(8, 6))
        qs[1, :3] = qs[0, :3]  # a wrist twin shares the arm terms
        _, M = ik_closed._pose(robot, S, T)
        for q, (dp, dr) in zip(qs, S.errors(S.model, qs.tolist(), M, S.t_end), strict=True):
            D = robot.fk(q) - T
            assert dp == pytest.approx(np.linalg.norm(D[:3, 3]), rel=1e-12, abs=1e-13)
            want = 2 * math.asin(min(1.0, np.linalg.norm(D[:3, :3]) / math.sqrt(8)))
            assert dr == pytest.approx(want, rel=1e-9, abs=1e-12)


def test_a_stretched_elbow_is_flagged_singular():
    robot = get("kuka_kr6_r700", geometry=False)
    m = family_model(robot)
    gamma = math.atan2(m.a2, m.c3)  # the forearm's angle off the wrist-centre line
    q = np.radians([20.0, -60.0, 0.0, 30.0, 50.0, 10.0])
    q[2] = m.signs[2] * (-gamma + m.offsets[2])  # theta3 = -gamma: upper arm and forearm in line
    T = robot.fk(q)
    sols = ik_all(robot, T)
    # at the stretch the elbow's up and down branches meet: both come out within ~1e-8
    # rad of q (acos near 1), both exact and both flagged
    mine = [s for s in sols if np.abs(wrapped(s.q - q)).max() < 1e-7]
    assert 1 <= len(mine) <= 2
    assert all(s.singular and s.success for s in mine)
    assert not any(s.singular for s in sols if s.config[0] != mine[0].config[0])


def test_a_wrist_inside_the_shoulder_offset_cylinder_is_out_of_reach():
    """A UR wrist point on axis 1 lies inside the cylinder of radius d4 (UR5e: 0.1333 m,
    UR's published DH) that the arm cannot enter: no solution, and the reason says so."""
    T = np.eye(4)
    T[:3, 3] = (0.0, 0.0, 0.4)
    sols, reason = ik_report(get("ur5e", geometry=False), T, None)
    assert sols == []
    assert "inside the cylinder of radius |d4| = 0.1333 m" in reason
