"""The kinematic simulator: joint-space commands, the thesis's modes and clocks (§4.4)."""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from workcell import JointLimitError, ProgramError, Workcell, compile_cell
from workcell.cli import main
from workcell.examples import thesis_joints
from workcell.sim import Simulator, Timeline, step_times
from workcell.spatial import rot_z, translation

SETTINGS = settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
START = np.radians([0.0, 0.0, -90.0, 0.0, 90.0, 0.0])


def one_puma(name: str = "puma", gripper: bool = False) -> Workcell:
    cell = Workcell("one")
    cell.add_robot(
        name, "puma260", gripper=gripper, base=translation(0.1, -0.2, 0.3) @ rot_z(0.4), q=START
    )
    return cell


@functools.cache
def _compiled():
    cell = one_puma()
    return cell, compile_cell(cell)


@pytest.fixture
def compiled():
    """The one-Puma cell and its compiled model (compiled once; hidden from hypothesis's repr)."""
    return _Hidden(*_compiled())


class _Hidden(tuple):
    def __new__(cls, *items):
        return super().__new__(cls, items)

    def __repr__(self) -> str:
        return "<one-puma cell>"


def sim_of(compiled, mode="path", dt=0.01, **kw):
    cell, cc = compiled
    return Simulator(cell, mode=mode, dt=dt, compiled=cc, **kw)


def targets(draw_from=st):
    """Random joint targets well inside the Puma 260's limits (rad)."""
    lo = np.radians([-150, -70, -200, -180, -110, -250])
    hi = np.radians([150, 240, 30, 370, 110, 250])
    return st.tuples(*[st.floats(float(a), float(b)) for a, b in zip(lo, hi, strict=False)]).map(
        np.array
    )


speeds = st.floats(0.05, 2.0)
dts = st.sampled_from([0.001, 0.005, 0.01, 0.033, 0.1])


def expected_count(T: float, dt: float) -> int:
    """m full steps plus one remainder step (none when the remainder is zero)."""
    if not T > 0:
        return 0
    m = math.floor(T / dt)
    return max(1, m + (1 if T - m * dt > 1e-9 * dt else 0))


def snapshot(sim: Simulator):
    return (
        sim.joints("puma").tolist(),
        sim.tool_pose("puma").tolist(),
        sim.sim_time,
        sim.wall_time,
        sim.speed("puma"),
        sim.frames,
        sim.timeline.qpos().tolist(),
        sim.timeline.sim_times().tolist(),
        sim.timeline.wall_times().tolist(),
        sim.events,
        sim.data.qpos.tolist(),
        sim.data.site_xpos.tolist(),
    )


# ------------------------------------------------------------------ step_times
def test_step_times_full_steps_plus_remainder():
    t = step_times(0.35, 0.1)
    assert len(t) == 4
    assert t[-1] == 0.35
    assert np.allclose(np.diff(t)[:-1], 0.1)
    assert math.isclose(t[-1] - t[-2], 0.05)
    exact = step_times(0.5, 0.125)  # remainder zero: the last full step is the end
    assert len(exact) == 4
    assert exact[-1] == 0.5
    assert len(step_times(0.0, 0.1)) == 0
    assert step_times(1e-15, 0.1).tolist() == [1e-15]


# ------------------------------------------------------------------ path mode
@SETTINGS
@given(q=targets(), speed=speeds, dt=dts)
def test_path_clock_frames_and_linearity(compiled, q, speed, dt):
    sim = sim_of(compiled, "path", dt)
    sim.set_speed("puma", speed)
    q0 = sim.joints("puma")
    n0 = sim.frames
    sim.move_joints_absolute("puma", q)
    T = float(np.max(np.abs(q - q0))) / speed  # eq. 4.27
    assert abs(sim.sim_time - T) <= 1e-12 * max(1.0, T)
    assert sim.frames - n0 == expected_count(T, dt)
    assert np.array_equal(sim.joints("puma"), q)  # exactly the target
    t, Q = sim.trajectory("puma")
    t, Q = t[n0:], Q[n0:]
    assert t[-1] == sim.sim_time
    full = t[:-1]  # the full steps dT, 2 dT, ...; the last frame ends the remainder at T
    assert np.allclose(full, dt * np.arange(1, len(full) + 1), rtol=0, atol=1e-9)
    assert 0 < t[-1] - (full[-1] if len(full) else 0.0) <= dt * (1 + 1e-9)
    # all joints together, linear in time: q(t) = q0 + (q - q0) t / T
    assert np.allclose(Q, q0 + np.outer(t / T, q - q0), rtol=0, atol=1e-12)
    # the joint that moves most moves at the speed
    if len(t) > 1:
        rates = np.abs(np.diff(Q, axis=0)) / np.diff(t)[:, None]
        assert np.allclose(rates.max(axis=1), speed, rtol=1e-6)
    placement = sim.cell.robots["puma"]
    assert np.allclose(sim.tool_pose("puma"), placement.tool_pose(q), rtol=0, atol=1e-9)


