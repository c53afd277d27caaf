"""Profile "jerk": time-optimal, synchronised, jerk-limited joint moves (ruckig), override."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from motion_helpers import (
    ACCELERATION,
    HOME,
    JERK,
    SPEED,
    derivatives,
    make,
    pose,
    seven_phase_time,
)

from workcell import ProgramError
from workcell.sim.jerk import Limits
from workcell.sim.planning import STILL, plan_move

SETTINGS = settings(max_examples=40, deadline=None)
limit = st.floats(0.2, 20.0)


@SETTINGS
@given(D=st.floats(1e-4, 6.0), v=limit, a=limit, j=st.floats(1.0, 400.0))
def test_one_joint_takes_the_seven_phase_minimum_time(D, v, a, j):
    m = plan_move(
        np.zeros(1), np.array([D]), speed=1.0, dt=0.01, profile="jerk",
        limits=Limits(np.array([v]), np.array([a]), np.array([j])),
    )  # fmt: skip
    assert m.duration == pytest.approx(seven_phase_time(D, v, a, j), rel=1e-9, abs=1e-12)


@pytest.mark.parametrize(("a", "j"), [(5.235987755982989, 52.35987755982989), (2.0, 40.0)])
def test_a_move_on_the_boundary_between_profile_shapes_is_planned(a, j):
    # D = 2 a^3 / j^2: the acceleration just reaches its limit (ruckig 0.19 raised here;
    # found by hypothesis on a Puma 260 under override: 6 deg on joint 3)
    D = 2 * a**3 / j**2
    for q0 in (0.0, -2.409223277464779):
        m = plan_move(
            np.array([q0]), np.array([q0 + D]), speed=1.0, dt=0.01, profile="jerk",
            limits=Limits(np.array([10.0]), np.array([a]), np.array([j])),
        )  # fmt: skip
        assert m.duration == pytest.approx(seven_phase_time(D, 10.0, a, j), rel=1e-6)


@SETTINGS
@given(
    d=st.lists(st.floats(-3.0, 3.0), min_size=6, max_size=6),
    f=st.lists(st.floats(0.2, 1.0), min_size=3, max_size=3),
)
# found by hypothesis: a 1.6e-33 rad move (ruckig: 0 s; the seven-phase time: 7.1e-12 s)
@example(d=[0.0, 0.0, 0.0, 1.6e-33, 0.0, 0.0], f=[1.0, 1.0, 1.0])
@example(d=[0.0, -STILL, 0.0, 0.0, 0.0, 0.0], f=[0.2, 0.2, 0.2])  # still no move
@example(d=[0.0, 0.0, 2 * STILL, 0.0, 0.0, 0.0], f=[0.2, 0.2, 0.2])  # a move
def test_the_joints_finish_together_at_the_slowest_joints_own_minimum_time(d, f):
    # a move whose joints all move at most STILL (1e-12 rad) is no move (sim.planning's
    # doc says why); any other takes the slowest joint's own seven-phase minimum time
    d = np.array(d)
    lim = Limits(SPEED * f[0], ACCELERATION * f[1], JERK * f[2])
    m = plan_move(np.zeros(6), d, speed=1.0, dt=0.01, profile="jerk", limits=lim)
    alone = [
        seven_phase_time(abs(x), v, a, j)
        for x, v, a, j in zip(d, lim.speed, lim.acceleration, lim.jerk, strict=True)
    ]
    if np.abs(d).max() <= 1e-12:
        assert m.duration == 0.0
        assert len(m.t) == 0
        return
    assert m.duration == pytest.approx(max(alone), rel=1e-9, abs=1e-12)
    assert np.array_equal(m.rows_of()[-1], d)  # the last frame is the target exactly


@pytest.mark.parametrize("profile", ["linear", "trapezoid", "quintic", "jerk"])
@pytest.mark.parametrize("mode", ["path", "joint-by-joint"])
def test_a_sub_picoradian_move_is_no_move_in_every_profile_and_mode(profile, mode):
    # the user's step: a move to where the robot is, but for 1.6e-33 rad on one joint
    sim = make(profile=profile)
    sim.set_mode(mode)
    frames, t = sim.frames, sim.sim_time
    sim.move_joints_absolute("puma", HOME + np.array([0, 0, 0, 1.6e-33, 0, 0]))
    sim.move_joints_relative("puma", np.array([0, 1e-12, 0, 0, 0, 0]))
    assert (sim.frames, sim.sim_time) == (frames, t)
    sim.move_joints_relative("puma", np.array([0, 2e-12, 0, 0, 0, 0]))  # one that moves
    assert sim.frames > frames
    assert sim.sim_time > t


def test_a_move_keeps_every_limit_in_every_frame():
    sim = make(profile="jerk", dt=0.002)
    target = HOME + np.radians([60.0, -25.0, 40.0, 90.0, -50.0, 120.0])
    sim.move_joints_absolute("puma", target)
    t, Q = sim.trajectory("puma")
    v, a, j = derivatives(t, Q)
    assert (np.abs(v) / SPEED).max() <= 1.0 + 1e-9
    assert (np.abs(a) / ACCELERATION).max() <= 1.0 + 1e-6
    assert (np.abs(j) / JERK).max() <= 1.0 + 1e-6
    assert (np.abs(a) / ACCELERATION).max() > 0.99  # and uses them: time-optimal
    # synchronised on a straight line in joint space (phase synchronisation)
    frac = (Q - HOME) / (target - HOME)
    assert np.allclose(frac, frac[:, :1], atol=1e-9)
    assert np.allclose(sim.joints("puma"), target, atol=0)


def test_the_report_names_the_limit_that_set_the_time():
    sim = make(profile="jerk")
    sim.move_joints_relative("puma", np.radians([150.0, 0, 0, 0, 0, 0]))  # cruises
    sim.move_joints_relative("puma", np.radians([0, 0, 0, 1.0, 0, 0]))  # a twitch
    recs = sim.cycle_time()["commands"]
    assert [r["limited_by"] for r in recs] == ["j1 speed", "j4 jerk"]
    D = np.radians(150.0)
    assert recs[0]["duration_s"] == pytest.approx(
        seven_phase_time(D, SPEED[0], ACCELERATION[0], JERK[0]), rel=1e-9
    )


@pytest.mark.parametrize("f", [0.5, 0.25])
def test_the_override_scales_the_time_by_one_over_f(f):
    target = HOME + np.radians([40.0, 10.0, -20.0, 30.0, 0.0, 50.0])
    times = []
    for override in (1.0, f):
        sim = make(profile="jerk")
        sim.set_override("puma", override)
        sim.move_joints_absolute("puma", target)
        times.append(sim.sim_time)
    assert times[1] == pytest.approx(times[0] / f, rel=1e-9)


def test_the_override_scales_the_thesis_profiles_too():
    sim = make(profile="linear")
    sim.set_override("puma", 0.5)
    sim.move_joints_relative("puma", np.radians([30.0, 0, 0, 0, 0, 0]))
    assert sim.sim_time == pytest.approx(np.radians(30.0) / (0.3 * 0.5), rel=1e-12)


@pytest.mark.parametrize("bad", [0.0, -0.5, 1.5, float("nan"), "half", True])
def test_a_bad_override_is_refused_and_changes_nothing(bad):
    sim = make(profile="jerk")
    with pytest.raises(ProgramError, match=r"\(0, 1\]"):
        sim.set_override("puma", bad)
    assert len(sim.events) == 0


def test_a_robot_without_limits_cannot_move_under_profile_jerk():
    sim = make("speeds", profile="jerk")  # speed limits only
    before = sim.frames, sim.sim_time
    with pytest.raises(ProgramError, match="joint 1 has no acceleration limit"):
        sim.move_joints_relative("puma", np.radians([10.0, 0, 0, 0, 0, 0]))
    assert (sim.frames, sim.sim_time) == before
    sim.set_profile("trapezoid")  # a thesis profile needs no limits
    sim.move_joints_relative("puma", np.radians([10.0, 0, 0, 0, 0, 0]))
    assert sim.sim_time > 0


def test_set_profile_checks_its_name_and_is_logged():
    sim = make()
    with pytest.raises(ProgramError, match="valid: linear, trapezoid, quintic, jerk"):
        sim.set_profile("smooth")
    sim.set_profile("jerk")
    assert sim.profile == "jerk"
    assert sim.events[-1].kind == "profile"


def test_joint_by_joint_mode_moves_each_joint_in_its_own_minimum_time():
    sim = make(profile="jerk", mode="joint-by-joint", joint_by_joint_clock="sequential")
    d = np.radians([30.0, 0.0, -20.0, 0.0, 0.0, 45.0])
    sim.move_joints_relative("puma", d)
    expected = sum(
        seven_phase_time(abs(x), v, a, j)
        for x, v, a, j in zip(d, SPEED, ACCELERATION, JERK, strict=True)
    )
    assert sim.sim_time == pytest.approx(expected, rel=1e-9)


def test_the_work_budget_refuses_a_move_of_too_many_frames_before_it_runs():
    from workcell import LimitError, limits

    sim = make(profile="jerk", dt=0.001)
    with limits.using(max_frames_per_command=100), pytest.raises(LimitError, match="move_joints"):
        sim.move_joints_relative("puma", np.radians([90.0, 0, 0, 0, 0, 0]))
    assert (sim.frames, sim.sim_time) == (1, 0.0)
    sim.move_end_effector("puma", pose(), config="ru")
    with limits.using(max_frames_per_command=100), pytest.raises(LimitError, match="move_linear"):
        sim.move_linear("puma", pose((0.0, 0.1, 0.0)), speed=0.2)
