"""Vendor configurations: each mapping against the vendor's own definition computed here
from the robot's geometry (wrist centre found numerically from FK, the stretched-arm
angle by search), and the configuration written for a target, read back, selecting the
same joint solution among all of the pose's solutions (every closed-form solution and
its whole-turn twins); FANUC's J2/J3 coupling against the ROS-Industrial driver."""

from __future__ import annotations

import math

import numpy as np
import pytest

from workcell.robotprog.configs import (
    abb_confdata,
    fanuc_config,
    fanuc_from_joints,
    fanuc_to_joints,
    kuka_status_turn,
    select,
    solutions,
)
from workcell.robots import get

FAMILIES = ["ur5e", "kuka_kr6_r700", "abb_irb140", "fanuc_lrmate200id", "puma560"]


def wrist_centre(robot, q: np.ndarray) -> np.ndarray:
    """The point of the last link that stays put when joints 4, 5, 6 turn (least squares
    over a few wrist settings): the wrist root point, found from FK alone."""
    rng = np.random.default_rng(0)
    rows, rhs = [], []
    for _ in range(4):
        v = q.copy()
        v[3:] = rng.uniform(-1.5, 1.5, 3)
        F = robot.link_frames(v)[-1]
        # R l + t = c  ->  [R, -I] [l; c] = -t
        rows.append(np.hstack([F[:3, :3], -np.eye(3)]))
        rhs.append(-F[:3, 3])
    sol, *_ = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)
    return sol[3:]


def axis_point(robot, q: np.ndarray, i: int) -> np.ndarray:
    """A point of joint i's axis line (1-based), in the base frame."""
    F = robot.link_frames(q)[i]
    return (F @ np.append(np.asarray(robot.joints[i - 1].axis_point, dtype=float), 1.0))[:3]


def behind_axis1(robot, q: np.ndarray) -> bool:
    """The wrist centre's x in the axis-1 frame (link 1's frame: the base frame turned
    with axis 1) is < 0."""
    F1 = robot.link_frames(q)[1]
    p = wrist_centre(robot, q) - axis_point(robot, q, 1)
    x_dir = F1[:3, :3] @ np.linalg.inv(robot.link_frames(np.zeros(6))[1][:3, :3])[:, 0]
    return float(x_dir @ p) < 0.0


def stretched_a3(robot, q: np.ndarray) -> float:
    """KUKA's phi: the axis-3 angle at which the wrist centre is farthest from axis 2."""
    o2 = axis_point(robot, q, 2)
    grid = np.radians(np.arange(-180.0, 180.0, 0.5))

    def dist(a3: float) -> float:
        v = q.copy()
        v[2] = a3
        return float(np.linalg.norm(wrist_centre(robot, v) - o2))

    best = max(grid, key=dist)
    lo, hi = best - math.radians(0.5), best + math.radians(0.5)
    for _ in range(60):  # golden-section refinement
        m1, m2 = lo + 0.382 * (hi - lo), lo + 0.618 * (hi - lo)
        if dist(m1) > dist(m2):
            hi = m2
        else:
            lo = m1
    return 0.5 * (lo + hi)


def front_of_lower_arm(robot, q: np.ndarray, reference: np.ndarray) -> bool:
    """The wrist centre on the same side of the lower arm (axis 2 -> axis 3) as at
    ``reference`` (a pose with the elbow up and the wrist in front)."""

    def side(v: np.ndarray) -> float:
        F = robot.link_frames(v)
        o2, o3 = axis_point(robot, v, 2), axis_point(robot, v, 3)
        axis2 = F[2][:3, :3] @ np.asarray(robot.joints[1].axis, dtype=float)
        return float(np.cross(o3 - o2, wrist_centre(robot, v) - o2) @ axis2)

    return side(q) * side(reference) > 0


def random_q(robot, rng: np.random.Generator) -> np.ndarray:
    lo, hi = np.maximum(robot.lower, -math.pi), np.minimum(robot.upper, math.pi)
    return rng.uniform(lo + 0.05, hi - 0.05)


def test_kuka_status_and_turn_follow_kukas_definitions() -> None:
    robot = get("kuka_kr6_r700", geometry=False)
    rng = np.random.default_rng(3)
    checked = 0
    for _ in range(60):
        q = random_q(robot, rng)
        if abs(math.sin(q[4])) < 0.05:
            continue
        s, t = kuka_status_turn(robot, q)
        assert bool(s & 1) == behind_axis1(robot, q)  # bit 0: overhead area
        phi = stretched_a3(robot, q)
        d = (q[2] - phi + math.pi) % (2 * math.pi) - math.pi
        if abs(d) > 0.01:
            assert bool(s & 2) == (d >= 0.0)  # bit 1: A3 >= phi
        assert bool(s & 4) == (q[4] < 0.0)  # bit 2: A5 negative
        assert t == sum(1 << i for i in range(6) if q[i] < 0)
        checked += 1
    assert checked > 40
    # KUKA's home {A1 0, A2 -90, A3 90, A4 0, A5 90, A6 0}: S 'B010', T 'B000010'
    assert kuka_status_turn(robot, np.radians([0, -90, 90, 0, 90, 0])) == (2, 2)
    # and its flange points down: A 0, B 90, C 0 (our KRL frame)
    from workcell.robotprog.krl import frame
    from workcell.robotprog.rotations import to_kuka_frame

    assert "A 0.000000,B 90.000000,C 0.000000" in frame(
        to_kuka_frame(robot.fk(np.radians([0, -90, 90, 0, 90, 0])))
    )