@SETTINGS
@given(dq=targets().map(lambda q: (q - START) * 0.5), speed=speeds)
def test_relative_moves_add_up(compiled, dq, speed):
    sim = sim_of(compiled, "path", 0.01)
    sim.set_speed("puma", speed)
    sim.move_joints_relative("puma", dq)
    sim.move_joints_relative("puma", -dq)
    assert np.allclose(sim.joints("puma"), START, rtol=0, atol=1e-12)
    assert math.isclose(sim.sim_time, 2 * float(np.max(np.abs(dq))) / speed, rel_tol=1e-12)
    placement = sim.cell.robots["puma"]
    assert np.allclose(
        sim.tool_pose("puma"), placement.tool_pose(sim.joints("puma")), rtol=0, atol=1e-9
    )


# ------------------------------------------------------------------ joint-by-joint
@SETTINGS
@given(q=targets(), speed=speeds, dt=dts, clock=st.sampled_from(["thesis", "sequential"]))
def test_joint_by_joint_clock_and_frames(compiled, q, speed, dt, clock):
    sim = sim_of(compiled, "joint-by-joint", dt, joint_by_joint_clock=clock)
    sim.set_speed("puma", speed)
    q0 = sim.joints("puma")
    n0 = sim.frames
    sim.move_joints_absolute("puma", q)
    per_joint = np.abs(q - q0) / speed
    expected = per_joint.sum() if clock == "sequential" else per_joint.max()
    assert abs(sim.sim_time - expected) <= 1e-12 * max(1.0, expected)
    assert sim.frames - n0 == sum(expected_count(T, dt) for T in per_joint)
    assert np.array_equal(sim.joints("puma"), q)
    t, Q = sim.trajectory("puma")
    t, Q = t[n0:], Q[n0:]
    moved = np.diff(np.vstack([q0, Q]), axis=0) != 0
    assert np.all(moved.sum(axis=1) <= 1)  # one joint at a time
    order = [int(np.flatnonzero(r)[0]) for r in moved if r.any()]
    assert order == sorted(order)  # joint 1 first, then 2, ...
    assert np.all(np.diff(np.concatenate([[0.0], t])) >= 0)
    placement = sim.cell.robots["puma"]
    assert np.allclose(sim.tool_pose("puma"), placement.tool_pose(q), rtol=0, atol=1e-9)


# ------------------------------------------------------------------ playback
@SETTINGS
@given(q=targets(), speed=speeds)
def test_playback_gives_the_path_frames(compiled, q, speed):
    runs = {}
    for mode in ("path", "playback"):
        sim = sim_of(compiled, mode, 0.01)
        sim.set_speed("puma", speed)
        sim.move_joints_absolute("puma", q)
        sim.wait(0.25)
        sim.move_joints_relative("puma", START - q)
        runs[mode] = sim
    path, play = runs["path"], runs["playback"]
    assert np.array_equal(path.timeline.qpos(), play.timeline.qpos())
    assert np.array_equal(path.timeline.sim_times(), play.timeline.sim_times())
    assert path.sim_time == play.sim_time
    assert [e[:3] for e in path.events] == [e[:3] for e in play.events]
    before = play.wall_time
    assert play.play(realtime=False) == play.frames
    assert play.wall_time > before
    walls = play.timeline.wall_times()
    assert np.all(np.diff(walls) >= 0)
    assert walls[-1] <= play.wall_time
    assert np.array_equal(play.joints("puma"), path.joints("puma"))
    assert np.allclose(play.joints("puma"), START, rtol=0, atol=1e-12)
    assert np.allclose(play.tool_pose("puma"), path.tool_pose("puma"), rtol=0, atol=0)


def test_realtime_playback_waits(compiled):
    sim = sim_of(compiled, "playback", 0.01, realtime=True)
    sim.set_speed("puma", 1.0)
    sim.move_joints_relative("puma", [0.15, 0, 0, 0, 0, 0])  # 0.15 s simulated
    w = sim.wall_time
    sim.play()
    assert sim.wall_time - w >= 0.15
    assert sim.wall_time - w < 1.0


