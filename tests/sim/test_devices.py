"""Devices on every frame (kinematic and playback mode), against numbers worked out by hand:
a belt carries a part exactly speed x time, a beam breaks after distance / speed, a
proximity ray measures the height of a box's top, sources make copies at k x every, sinks
count what enters them; an undone command takes the devices' state back."""

from __future__ import annotations

import math

import numpy as np
import pytest
from belt_cells import BOX, END, TOP, belt_cell
from hypothesis import given, settings
from hypothesis import strategies as st

from workcell import DeadlockError, ProgramError, SignalTimeout, solids
from workcell.cell import Workcell
from workcell.sim import Simulator
from workcell.spatial import translation


def front(sim: Simulator, part: str = "box") -> float:
    """x of the part's front face (m)."""
    return sim.part_positions()[part][0] + BOX / 2


@settings(max_examples=12, deadline=None)
@given(
    speed=st.floats(0.05, 1.0),
    distance=st.floats(0.05, 1.5),
    dt=st.sampled_from([0.002, 0.01, 0.03]),
    mode=st.sampled_from(["path", "playback"]),
)
def test_a_part_reaches_a_beam_after_distance_over_speed(speed, distance, dt, mode):
    box_x = 0.2
    beam = box_x + BOX + distance
    sim = Simulator(belt_cell(speed=speed, box_x=box_x, beam_x=beam), mode=mode, dt=dt)
    sim.wait_signal("beam", True)
    # the first frame at or after distance / speed (frames every dt from t = 0)
    assert distance / speed - 1e-9 <= sim.sim_time <= distance / speed + dt + 1e-9
    # the part moved exactly speed x time
    assert front(sim) == pytest.approx(box_x + BOX + speed * sim.sim_time, abs=1e-9)
    beam_events = [e for e in sim.events if e.kind == "signal"]
    assert beam_events[-1].t == sim.sim_time
    assert beam_events[-1].data["value"] is True


@pytest.mark.parametrize("dt", [0.01, 0.037])
def test_a_belt_stopped_by_its_sensor_leaves_the_part_at_the_beam(dt):
    speed, beam = 0.3, 1.234
    sim = Simulator(belt_cell(speed=speed, beam_x=beam, run_signal="run"), dt=dt)
    sim.wait_signal("beam", True)
    sim.set_signal("run", False)
    sim.wait(2.0)
    assert beam <= front(sim) <= beam + speed * dt + 1e-9
    stopped = front(sim)
    sim.wait(1.0)
    assert front(sim) == stopped  # a stopped belt carries nothing
    sim.set_signal("run", True)
    sim.wait(1.0)
    assert front(sim) == pytest.approx(stopped + speed * 1.0, abs=1e-9)


def test_the_end_stop_holds_the_part_at_the_belts_end():
    sim = Simulator(belt_cell(speed=1.0, box_x=2.0), dt=0.01)
    sim.wait(5.0)  # 0.9 m to go at 1 m/s
    assert front(sim) == pytest.approx(END, abs=1e-8)  # (MuJoCo keeps meshes in float32)
    assert sim.summary()["collisions"] == 0  # touching the stop, not in it
    assert not sim._logic.alive()  # nothing moves any more


def test_a_part_off_the_belt_or_above_it_is_not_carried():
    cell = belt_cell(speed=0.5)
    solids.cube(cell.model, "c2", size=0.05)
    cell.add_movable("beside", "c2", translation(1.0, 0.5, TOP), density=500.0)  # off the belt
    cell.add_movable("above", "c2", translation(1.0, -0.025, TOP + 0.01), density=500.0)
    sim = Simulator(cell, dt=0.01)
    start = sim.part_positions()
    sim.wait(1.0)
    now = sim.part_positions()
    assert now["beside"] == start["beside"]
    assert now["above"] == start["above"]
    assert now["box"][0] == pytest.approx(start["box"][0] + 0.5, abs=1e-12)


def test_wait_without_devices_makes_one_frame_and_with_a_moving_belt_one_per_dt():
    cell = Workcell("empty")
    sim = Simulator(cell, dt=0.01)
    sim.wait(1.0)
    assert sim.frames == 2
    belt = Simulator(belt_cell(), dt=0.01)
    belt.wait(1.0)
    assert belt.frames == 1 + 100
    assert np.allclose(np.diff(belt.timeline.sim_times()), 0.01)


