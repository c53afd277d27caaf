"""Devices in physics mode: MuJoCo's geom surfacevel carries a box at the belt's speed, a
belt stopped in the plan stops carrying, the end stop holds the box, a beam breaks in
physics when the kinematic plan says (within the box's start-up slip), and the conveyor
demo replayed with dynamics stacks every box where the plan did."""

from __future__ import annotations

import numpy as np
import pytest
from belt_cells import BOX, END, belt_cell

from workcell.examples import conveyor as cv
from workcell.sim import Simulator
from workcell.sim.physics import run_physics
from workcell.spatial import translation


def physics_of(cell, program, dt=0.01):
    cell.add_robot("puma", "puma260", base=translation(0, -1.5, 0))  # physics drives a robot
    sim = Simulator(cell, dt=dt)
    program(sim)
    return sim, run_physics(sim, settle=0.5)


def box_x(sim, result):
    adr = sim._free_adr["box"]
    return result.timeline.sim_times(), result.timeline.qpos()[:, adr]


def test_a_belt_carries_a_box_at_its_speed_in_physics():
    speed = 0.25
    sim, result = physics_of(belt_cell(speed=speed), lambda s: s.wait(3.0))
    t, x = box_x(sim, result)
    settled = (t >= 1.0) & (t <= 3.0)  # after the box has taken up the belt's speed
    v = np.polyfit(t[settled], x[settled], 1)[0]
    assert v == pytest.approx(speed, rel=0.02)
    # and the kinematic run carried it exactly speed x time
    assert sim.part_positions()["box"][0] == pytest.approx(0.2 + BOX / 2 + 3.0 * speed, abs=1e-9)


def test_a_belt_stopped_in_the_plan_stops_carrying_in_physics():
    def program(s):
        s.wait(1.5)
        s.set_signal("run", False)
        s.wait(1.5)

    sim, result = physics_of(belt_cell(speed=0.3, run_signal="run"), program)
    t, x = box_x(sim, result)
    late = t >= 2.0  # half a second after the stop
    assert np.ptp(x[late]) < 1e-3
    assert x[late][-1] == pytest.approx(x[t <= 1.5][-1], abs=0.01)


def test_the_end_stop_holds_the_box_in_physics():
    sim, result = physics_of(belt_cell(speed=0.25, box_x=2.6), lambda s: s.wait(3.0))
    t, x = box_x(sim, result)
    adr = sim._free_adr["box"]
    z = result.timeline.qpos()[:, adr + 2]
    held = t >= 2.0  # the box reached the stop at 1.2 s
    # pressed against the plate: its front within a few mm of the belt's end (a box on a
    # belt sliding under it chatters a little in MuJoCo's soft contacts) and on the belt
    assert np.all(np.abs(x[held] + BOX - END) < 5e-3)
    assert np.all(np.abs(z[held] - 0.5) < 0.02)


def test_a_beam_breaks_in_physics_as_in_the_plan():
    sim, result = physics_of(belt_cell(speed=0.2, beam_x=1.0), lambda s: s.wait(5.0))
    plan = [e.t for e in sim.events if e.kind == "signal"]
    physics = [e.t for e in result.events if e.kind == "signal"]
    assert len(plan) == len(physics) == 2  # on, off
    # the box needs ~0.1 s to take up the belt's speed: it arrives a little later
    assert np.all(np.array(physics) - np.array(plan) >= 0)
    assert np.all(np.array(physics) - np.array(plan) <= 0.1)
    assert all(e.data["source"] == "sensor" for e in result.events if e.kind == "signal")


def test_the_conveyor_demo_replayed_with_dynamics_stacks_every_box_in_its_place():
    sim = cv.run("path", 0.01)
    result = run_physics(sim)
    for k, place in enumerate(cv.stack_positions()):
        part = result.parts[f"box_{k + 1}"]
        assert part.resting
        assert part.distance < 2e-3  # from where the kinematic run put it
        # the kinematic place of a box's body frame: its centroid over its stack place
        centroid = part.kinematic_position + np.array(cv.BOX) / 2
        assert np.linalg.norm(centroid - place) < cv.BELT_SPEED * 0.01 + 1e-6
    assert set(result.parts) == {f"box_{k + 1}" for k in range(cv.BOXES)}  # parked left out
