"""Zones: moves blend through their corners within the zone, faster than stopping."""

from __future__ import annotations

import functools
import itertools

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from motion_helpers import (
    ACCELERATION,
    BASE,
    CENTRE,
    HOME,
    JERK,
    SPEED,
    derivatives,
    limited,
    make,
    pose,
    tool_points,
)

from workcell import UnreachableError, Workcell, WorkcellError, compile_cell
from workcell.sim import Simulator
from workcell.spatial import translation

V = 0.2  # m/s


def seg_distance(P: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = b - a
    s = np.clip((P - a) @ d / (d @ d), 0.0, 1.0)
    return np.linalg.norm(P - (a + np.outer(s, d)), axis=1)


def within_limits(sim: Simulator, first: int = 1, jerk: bool = False, tol: float = 1e-3) -> None:
    t = sim.timeline.sim_times()[first - 1 :]
    Q = sim.timeline.qpos()[first - 1 :, sim._qadr["puma"]]
    v, a, j = derivatives(t, Q)
    assert (np.abs(v) / SPEED).max() <= 1 + tol
    assert (np.abs(a) / ACCELERATION).max() <= 1 + tol
    if jerk:
        assert (np.abs(j) / JERK).max() <= 1 + tol


def corner_run(zone: float, dt: float = 0.005, mode: str = "path"):
    """From pose() 150 mm along +y, then 100 mm along -x (a 90 deg corner)."""
    sim = make(profile="jerk", dt=dt)
    sim.move_end_effector("puma", pose(), config="ru")
    first = sim.frames
    A = sim.tool_pose("puma")
    B = translation(0.0, 0.15, 0.0) @ A
    C = translation(-0.1, 0.0, 0.0) @ B
    sim.move_linear("puma", B, speed=V, zone=zone)
    sim.move_linear("puma", C, speed=V)
    return sim, first, A[:3, 3], B[:3, 3], C[:3, 3]


def test_two_lines_blend_inside_the_zone_and_faster_than_stopping():
    z = 0.03
    stop, *_ = corner_run(0.0)
    sim, first, a, c, b = corner_run(z)
    P = tool_points(sim)[first - 1 :]
    on_a = seg_distance(P, a, c) < 1e-6
    on_b = seg_distance(P, c, b) < 1e-6
    off = ~(on_a | on_b)
    assert off.sum() > 5  # it does leave the corner's two lines
    assert np.linalg.norm(P[off] - c, axis=1).max() <= z + 1e-9  # only inside the zone
    assert np.linalg.norm(P - c, axis=1).min() > 0.2 * z  # and cuts the corner
    assert sim.sim_time < stop.sim_time - 0.1
    speed = np.linalg.norm(np.diff(P, axis=0), axis=1) / np.diff(
        sim.timeline.sim_times()[first - 1 :]
    )
    assert speed.max() <= V * (1 + 1e-6)
    within_limits(sim, first)
    recs = sim.cycle_time()["commands"][-2:]
    assert recs[0]["zone_m"] == pytest.approx(z)
    assert recs[1]["zone_m"] == 0.0
    assert recs[0]["t_start"] + recs[0]["duration_s"] == pytest.approx(recs[1]["t_start"])
    assert recs[1]["t_start"] + recs[1]["duration_s"] == pytest.approx(sim.sim_time)
    # the blended move ends where the tool leaves its line: zone before the corner
    k = int(np.searchsorted(sim.timeline.sim_times()[first - 1 :], recs[1]["t_start"]))
    assert np.linalg.norm(P[k] - c) == pytest.approx(z, abs=V * sim.dt)


def test_a_zone_larger_than_half_a_move_is_clipped_and_reported():
    sim, *_ = corner_run(0.5)
    rec = sim.cycle_time()["commands"][-2]
    assert rec["zone_m"] == pytest.approx(0.05)  # half of the 100 mm second line
    assert "clipped to 50 mm (half of this move)" in rec["note"]


def joint_program(sim: Simulator, zone: float) -> None:
    sim.move_joints_absolute(
        "puma", HOME + np.radians([30.0, 10.0, 0.0, 0.0, -20.0, 0.0]), zone=zone
    )
    sim.move_joints_absolute("puma", HOME + np.radians([30.0, 30.0, 20.0, 0.0, -40.0, 30.0]))


def path_length(P: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum())


def test_joint_moves_blend_jerk_limited_and_rejoin_the_next_move():
    z = 0.02
    stop = make(profile="jerk", dt=0.002)
    joint_program(stop, 0.0)
    sim = make(profile="jerk", dt=0.002)
    joint_program(sim, z)
    assert sim.sim_time < stop.sim_time - 0.05
    within_limits(sim, jerk=True, tol=1e-6)
    Qs, Qb = stop.trajectory("puma")[1], sim.trajectory("puma")[1]
    Ps = tool_points(stop)
    t_corner = stop.cycle_time()["commands"][1]["t_start"]
    corner = int(np.searchsorted(stop.timeline.sim_times(), t_corner))
    k = min(len(Qs), len(Qb))
    n = int(np.argmax(np.any(np.abs(Qs[:k] - Qb[:k]) > 1e-12, axis=1)))  # first different
    m = int(np.argmax(np.any(np.abs(Qs[::-1][:k] - Qb[::-1][:k]) > 1e-12, axis=1)))  # same tail
    assert 1 < n <= corner
    assert m > 10
    # it left the first move at a frame whose tool path to the corner is within the zone
    assert path_length(Ps[n - 1 : corner + 1]) <= z + 1e-9
    # and joined the second move's own frames within the zone after the corner
    assert path_length(Ps[corner : len(Ps) - m + 1]) <= z + 1e-9
    recs = sim.cycle_time()["commands"]
    assert recs[0]["zone_m"] == z
    assert recs[0]["limited_by"]
    assert recs[1]["limited_by"]


def test_joint_and_cartesian_moves_blend_both_ways():
    stop, sim = make(profile="jerk"), make(profile="jerk")
    for s, z in ((stop, 0.0), (sim, 0.02)):
        s.move_end_effector("puma", pose((0.0, 0.0, 0.05)), config="ru", zone=z)
        s.move_linear("puma", pose((0.0, 0.1, 0.0)), speed=V, zone=z)
        s.move_joints_relative("puma", np.radians([-15.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
    assert sim.sim_time < stop.sim_time - 0.1
    within_limits(sim, tol=2e-3)
    assert [r["zone_m"] for r in sim.cycle_time()["commands"]] == [0.02, 0.02, 0.0]


def test_a_line_blends_into_an_arc_within_the_zone():
    z = 0.02
    results = []
    for zone in (0.0, z):
        sim = make(profile="jerk", dt=0.005)
        sim.move_end_effector("puma", pose(), config="ru")
        first = sim.frames
        a = sim.tool_pose("puma")[:3, 3]
        c = a + np.array([0.0, 0.1, 0.0])
        sim.move_linear("puma", translation(*(c - a)) @ sim.tool_pose("puma"), speed=V, zone=zone)
        end = c + np.array([-0.1, 0.1, 0.0])
        via = c + np.array([-0.1 + 0.1 / np.sqrt(2), 0.1 / np.sqrt(2), 0.0])  # at 45 deg
        sim.move_circular("puma", via, translation(*(end - a)) @ pose(), speed=V)
        results.append(sim)
    stop, sim = results
    assert sim.sim_time < stop.sim_time - 0.05
    P = tool_points(sim)[first - 1 :]
    centre = c + np.array([-0.1, 0.0, 0.0])  # quarter circle of radius 0.1 from c to end
    on_line = seg_distance(P, a, c) < 1e-6
    on_arc = (np.abs(np.linalg.norm(P - centre, axis=1) - 0.1) < 1e-6) & (P[:, 1] >= c[1] - 1e-9)
    off = ~(on_line | on_arc)
    assert off.sum() > 3
    assert np.linalg.norm(P[off] - c, axis=1).max() <= z + 1e-9
    within_limits(sim, first)


def test_any_other_command_in_between_makes_the_stop_final():
    stop, sim = make(profile="jerk"), make(profile="jerk")
    for s, between in ((stop, False), (sim, True)):
        s.move_joints_absolute(
            "puma", HOME + np.radians([30.0, 0, 0, 0, 0, 0]), zone=0.05 * between
        )
        if between:
            s.wait(0.0)
        s.move_joints_absolute("puma", HOME + np.radians([30.0, 20.0, 0, 0, 0, 0]))
    assert sim.sim_time == pytest.approx(stop.sim_time, rel=1e-12)
    assert sim.cycle_time()["commands"][0]["zone_m"] == 0.0


def test_read_backs_do_not_end_a_zone_and_a_failed_move_keeps_it():
    stop, sim = make(profile="jerk"), make(profile="jerk")
    for s in (stop, sim):
        s.move_end_effector("puma", pose(), config="ru")
    stop.move_linear("puma", pose((0, 0.1, 0)), speed=V)
    sim.move_linear("puma", pose((0, 0.1, 0)), speed=V, zone=0.03)
    before = sim.frames, len(sim.events), sim.sim_time
    sim.joints("puma"), sim.tool_pose("puma"), sim.summary()
    with pytest.raises(UnreachableError):
        sim.move_linear("puma", pose((0.5, 0.1, 0)), speed=V)
    assert (sim.frames, len(sim.events), sim.sim_time) == before
    for s in (stop, sim):
        s.move_linear("puma", pose((-0.08, 0.1, 0)), speed=V)
    assert sim.sim_time < stop.sim_time - 0.05


def test_a_thesis_profile_joint_move_does_not_blend_and_says_so():
    sim = make()  # profile linear
    sim.move_joints_relative("puma", np.radians([10.0, 0, 0, 0, 0, 0]), zone=0.05)
    sim.move_joints_relative("puma", np.radians([0, 10.0, 0, 0, 0, 0]))
    rec = sim.cycle_time()["commands"][0]
    assert rec["zone_m"] == 0.0
    assert "zones need 'jerk'" in rec["note"]
    assert sim.sim_time == pytest.approx(2 * np.radians(10.0) / 0.3, rel=1e-12)


def test_zones_run_the_same_in_playback():
    ref, *_ = corner_run(0.03, dt=0.01)
    sim = make(profile="jerk", mode="playback")
    sim.move_end_effector("puma", pose(), config="ru")
    B = translation(0.0, 0.15, 0.0) @ sim.tool_pose("puma")
    sim.move_linear("puma", B, speed=V, zone=0.03)
    sim.move_linear("puma", translation(-0.1, 0.0, 0.0) @ B, speed=V)
    assert sim.play() == sim.frames
    assert sim.sim_time == pytest.approx(ref.sim_time, rel=1e-12)
    assert np.allclose(sim.timeline.qpos(), ref.timeline.qpos(), atol=1e-12)


@functools.cache
def _two():
    cell = Workcell("two_limited")
    cell.add_robot("a", limited(), base=BASE, q=HOME)
    cell.add_robot("b", limited(), base=translation(1.2, 0.0, 0.4), q=HOME)
    return cell, compile_cell(cell)


def test_zones_blend_inside_a_concurrent_block():
    cell, cc = _two()
    times = []
    for z in (0.0, 0.02):
        sim = Simulator(cell, compiled=cc, profile="jerk", check_collisions=False)
        with sim.concurrently():
            for r in ("a", "b"):
                sim.move_joints_relative(r, np.radians([15.0, 10.0, 0, 0, 0, 0]), zone=z)
                sim.move_joints_relative(r, np.radians([0.0, 10.0, 10.0, 0, 0, 0]))
        times.append(sim.sim_time)
        recs = sim.cycle_time()["commands"]
        assert [r["zone_m"] for r in recs] == [z, z, 0.0, 0.0]
    assert times[1] < times[0] - 0.05


def test_physics_mode_replays_jerk_limited_blended_programs():
    from workcell.sim.physics import run_physics

    sim = make(profile="jerk", dt=0.02)
    sim.move_end_effector("puma", pose(), config="ru", zone=0.02)
    sim.move_linear("puma", pose((0, 0.12, 0)), speed=V, zone=0.02)
    sim.move_linear("puma", pose((-0.08, 0.12, 0)), speed=V, zone=0.02)
    sim.move_joints_absolute("puma", HOME)
    res = run_physics(sim, settle=0.2)
    track = res.summary()["physics"]["tracking"]["puma"]
    assert track["joint_max_rad"] < 0.01  # the bounds test_physics states for the thesis runs
    assert track["tool_max_m"] < 3e-3
    q_end = res.timeline.frame(-1)[2][sim._qadr["puma"]]
    assert np.abs(q_end - HOME).max() < 0.01
    assert res.summary()["commands"] == sim.summary()["commands"]  # the plan's cycle


def test_linear_moves_blend_inside_a_concurrent_block():
    cell, cc = _two()
    times = []
    for z in (0.0, 0.02):
        sim = Simulator(cell, compiled=cc, profile="jerk", check_collisions=False)
        for r, dx in (("a", 0.0), ("b", 1.2)):
            sim.move_end_effector(r, pose((dx, 0.0, 0.0)), config="ru")
        t0, first = sim.sim_time, sim.frames
        with sim.concurrently():
            for r, dx in (("a", 0.0), ("b", 1.2)):
                sim.move_linear(r, pose((dx, 0.1, 0.0)), speed=V, zone=z)
                sim.move_linear(r, pose((dx - 0.06, 0.1, 0.0)), speed=V)
        times.append(sim.sim_time - t0)
        P = tool_points(sim, "a")[first - 1 :]
        corner = pose((0.0, 0.1, 0.0))[:3, 3]
        off = (seg_distance(P, pose()[:3, 3], corner) > 1e-6) & (
            seg_distance(P, corner, pose((-0.06, 0.1, 0.0))[:3, 3]) > 1e-6
        )
        assert np.linalg.norm(P[off] - corner, axis=1).max(initial=0.0) <= z + 1e-9
        assert bool(off.any()) == (z > 0)
    assert times[1] < times[0] - 0.05


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    moves=st.lists(
        st.tuples(
            st.sampled_from(["joints", "linear", "circular"]),
            st.sampled_from([0.0, 0.01, 0.03, 0.2]),  # zones, 0.2 m is clipped
            st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6),
            st.floats(0.05, 0.4),  # m/s
        ),
        min_size=2,
        max_size=4,
    )
)
def test_random_programs_keep_every_limit_and_account_for_their_time(moves):
    sim = make(profile="jerk", dt=0.004)
    sim.move_end_effector("puma", pose(), config="ru")
    first = sim.frames
    for kind, zone, u, speed in moves:
        off = np.array([0.07, 0.12, 0.08]) * np.array(u[:3])
        try:
            if kind == "joints":
                sim.move_joints_relative("puma", np.radians(20.0) * np.array(u), zone=zone)
            elif kind == "linear":
                sim.move_linear("puma", pose(off), speed=speed, zone=zone)
            else:
                via = CENTRE + 0.5 * off + 0.03 * np.array(u[3:])
                sim.move_circular("puma", via, pose(off), speed=speed, zone=zone)
        except WorkcellError:  # out of reach, collinear: refused, nothing changed
            pass
    if sim.frames > first + 3:
        within_limits(sim, first, tol=1e-6)
    recs = sim.cycle_time()["commands"]
    assert sum(r["duration_s"] for r in recs) == pytest.approx(sim.sim_time, abs=1e-9)
    for a, b in itertools.pairwise(recs):
        assert a["t_start"] + a["duration_s"] == pytest.approx(b["t_start"], abs=1e-9)