# ------------------------------------------------------------------ wait, clocks
def test_wait_advances_the_simulated_clock_only(compiled):
    sim = sim_of(compiled)
    q = sim.joints("puma")
    sim.wait(1.5)
    sim.wait(0)
    assert sim.sim_time == 1.5
    assert sim.frames == 2
    assert np.array_equal(sim.joints("puma"), q)
    assert [e.kind for e in sim.events] == ["wait", "wait"]
    assert sim.events[0].robot is None


def test_zero_move_adds_no_frames(compiled):
    sim = sim_of(compiled)
    sim.move_joints_absolute("puma", START)
    assert sim.frames == 1
    assert sim.sim_time == 0.0
    assert sim.events[-1].kind == "move"


def test_initial_frame_and_clocks_on_the_timeline(compiled):
    sim = sim_of(compiled)
    t, w, q = sim.timeline.frame(0)
    assert t == 0.0
    assert w == 0.0
    assert np.array_equal(q, START)
    sim.move_joints_relative("puma", [0.1] * 6)
    assert sim.timeline.frame(-1)[0] == sim.sim_time
    assert 0 < sim.timeline.frame(-1)[1] <= sim.wall_time


def test_two_robots_move_independently():
    cell = one_puma("puma_1", gripper=True)
    cell.add_robot("puma_2", "puma260", base=translation(1.0, 0, 0), q=START)
    sim = Simulator(cell)
    sim.move_joints_relative("puma_2", [0.3, 0, 0, 0, 0, 0])
    assert np.array_equal(sim.joints("puma_1"), START)
    assert np.allclose(sim.joints("puma_2"), START + np.array([0.3, 0, 0, 0, 0, 0]), atol=1e-15)
    for name in ("puma_1", "puma_2"):
        placement = cell.robots[name]
        assert np.allclose(
            sim.tool_pose(name), placement.tool_pose(sim.joints(name)), rtol=0, atol=1e-9
        )


# ------------------------------------------------------------------ errors
def test_limit_error_names_joint_and_range_and_changes_nothing(compiled):
    sim = sim_of(compiled)
    sim.move_joints_relative("puma", [0.2] * 6)
    before = snapshot(sim)
    bad = sim.joints("puma")
    bad[2] = np.radians(60)  # joint 3 of the Puma 260: [-214, 34] deg
    with pytest.raises(JointLimitError, match=r"joint 3.*\[-214, 34\] deg"):
        sim.move_joints_absolute("puma", bad)
    with pytest.raises(JointLimitError, match="joint 2"):
        sim.move_joints_relative("puma", [0, 10, 0, 0, 0, 0])
    assert snapshot(sim) == before


@pytest.mark.parametrize(
    "call",
    [
        lambda s: s.move_joints_absolute("nobody", START),
        lambda s: s.move_joints_relative(3, START),
        lambda s: s.set_speed("nobody", 0.3),
        lambda s: s.set_speed("puma", 0),
        lambda s: s.set_speed("puma", -1),
        lambda s: s.set_speed("puma", float("nan")),
        lambda s: s.set_speed("puma", 1e6),
        lambda s: s.set_speed("puma", True),
        lambda s: s.move_joints_absolute("puma", [0, 0, 0]),
        lambda s: s.move_joints_absolute("puma", [0, 0, 0, 0, 0, float("inf")]),
        lambda s: s.move_joints_relative("puma", "abc"),
        lambda s: s.wait(-1),
        lambda s: s.wait(float("nan")),
        lambda s: s.joints("nobody"),
        lambda s: s.tool_pose("nobody"),
        lambda s: s.play(start=10_000),
    ],
)
def test_bad_commands_raise_program_error_and_change_nothing(compiled, call):
    sim = sim_of(compiled)
    sim.move_joints_relative("puma", [0.2] * 6)
    before = snapshot(sim)
    with pytest.raises(ProgramError) as info:
        call(sim)
    if "robot" in str(info.value) and "no robot" in str(info.value):
        assert "known: puma" in str(info.value)
    assert snapshot(sim) == before


def test_unknown_robot_lists_the_known_ones(compiled):
    sim = sim_of(compiled)
    with pytest.raises(ProgramError, match="known: puma"):
        sim.move_joints_absolute("puma_9", START)


def test_failure_while_applying_frames_rolls_back(compiled, monkeypatch):
    sim = sim_of(compiled)
    sim.move_joints_relative("puma", [0.2] * 6)
    before = snapshot(sim)
    calls = {"n": 0}
    real = Timeline.extend

    def boom(self, *a, **k):
        calls["n"] += 1
        real(self, *a, **k)  # frames written, then a failure (a later collision stop)
        raise RuntimeError("stop")

    monkeypatch.setattr(Timeline, "extend", boom)
    with pytest.raises(RuntimeError):
        sim.move_joints_relative("puma", [-0.1] * 6)
    monkeypatch.undo()
    assert calls["n"] == 1
    assert snapshot(sim) == before