def test_sources_make_copies_every_n_seconds_and_sinks_count_them():
    cell = Workcell("flow")
    solids.cube(cell.model, "cube", size=BOX)
    cell.add_movable("box", "cube", translation(0, 2, 0), density=500.0)
    cell.add_conveyor("belt", start=(0, 0, TOP), end=(3, 0, TOP), width=0.3, speed=0.5)
    cell.add_source("feeder", "box", at=(0.1, -BOX / 2, TOP), every=1.5, count=4)
    cell.add_sink("out", center=(2.0, 0, TOP + BOX / 2), size=(0.2, 0.4, 0.4))
    sim = Simulator(cell, dt=0.013)  # source times fall between frames: frames are added
    assert list(sim.part_positions()) == ["box_1"]  # the pattern stays out; copy 1 at t = 0
    sim.wait(10.0)
    made = [e for e in sim.events if e.kind == "source"]
    assert [e.t for e in made] == pytest.approx([0.0, 1.5, 3.0, 4.5], abs=1e-12)
    assert [e.data["part"] for e in made] == ["box_1", "box_2", "box_3", "box_4"]
    # a centroid enters the sink when it is 0.1 m before its centre: 1.75 m from 0.15 m
    sunk = [e for e in sim.events if e.kind == "sink"]
    reach = (1.9 - 0.15) / 0.5
    for e, t0 in zip(sunk, [0.0, 1.5, 3.0, 4.5], strict=True):
        assert t0 + reach - 1e-9 <= e.t <= t0 + reach + 0.013 + 1e-9
    assert sim.part_positions() == {}
    tp = sim.throughput()
    assert tp["sinks"]["out"]["parts"] == 4
    assert tp["sinks"]["out"]["parts_per_hour"] == pytest.approx(4 * 3600 / sim.sim_time)


def test_a_source_on_a_signal_makes_a_copy_at_each_rising_edge():
    cell = Workcell("edges")
    solids.cube(cell.model, "cube", size=BOX)
    cell.add_movable("box", "cube", translation(0, 2, 0), density=500.0)
    cell.add_signal("drop", False)
    cell.add_source("feeder", "box", at=(0, 0, 0), on_signal="drop", count=2)
    sim = Simulator(cell, dt=0.01)
    assert sim.part_positions() == {}
    for v in (True, True, False, True, False, True):
        sim.set_signal("drop", v)
        sim.wait(0.1)
    made = [e.t for e in sim.events if e.kind == "source"]
    assert made == pytest.approx([0.0, 0.3])  # edges at 0 and 0.3 s; the one at 0.5 finds none left
    assert any(e.kind == "warning" and "its count 2" in e.detail for e in sim.events)


def test_a_proximity_ray_measures_the_distance_to_a_box_top():
    cell = belt_cell(speed=0.2, box_x=0.2)
    # a ray straight down at x = 0.5: the belt top (0.5 m) until the box passes under it
    cell.add_sensor(
        "height", "proximity", origin=(0.5, 0, 1.5), direction=(0, 0, -1), range=2.0, threshold=0.95
    )
    sim = Simulator(cell, dt=0.01)
    assert sim.distance("height") == pytest.approx(1.5 - TOP, abs=1e-9)
    assert sim.signal("height") is False
    sim.wait_signal("height", True)  # the box's front face reaches x = 0.5: 0.2 m at 0.2 m/s
    assert sim.sim_time == pytest.approx(1.0, abs=0.01 + 1e-9)
    assert sim.distance("height") == pytest.approx(1.5 - TOP - BOX, abs=1e-8)  # float32 mesh
    with pytest.raises(ProgramError, match="proximity sensors: height"):
        sim.distance("box")


def test_a_presence_box_sees_centroids_and_a_beam_ignores_robots_unless_asked():
    cell = belt_cell(speed=0.0001, box_x=0.2)
    cell.add_sensor("zone", "presence", center=(0.25, 0, TOP + 0.05), size=(0.2, 0.2, 0.2))
    cell.add_sensor("empty", "presence", center=(0.6, 0, TOP + 0.05), size=(0.2, 0.2, 0.2))
    cell.add_robot("puma", "puma260", base=translation(-0.6, 0, 0))
    # beams through the robot's upper arm at its initial pose
    sim0 = Simulator(cell)
    p = sim0.data.xpos[sim0.model.body("puma.link2").id]
    for name, robots in (("blind", False), ("sees", True)):
        cell.add_sensor(
            name,
            "beam",
            start=p + np.array([0, -0.3, 0]),
            end=p + np.array([0, 0.3, 0]),
            robots=robots,
        )
    sim = Simulator(cell)
    assert sim.signals()["zone"] is True
    assert sim.signals()["empty"] is False
    assert sim.signal("blind") is False
    assert sim.signal("sees") is True