def test_abb_confdata_follows_abbs_definitions() -> None:
    robot = get("abb_irb140", geometry=False)
    rng = np.random.default_rng(4)
    home = np.radians([0, 0, 0, 0, 30, 0])
    for _ in range(60):
        q = random_q(robot, rng)
        cf1, cf4, cf6, cfx = abb_confdata(robot, q)
        for cf, a in ((cf1, q[0]), (cf4, q[3]), (cf6, q[5])):
            assert cf * 90 <= math.degrees(a) < (cf + 1) * 90
        assert bool(cfx & 4) == behind_axis1(robot, q)
        assert bool(cfx & 2) == (not front_of_lower_arm(robot, q, home))
        assert bool(cfx & 1) == (q[4] < 0)


def test_fanuc_config_follows_the_flags_and_turns() -> None:
    robot = get("fanuc_lrmate200id", geometry=False)
    rng = np.random.default_rng(5)
    home = np.radians([0, 0, 0, 0, -90, 0])
    assert fanuc_config(robot, home) == ("N U T", 0, 0, 0)  # FANUC's home posture: NUT 000
    for _ in range(60):
        q = random_q(robot, rng)
        if abs(math.sin(q[4])) < 0.05:
            continue
        flags, t4, t5, t6 = fanuc_config(robot, q)
        f, u, t = flags.split()
        assert (t == "B") == behind_axis1(robot, q)
        assert (u == "U") == front_of_lower_arm(robot, q, home)
        assert (f == "N") == (q[4] < 0)  # the LR Mate's J5 sign
        for turn, a in ((t4, q[3]), (t5, q[4]), (t6, q[5])):
            assert turn == math.floor((math.degrees(a) + 180) / 360)


def test_fanuc_j3_is_measured_from_the_horizontal() -> None:
    """ROS-Industrial's fanuc_driver reports J3_ros = J3_fanuc + J23_factor x J2_fanuc with
    J23_factor = 1 for the LR Mate 200iD (robot_interface_streaming_lrmate200id.launch);
    geometrically: with the controller's J3 = 0 the forearm stays level whatever J2."""
    robot = get("fanuc_lrmate200id", geometry=False)
    for j2 in (-40.0, 0.0, 30.0, 80.0):
        j = np.radians([10.0, j2, 0.0, 0.0, -90.0, 0.0])
        q = fanuc_to_joints(robot, j)
        assert q[2] == pytest.approx(j[2] + 1 * j[1])  # the driver's formula
        F = robot.link_frames(q)
        elbow, wrist = F[3][:3, 3], wrist_centre(robot, q)
        # level forearm: the wrist centre 35 mm (the forearm's rise) above the elbow
        assert wrist[2] - elbow[2] == pytest.approx(0.035, abs=1e-9)
        assert np.allclose(fanuc_from_joints(robot, q), j)
    other = get("kuka_kr6_r700", geometry=False)
    q = np.radians([1.0, -50.0, 70.0, 0.0, 20.0, 0.0])
    assert np.allclose(fanuc_from_joints(other, q), q)  # no coupling but on FANUC's arm


def _twins_only_in(a: np.ndarray, b: np.ndarray, joints: set[int]) -> bool:
    d = a - b
    for j in range(6):
        k = d[j] / (2 * math.pi)
        if abs(d[j]) > 1e-7 and (j not in joints or abs(k - round(k)) > 1e-7):
            return False
    return True


def beyond_one_turn(robot) -> set[int]:
    """Joints whose range reaches past +-360 deg: a sign cannot tell their turns apart."""
    return {j for j in range(6) if robot.lower[j] < -2 * math.pi or robot.upper[j] > 2 * math.pi}


MAPPINGS = {
    # vendor: (key of q, joints whose whole turns the format does not name, own family)
    "kuka": (kuka_status_turn, beyond_one_turn, "kuka_kr6_r700"),
    "abb": (abb_confdata, lambda robot: {1, 2, 4}, "abb_irb140"),
    "fanuc": (fanuc_config, lambda robot: {0, 1, 2}, "fanuc_lrmate200id"),
}


@pytest.mark.parametrize("family", FAMILIES)
@pytest.mark.parametrize("vendor", sorted(MAPPINGS))
def test_written_configuration_reads_back_to_the_same_solution(family: str, vendor: str) -> None:
    key, unnamed, own = MAPPINGS[vendor]
    robot = get(family, geometry=False)
    rng = np.random.default_rng(7)
    start = robot.poses["home"]
    for _ in range(25):
        q = random_q(robot, rng)
        if abs(math.sin(q[4])) < 0.05:  # near the aligned wrist q4/q6 are not unique
            continue
        Tb = robot.fk(q)
        wanted = key(robot, q)
        same = [s for s in solutions(robot, Tb) if key(robot, s) == wanted]
        assert any(np.allclose(s, q, atol=1e-7) for s in same)
        for s in same:  # the other matches are whole turns of joints the format leaves open
            assert _twins_only_in(s, q, unnamed(robot))
        got = select(robot, Tb, lambda v: key(robot, v), wanted, start, "target")
        assert np.allclose(robot.fk(got), Tb, atol=1e-9)
        if family == own and vendor == "kuka":  # S and T name every joint's turn
            assert np.allclose(got, q, atol=1e-7)
        if len(same) == 1:
            assert np.allclose(got, q, atol=1e-7)


def test_unreachable_configuration_says_what_there_is() -> None:
    robot = get("kuka_kr6_r700", geometry=False)
    q = np.radians([10, -80, 100, 20, 40, 30])
    from workcell.errors import ProgramError

    with pytest.raises(ProgramError, match=r"XP1: no joint solution .* configuration \(7, 0\)"):
        select(robot, robot.fk(q), lambda v: kuka_status_turn(robot, v), (7, 0), q, "XP1")