@pytest.mark.parametrize(
    "kwargs",
    [{"mode": "fast"}, {"dt": 0}, {"dt": float("inf")}, {"joint_by_joint_clock": "x"}],
)
def test_bad_simulator_arguments(compiled, kwargs):
    cell, cc = compiled
    with pytest.raises(ProgramError):
        Simulator(cell, compiled=cc, **kwargs)


# ------------------------------------------------------------------ timeline
def test_timeline_chunks_mark_and_truncate():
    tl = Timeline(3, chunk=4)
    Q = np.arange(30.0).reshape(10, 3)
    tl.extend(np.arange(10.0), np.arange(10.0) / 10, Q)
    assert len(tl) == 10
    assert len(tl._blocks) == 3
    assert np.array_equal(tl.qpos(), Q)
    assert np.array_equal(tl.qpos(3, 9), Q[3:9])
    assert np.array_equal(tl.sim_times(5), np.arange(5.0, 10.0))
    mark = tl.mark()
    tl.append(10, 1.0, [1, 2, 3])
    tl.add_event(10, "r", "move", "x")
    tl.truncate(mark)
    assert len(tl) == 10
    assert tl.events == ()
    assert len(tl._blocks) == 3
    tl.truncate(tl.mark()._replace(frames=4))
    assert len(tl) == 4
    assert len(tl._blocks) == 1
    tl.extend([4, 5], [0, 0], [[9, 9, 9], [8, 8, 8]])
    assert tl.frame(-1)[2].tolist() == [8, 8, 8]
    assert tl.frame(4)[0] == 4
    tl.set_wall_times(2, [7, 7, 7, 7])
    assert tl.wall_times().tolist() == [0.0, 0.1, 7, 7, 7, 7]
    with pytest.raises(IndexError):
        tl.frame(6)
    with pytest.raises(ValueError, match="qpos"):
        tl.extend([1], [1], [[1, 2]])
    assert tl.qpos(5, 5).shape == (0, 3)


def test_timeline_spills_to_disk_and_reads_back(tmp_path):
    tl = Timeline(3, chunk=4, memory_limit=2 * 4 * 5 * 8, spill_dir=str(tmp_path))
    ref = Timeline(3, chunk=4, memory_limit=None)
    rng = np.random.default_rng(1)
    for _ in range(7):
        n = int(rng.integers(1, 9))
        args = (rng.random(n), rng.random(n), rng.random((n, 3)))
        tl.extend(*args)
        ref.extend(*args)
    assert tl.spilled_blocks > 0
    assert tl.memory_bytes <= 2 * 4 * 5 * 8 + 4 * 5 * 8
    assert np.array_equal(tl.qpos(), ref.qpos())
    assert np.array_equal(tl.sim_times(3, 17), ref.sim_times(3, 17))
    assert np.array_equal(tl.frame(1)[2], ref.frame(1)[2])
    rows = np.concatenate([r for _, r in tl.iter_blocks(2)])
    assert np.array_equal(rows[:, 2:], ref.qpos(2))
    w = np.arange(len(tl) - 1.0)
    tl.set_wall_times(1, w)
    ref.set_wall_times(1, w)
    assert np.array_equal(tl.wall_times(), ref.wall_times())
    mark = tl.mark()._replace(frames=6)  # inside a spilled block
    tl.truncate(mark)
    ref.truncate(mark)
    tl.extend([9, 9, 9], [9, 9, 9], np.full((3, 3), 9.0))
    ref.extend([9, 9, 9], [9, 9, 9], np.full((3, 3), 9.0))
    assert np.array_equal(tl.qpos(), ref.qpos())
    assert np.array_equal(tl.wall_times(), ref.wall_times())
    tl.close()
    assert len(tl) == 0


def test_simulator_with_spilled_frames_replays_the_same(compiled):
    sims = [sim_of(compiled, "playback", 0.001, memory_limit=lim) for lim in (None, 0)]
    for sim in sims:
        thesis_joints.program(sim)
        sim.play()
    assert sims[1].timeline.spilled_blocks > 0
    assert np.array_equal(sims[0].timeline.qpos(), sims[1].timeline.qpos())
    assert np.array_equal(sims[0].joints("puma"), sims[1].joints("puma"))
    assert np.all(np.diff(sims[1].timeline.wall_times()) >= 0)