def test_a_wait_for_what_nothing_can_change_is_refused_and_undone():
    sim = Simulator(belt_cell(speed=1.0, box_x=2.0, beam_x=0.5, run_signal="run"), dt=0.01)
    before = (sim.frames, sim.part_positions(), sim.signals())
    with pytest.raises(DeadlockError, match="nothing can change"):
        sim.wait_signal("beam", True)  # the box goes to the end stop, away from the beam
    assert (sim.frames, sim.part_positions(), sim.signals()) == before
    assert sim._logic.t_prev == sim.sim_time == 0.0


def test_a_wait_with_a_timeout_ends_exactly_at_the_timeout():
    sim = Simulator(belt_cell(speed=0.2, beam_x=2.5), dt=0.01)
    sim.wait(0.123)
    with pytest.raises(SignalTimeout, match=r"'beam' did not become true within 1\.2345 s"):
        sim.wait_signal("beam", True, timeout=1.2345)
    assert sim.sim_time == 0.123 + 1.2345  # the time passed
    last = sim.events[-1]
    assert last.kind == "wait_signal"
    assert last.data["duration_s"] == pytest.approx(1.2345, abs=1e-12)
    assert last.data["note"] == "timed out"


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda s: s.set_signal("nope", True), "signals: run, beam"),
        (lambda s: s.set_signal("run", 1), "bool signal takes true or false"),
        (lambda s: s.wait_signal("run", "yes"), "bool signal takes"),
        (lambda s: s.wait_signal("run", True, timeout=-1), "timeout"),
        (lambda s: s.wait_signal("run", True, timeout=math.inf), "timeout"),
        (lambda s: s.signal(3), "no signal 3"),
    ],
)
def test_bad_signal_commands_are_refused_and_change_nothing(call, words):
    sim = Simulator(belt_cell(beam_x=1.0, run_signal="run"), dt=0.01)
    before = (sim.frames, len(sim.events), sim.signals())
    with pytest.raises(ProgramError, match=words):
        call(sim)
    assert (sim.frames, len(sim.events), sim.signals()) == before


def test_signal_kinds_are_kept():
    cell = Workcell("kinds")
    cell.add_signal("n", 2)
    cell.add_signal("x", 0.5)
    sim = Simulator(cell)
    sim.set_signal("n", 7)
    sim.set_signal("x", 3)  # an int is a number
    assert sim.signals() == {"n": 7, "x": 3.0}
    assert type(sim.signal("x")) is float
    with pytest.raises(ProgramError, match="whole number"):
        sim.set_signal("n", 2.5)
    with pytest.raises(ProgramError, match="has no signals"):
        Simulator(Workcell("none")).signal("n")


def test_signal_events_carry_name_value_and_time_for_export():
    sim = Simulator(belt_cell(run_signal="run"), dt=0.01)
    sim.wait(0.5)
    sim.set_signal("run", False)
    sim.set_signal("run", False)  # unchanged: still an instruction, still an event
    sets = [e for e in sim.events if e.kind == "signal"]
    assert [(e.t, e.data["signal"], e.data["value"], e.data["command"]) for e in sets] == [
        (0.5, "run", False, "set_signal"),
        (0.5, "run", False, "set_signal"),
    ]
    assert [r["command"] for r in sim.cycle_time()["commands"]] == [
        "wait",
        "set_signal",
        "set_signal",
    ]


def test_a_part_is_picked_off_a_running_belt_where_it_is_at_that_frame():
    from workcell.examples import conveyor as cv
    from workcell.sim.grasp import tool_down

    sim = Simulator(cv.build(), dt=0.01, profile="jerk")
    pick = cv.pick_position()
    sim.move_end_effector(cv.ROBOT, tool_down(pick))  # open fingers across the belt
    sim.wait_signal("beam", True)  # the belt keeps running: nothing stops it here
    at_grasp = np.array(sim.part_positions()["box_1"])
    assert sim.close_gripper(cv.ROBOT) == "box_1"
    # the weld holds the part where it was at that frame (the tool point is at `pick`)
    grasp = next(g for g in sim.grasps if g.kind == "grasp")
    T = sim.gripper_pose(cv.ROBOT) @ np.vstack(
        [np.column_stack([np.eye(3), grasp.pos]), [0, 0, 0, 1]]
    )
    assert np.allclose(T[:3, 3] + np.array(cv.BOX) / 2, at_grasp, atol=1e-9)
    sim.move_linear(cv.ROBOT, tool_down(pick + np.array([0, 0, 0.1])), speed=0.25)
    # lifted with the gripper, no longer carried along by the belt
    assert np.allclose(sim.part_positions()["box_1"], at_grasp + np.array([0, 0, 0.1]), atol=1e-6)
    assert sim.summary()["collisions"] == 0
