"""Simulator.jog (no time passes, a jog event, limits refused) and the frame and event
listeners the live view hangs on."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from workcell import JointLimitError, ProgramError, Workcell, compile_cell
from workcell.robots import puma260
from workcell.sim import Simulator
from workcell.spatial import translation

START = np.radians([0.0, 0.0, -90.0, 0.0, 90.0, 0.0])
SETTINGS = settings(
    max_examples=20, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)


@functools.cache
def _compiled():
    cell = Workcell("jog")
    cell.add_robot("puma", "puma260", base=translation(0.1, -0.2, 0.3), q=START)
    return cell, compile_cell(cell)


def new_sim(**kw) -> Simulator:
    cell, cc = _compiled()
    return Simulator(cell, compiled=cc, **kw)


LIMITS = np.radians(
    np.array([[-160, 160], [-76, 256], [-214, 34], [-194, 384], [-122, 122], [-267, 267]])
)


@SETTINGS
@given(st.lists(st.floats(0.02, 0.98), min_size=6, max_size=6))
def test_jog_sets_joints_at_once_and_fk_follows(frac):
    """The tool pose after a jog is the robot's FK (an independent chain evaluation)
    placed at the base, the clock does not move, one frame and one jog event are added."""
    q = LIMITS[:, 0] + np.array(frac) * (LIMITS[:, 1] - LIMITS[:, 0])
    sim = new_sim(check_collisions=False)
    frames, t0 = sim.frames, sim.sim_time
    sim.jog("puma", q)
    np.testing.assert_allclose(sim.joints("puma"), q, atol=0)
    expect = translation(0.1, -0.2, 0.3) @ puma260().fk(q)
    np.testing.assert_allclose(sim.tool_pose("puma"), expect, atol=1e-9)
    assert sim.sim_time == t0
    assert sim.frames == frames + 1
    e = sim.events[-1]
    assert (e.kind, e.robot, e.frame) == ("jog", "puma", frames)
    np.testing.assert_allclose(sim.timeline.frame(-1)[2][sim._qadr["puma"]], q)


def test_jog_outside_limits_changes_nothing():
    sim = new_sim()
    before = (sim.joints("puma"), sim.frames, len(sim.events))
    q = START.copy()
    q[1] = np.radians(260.0)  # joint 2 allows -76 ... 256 deg
    with pytest.raises(JointLimitError, match=r"j2|joint 2"):
        sim.jog("puma", q)
    with pytest.raises(ProgramError, match="6 joint values"):
        sim.jog("puma", [0.0, 1.0])
    with pytest.raises(ProgramError, match="no robot"):
        sim.jog("nobody", START)
    np.testing.assert_array_equal(sim.joints("puma"), before[0])
    assert (sim.frames, len(sim.events)) == before[1:]


def test_frame_listeners_see_every_applied_frame_and_undo():
    """Each frame of a command is announced with its timeline index and time while
    ``sim.data`` shows it; an undone command announces the restored last frame."""
    sim = new_sim(dt=0.01)
    seen: list[tuple[int, float, np.ndarray]] = []
    sim.frame_listeners.append(lambda i, t: seen.append((i, t, sim.data.qpos.copy())))
    events = []
    sim.event_listeners.append(events.append)
    q = START + np.radians([20, -10, 15, 0, 10, 30])
    sim.move_joints_absolute("puma", q)
    n = sim.frames
    assert [i for i, _, _ in seen] == list(range(1, n))
    np.testing.assert_allclose([t for _, t, _ in seen], sim.timeline.sim_times(1), atol=0)
    np.testing.assert_allclose(np.array([x for *_, x in seen]), sim.timeline.qpos(1), atol=0)
    assert events == list(sim.events)  # the move's event, as recorded
    seen.clear()

    def stop(i, t):  # an error while frames are applied (as a collision stop would raise)
        if i == n + 3:
            raise ProgramError("stop here")

    sim.frame_listeners.insert(0, stop)
    with pytest.raises(ProgramError, match="stop here"):
        sim.move_joints_absolute("puma", START)
    assert [i for i, _, _ in seen] == [*range(n, n + 3), n - 1]
    assert sim.frames == n
    np.testing.assert_allclose(seen[-1][2], sim.timeline.frame(-1)[2])
    np.testing.assert_allclose(sim.joints("puma"), q)


def test_playback_announces_replayed_frames():
    sim = new_sim(mode="playback", check_collisions=False)
    sim.move_joints_absolute("puma", START + np.radians([10, 0, 0, 0, 0, 0]))
    seen = []
    sim.frame_listeners.append(lambda i, t: seen.append(i))
    sim.play()
    assert seen == [*range(sim.frames), sim.frames - 1]