# ------------------------------------------------------------------ example 1
@pytest.mark.parametrize("mode", ["path", "joint-by-joint", "playback"])
def test_thesis_example_1_takes_9_89_s(mode):
    sim = thesis_joints.run(mode, dt=0.01)
    t = sim.sim_time
    assert abs(t - 170 * math.pi / 180 / 0.3) < 1e-9
    assert round(t, 2) == 9.89
    assert abs(thesis_joints.expected_sim_time() - t) < 1e-12
    assert np.allclose(sim.joints("puma"), np.radians(thesis_joints.START_DEG), atol=1e-12)
    assert [e.kind for e in sim.events] == ["speed", "move", "move", "move"]
    if mode != "joint-by-joint":
        counts = [expected_count(np.radians(d) / 0.3, 0.01) for d in (70, 40, 60)]
        assert sim.frames == 1 + sum(counts)


def test_demo_joints_json(tmp_path, capsys):
    assert main(["demo", "joints", "--json", "--dt", "0.001", "--mjcf", str(tmp_path)]) == 0
    data = json.loads(capsys.readouterr().out)
    for key in ("sim_time_s", "wall_time_s", "frames", "events", "collisions", "objects", "mjcf"):
        assert key in data
    assert round(data["sim_time_s"], 2) == 9.89
    assert data["collisions"] == 0
    assert data["objects"] == {}
    assert data["frames"] > 9890
    for e in data["events"]:
        assert set(e) == {"t", "robot", "kind", "detail", "frame"}
        assert 0 <= e["frame"] < data["frames"]
    assert (tmp_path / "thesis_joints.xml").exists()
    assert data["mjcf"].endswith(".xml")
    assert main(["demo", "joints", "--json", "--mode", "joint-by-joint"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["mjcf"] is None
    assert round(data["sim_time_s"], 2) == 9.89


def test_demo_joints_human(capsys):
    assert main(["demo", "joints", "--mode", "playback"]) == 0
    out = capsys.readouterr().out
    assert "9.89 s" in out
    assert "move_joints_relative" in out


def test_part_positions_are_centroids_where_grasps_aim():
    """positions, the summary's objects and the grasp point agree: the part's centroid (a
    40 mm cube whose frame is a corner: the corner plus 20 mm on each axis)."""
    from workcell.examples import thesis_pick_place as pp

    sim = Simulator(pp.build(), dt=0.01)
    centre = np.array(pp.CUBE_CORNER) + pp.CUBE_SIZE / 2
    assert sim.part_positions()["cube"] == pytest.approx(centre.tolist(), abs=1e-12)
    assert sim.summary()["objects"]["cube"] == pytest.approx(centre.tolist(), abs=1e-12)
    assert np.allclose(pp.grasp_position(), centre, atol=1e-12)
    assert np.allclose(sim.part_pose("cube")[:3, 3], pp.CUBE_CORNER, atol=1e-12)  # the frame


def test_a_release_event_says_where_the_centroid_was_set_down():
    import re

    from workcell.examples import thesis_pick_place as pp

    sim = pp.run("path", 0.01)
    (release,) = [e for e in sim.events if e.kind == "release"]
    found = re.search(r": centroid \(([^)]*)\) m", release.detail)
    assert found, release.detail
    where = [float(v) for v in found.group(1).split(",")]
    on_stage = [*pp.STAGE_1_CENTRE, pp.STAGE_1_TOP + pp.CUBE_SIZE / 2]  # cube on stage 1
    assert where == pytest.approx(on_stage, abs=1e-4)
    assert sim.part_positions()["cube"] == pytest.approx(on_stage, abs=1e-6)


def test_read_outs_are_calls_and_the_contract_spellings_still_work():
    # read-outs of a run are calls: events(), summary(), cycle_time(), part_positions();
    # `sim.events` (DESIGN's contract: "sim.events gets ... event") is the same tuple
    import warnings

    sim = thesis_joints.run()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # neither spelling warns: both are contracts
        listed = sim.events()
        attribute = sim.events
        summary = sim.summary()
    assert listed == attribute
    assert isinstance(attribute, tuple)
    assert [e.kind for e in attribute] == [e.kind for e in listed]
    assert attribute[-1] == listed[-1]
    assert len(attribute) == len(summary["events"]) == 4  # speed and three moves
    assert [e.to_dict() for e in sim.events()] == summary["events"]
    assert summary["commands"] == sim.cycle_time()["commands"]
    # a new event shows in both spellings at once
    sim.wait(1.0)
    assert sim.events[-1].kind == sim.events()[-1].kind == "wait"
