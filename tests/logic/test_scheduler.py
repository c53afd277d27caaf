"""run_programs: programs on one simulated clock, each blocking only itself.

Checked against independent runs: a program run alone through run_programs gives the frames
the same program gives when called directly on a simulator (zones, override, planning and
task commands included); two robots far apart each follow their own direct run; a handshake
starts the waiting robot at the frame the signal is set; a wait with a timeout ends
exactly at the timeout; a deadlock is reported, not hung; the same programs give the same
timeline every time.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest

from workcell import DeadlockError, JointLimitError, ProgramError, SignalTimeout
from workcell.cell import Workcell
from workcell.examples import thesis_pick_place as pp
from workcell.sim import Simulator
from workcell.spatial import translation

DQ = np.radians([25, -10, 15, 0, 20, 0])


def two_robots(*, gap: float = 1.6) -> Workcell:
    cell = Workcell("pair")
    cell.add_robot("a", "ur5e", gripper=True)
    cell.add_robot("b", "ur5e", gripper=True, base=translation(gap, 0, 0))
    cell.add_signal("a_done", False)
    cell.add_signal("b_done", False)
    return cell


def moves_of(robot: str, q0: np.ndarray):
    """A robot program: a zone move, a linear move, an override change, back home."""

    def program(sim) -> None:
        sim.move_joints_absolute(robot, q0 + DQ, zone=0.05)
        T = sim.cell.robots[robot].tool_pose(q0)
        sim.move_linear(robot, translation(0.05, 0.0, -0.05) @ T, speed=0.3, zone=0.02)
        sim.set_override(robot, 0.5)
        sim.move_joints_relative(robot, -DQ / 2)
        sim.move_joints_absolute(robot, q0)

    return program


def frames(sim: Simulator) -> tuple[np.ndarray, np.ndarray]:
    return sim.timeline.sim_times(), sim.timeline.qpos()


def test_one_program_alone_gives_the_frames_of_its_direct_run():
    cell = two_robots()
    direct = Simulator(cell, dt=0.01, profile="jerk")
    q0 = direct.joints("a")
    moves_of("a", q0)(direct)
    run = Simulator(cell, dt=0.01, profile="jerk")
    out = run.run_programs({"a": moves_of("a", q0)})
    assert out["a"]["state"] == "done"
    assert out["a"]["t_end"] == pytest.approx(direct.sim_time)
    t0, q_0 = frames(direct)
    t1, q_1 = frames(run)
    assert t1.shape == t0.shape
    np.testing.assert_allclose(t1, t0, atol=1e-12)
    np.testing.assert_allclose(q_1, q_0, atol=1e-12)
    strip = lambda recs: [{k: v for k, v in r.items() if k != "program_name"} for r in recs]  # noqa: E731
    assert strip(run.cycle_time()["commands"]) == direct.cycle_time()["commands"]
    assert any(r["zone_m"] > 0 for r in run.cycle_time()["commands"])  # the zones blended


def test_two_robots_far_apart_each_follow_their_own_direct_run():
    cell = two_robots()
    ref = Simulator(cell, dt=0.01, profile="jerk")
    qa, qb = ref.joints("a"), ref.joints("b")
    direct = {}
    for r, q0 in (("a", qa), ("b", qb)):
        s = Simulator(cell, dt=0.01, profile="jerk")
        moves_of(r, q0)(s)
        direct[r] = s.trajectory(r)
    both = Simulator(cell, dt=0.01, profile="jerk")
    both.run_programs({"a": moves_of("a", qa), "b": moves_of("b", qb)})
    for r in ("a", "b"):
        t, q = direct[r]
        tb, qb_ = both.trajectory(r)
        # the combined run has both robots' frame times; at a robot's own times its joints
        # are its direct run's, and in between they lie on its path (linear interpolation)
        for c in range(6):
            np.testing.assert_allclose(np.interp(t, tb, qb_[:, c]), q[:, c], atol=1e-9)
    # (times closer than 1e-9 s are one frame time)
    assert both.sim_time == pytest.approx(max(t[-1] for t, _ in direct.values()), abs=1e-9)


def test_a_handshake_starts_the_other_robot_at_the_frame_the_signal_is_set():
    cell = two_robots()
    sim = Simulator(cell, dt=0.01, profile="jerk")
    qa, qb = sim.joints("a"), sim.joints("b")

    def a(s):
        s.move_joints_absolute("a", qa + DQ)
        s.set_signal("a_done", True)

    def b(s):
        s.wait_signal("a_done", True)
        s.move_joints_absolute("b", qb - DQ)

    sim.run_programs({"a": a, "b": b})
    signal = next(e for e in sim.events if e.kind == "signal")
    _t, q = sim.trajectory("b")
    f = signal.frame
    assert np.array_equal(q[f], qb)
    assert not np.array_equal(q[f + 1], qb)
    assert np.all(q[: f + 1] == qb)
    b_move = next(
        r
        for r in sim.cycle_time()["commands"]
        if r["robot"] == "b" and r["command"].startswith("move")
    )
    assert b_move["t_start"] == signal.t
    a_move = next(r for r in sim.cycle_time()["commands"] if r["robot"] == "a")
    assert signal.t == pytest.approx(a_move["t_start"] + a_move["duration_s"], abs=1e-12)
    wait = next(r for r in sim.cycle_time()["commands"] if r["command"] == "wait_signal")
    assert wait["robot"] == "b"
    assert wait["duration_s"] == pytest.approx(signal.t, abs=1e-12)


def test_a_wait_with_a_timeout_in_a_program_ends_exactly_at_the_timeout():
    cell = two_robots()
    sim = Simulator(cell, dt=0.01, profile="jerk")
    qa = sim.joints("a")
    seen = {}

    def a(s):
        s.move_joints_absolute("a", qa + DQ)  # other frames go on meanwhile
        s.wait(0.0123)
        t0 = s.sim_time
        try:
            s.wait_signal("b_done", True, timeout=0.777)
        except SignalTimeout:
            seen["t"] = s.sim_time - t0
        s.move_joints_absolute("a", qa)

    def b(s):
        s.wait(5.0)

    sim.run_programs({"a": a, "b": b})
    assert seen["t"] == pytest.approx(0.777, abs=1e-12)
    waits = [r for r in sim.cycle_time()["commands"] if r["command"] == "wait_signal"]
    assert waits[0]["duration_s"] == pytest.approx(0.777, abs=1e-12)
    assert waits[0]["note"] == "timed out"
    assert sim.sim_time == pytest.approx(5.0)


def test_an_uncaught_timeout_stops_the_run_with_the_programs_name():
    sim = Simulator(two_robots(), dt=0.01)
    with pytest.raises(SignalTimeout, match=r"^program 'a': wait_signal: signal 'b_done'"):
        sim.run_programs({"a": lambda s: s.wait_signal("b_done", timeout=0.5)})
    assert sim.sim_time == pytest.approx(0.5)
    assert sim.events[-1].kind == "error"
    assert sim._block is None  # the simulator is usable again
    sim.wait(0.1)


def _run_in_thread(fn, seconds: float = 120.0):
    box: dict[str, object] = {}

    def target():
        try:
            box["value"] = fn()
        except BaseException as exc:
            box["error"] = exc

    t = threading.Thread(target=target, daemon=True)
    t.start()
    t.join(seconds)
    assert not t.is_alive(), "run_programs hung"
    return box


def test_a_two_robot_deadlock_is_reported_not_hung():
    sim = Simulator(two_robots(), dt=0.01, profile="jerk")
    qa, qb = sim.joints("a"), sim.joints("b")

    def a(s):
        s.move_joints_absolute("a", qa + DQ)
        s.wait_signal("b_done", True)
        s.set_signal("a_done", True)

    def b(s):
        s.move_joints_absolute("b", qb - DQ / 2)
        s.wait_signal("a_done", True)
        s.set_signal("b_done", True)

    box = _run_in_thread(lambda: sim.run_programs({"a": a, "b": b}))
    exc = box.get("error")
    assert isinstance(exc, DeadlockError), box
    text = str(exc)
    assert "'a' waits for signal 'b_done' = true (it is false)" in text
    assert "'b' waits for signal 'a_done' = true (it is false)" in text
    # reported when the last motion ended: nothing could change after it
    ends = [
        r["t_start"] + r["duration_s"]
        for r in sim.cycle_time()["commands"]
        if r["command"].startswith("move")
    ]
    assert sim.sim_time == pytest.approx(max(ends), abs=1e-12)
    assert sim.events[-1].kind == "error"


def test_until_stops_an_endless_controller_and_a_robot_mid_move():
    sim = Simulator(two_robots(), dt=0.01, profile="jerk")
    qa = sim.joints("a")

    def controller(s):
        while True:
            s.wait(0.25)
            s.set_signal("b_done", not s.signal("b_done"))

    def a(s):
        while True:
            s.move_joints_absolute("a", qa + DQ)
            s.move_joints_absolute("a", qa)

    out = sim.run_programs({"a": a, "controller": controller}, until=2.0)
    assert sim.sim_time == pytest.approx(2.0, abs=1e-12)
    assert out["a"]["state"] == out["controller"]["state"] == "stopped"
    assert sim.events[-1].kind == "stop"
    assert "'a' (moving)" in sim.events[-1].detail
    cut = [r for r in sim.cycle_time()["commands"] if r.get("note") == "stopped at until"]
    assert {r["command"] for r in cut} == {"move_joints_absolute", "wait"}
    assert all(r["t_start"] + r["duration_s"] == pytest.approx(2.0) for r in cut)
    flips = [e for e in sim.events if e.kind == "signal"]
    assert [e.t for e in flips] == pytest.approx(np.arange(1, 8) * 0.25)


def test_the_same_programs_give_the_same_timeline_every_run():
    runs = []
    for _ in range(2):
        sim = Simulator(two_robots(), dt=0.01, profile="jerk")
        qa, qb = sim.joints("a"), sim.joints("b")

        def a(s, qa=qa):
            for _ in range(3):
                s.move_joints_absolute("a", qa + DQ, zone=0.03)
                s.set_signal("a_done", True)
                s.move_joints_absolute("a", qa)
                s.wait_signal("b_done", True)
                s.set_signal("b_done", False)

        def b(s, qb=qb):
            for _ in range(3):
                s.wait_signal("a_done", True)
                s.set_signal("a_done", False)
                s.move_joints_relative("b", -DQ)
                s.move_joints_absolute("b", qb)
                s.set_signal("b_done", True)

        sim.run_programs({"a": a, "b": b})
        runs.append(sim)
    assert [(e.t, e.robot, e.kind, e.detail, e.frame) for e in runs[0].events] == [
        (e.t, e.robot, e.kind, e.detail, e.frame) for e in runs[1].events
    ]
    assert np.array_equal(runs[0].timeline.qpos(), runs[1].timeline.qpos())


@pytest.mark.parametrize(
    ("programs", "error", "words"),
    [
        ({}, ProgramError, "non-empty mapping"),
        ({"a": 3}, ProgramError, "callable f\\(sim\\) or a .wcl file"),
        ({"a": "prog.txt"}, ProgramError, ".wcl file"),
        ({"a": "missing.wcl"}, ProgramError, "missing.wcl"),
        ({"b": lambda s: s.move_joints_relative("a", DQ)}, ProgramError, "moves robot 'b' only"),
        ({"ctl": lambda s: s.close_gripper("a")}, ProgramError, "controller program"),
        ({"a": lambda s: s.handover("a", "b", "x")}, ProgramError, "two robots"),
        ({"a": lambda s: s.concurrently()}, ProgramError, "run together already"),
        (
            {"a": lambda s: s.move_joints_relative("a", [10, 0, 0, 0, 0, 0])},
            JointLimitError,
            "program 'a'",
        ),
    ],
)
def test_bad_programs_are_refused_with_the_reason(programs, error, words):
    sim = Simulator(two_robots(), dt=0.01)
    with pytest.raises(error, match=words):
        sim.run_programs(programs)
    assert sim._block is None


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [({"until": -1.0}, "until must be"), ({"until": float("nan")}, "until must be")],
)
def test_bad_run_arguments_change_nothing(kwargs, words):
    sim = Simulator(two_robots(), dt=0.01)
    with pytest.raises(ProgramError, match=words):
        sim.run_programs({"a": lambda s: None}, **kwargs)
    assert sim.frames == 1
    assert len(sim.events) == 0
    with pytest.raises(ProgramError, match="joint-by-joint"):
        Simulator(two_robots(), mode="joint-by-joint").run_programs({"a": lambda s: None})


def test_a_busy_loop_is_stopped():
    sim = Simulator(two_robots(), dt=0.01)

    def spin(s):
        while not s.signal("a_done"):
            pass

    box = _run_in_thread(lambda: sim.run_programs({"ctl": spin}))
    assert isinstance(box.get("error"), ProgramError)
    assert "without simulated time passing" in str(box["error"])


def test_planning_and_task_commands_work_inside_a_program():
    def program(sim):
        sim.set_speed(pp.ROBOT, 0.5)
        sim.pick(pp.ROBOT, pp.CUBE)
        sim.place(pp.ROBOT, pp.CUBE, on="stage_2")
        sim.move_joints_absolute(pp.ROBOT, "home", plan=True)

    direct = Simulator(pp.build(), dt=0.01)
    program(direct)
    run = Simulator(pp.build(), dt=0.01)
    run.run_programs({pp.ROBOT: program})
    np.testing.assert_allclose(run.timeline.sim_times(), direct.timeline.sim_times(), atol=1e-12)
    np.testing.assert_allclose(run.timeline.qpos(), direct.timeline.qpos(), atol=1e-12)
    np.testing.assert_allclose(
        run.part_positions()["cube"], direct.part_positions()["cube"], atol=1e-12
    )


def test_a_wcl_program_runs_beside_a_python_one(tmp_path):
    cell = two_robots()
    (tmp_path / "b.wcl").write_text(
        "signal wait a_done true\n"
        "move joints relative b -20 0 0 0 0 0\n"
        "signal set b_done true\n"
        "signal show b_done\n"
    )
    sim = Simulator(cell, dt=0.01, profile="jerk")
    qa = sim.joints("a")

    def a(s):
        s.move_joints_absolute("a", qa + DQ)
        s.set_signal("a_done", True)
        s.wait_signal("b_done", True)

    out = sim.run_programs({"a": a, "b": tmp_path / "b.wcl"})
    assert out["b"]["state"] == "done"
    assert out["b"]["output"] == ["b_done = true"]
    waits = [r for r in sim.cycle_time()["commands"] if r["command"] == "wait_signal"]
    assert {r["robot"] for r in waits} == {"a", "b"}
    (tmp_path / "bad.wcl").write_text("simulate path\n")
    fresh = Simulator(cell, dt=0.01)
    with pytest.raises(ProgramError, match="cannot run inside a program"):
        fresh.run_programs({"b": tmp_path / "bad.wcl"})


def test_one_program_in_a_live_cell_gives_the_frames_of_its_direct_run():
    """Belts, sources and sensors on every frame: the same frames either way (the timed
    source makes its copies at the frames the robot's motion makes)."""
    from workcell.examples import conveyor as cv

    def motions(sim):
        sim.move_end_effector(cv.ROBOT, cv.tool_down(cv.pick_position() + np.array([0, 0, 0.1])))
        sim.move_linear(
            cv.ROBOT, cv.tool_down(cv.pick_position() + np.array([0, 0, 0.2])), speed=0.3
        )
        sim.wait(6.5)  # the cell alive: a frame every dt, a copy at 6 s
        sim.move_joints_absolute(cv.ROBOT, "home")

    direct = Simulator(cv.build(), dt=0.01, profile="jerk")
    motions(direct)
    run = Simulator(cv.build(), dt=0.01, profile="jerk")
    run.run_programs({cv.ROBOT: motions})
    np.testing.assert_allclose(run.timeline.sim_times(), direct.timeline.sim_times(), atol=1e-12)
    np.testing.assert_allclose(run.timeline.qpos(), direct.timeline.qpos(), atol=1e-12)
    kinds = lambda s: [(e.kind, e.detail) for e in s.events if e.kind in ("signal", "source")]  # noqa: E731
    assert kinds(run) == kinds(direct)
