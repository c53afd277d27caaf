"""Benchmark the cell logic, measured in one run (ratios, so load on the machine cancels).

1. Sensors: frames per second of the conveyor demo (``workcell demo conveyor``: a belt,
   a source, a light beam, a UR5e and a controller run together) with its beam, against
   the same cell without any sensor running the same motions: there the two programs
   wait for the times at which the beam broke in the first run instead of the beam
   (``wait`` until then), so both runs make the same frames. Then the same with five
   more sensors (two beams, two presence boxes, a proximity ray). Target: sensors cost
   <= 1.3x.
2. run_programs: the conveyor demo robot's motions (its eight cycles without the grippers
   and the waits: 65 moves, joint and linear, jerk-limited) as one program run by
   ``run_programs``, against the same program called directly on a simulator (the same
   frames, one after another). Target <= 1.2x.

Both measured in alternation (:func:`benchutil.paired_median_times`).

Usage: python scripts/bench_logic.py [--repeat 3] [--dt 0.01]
"""

from __future__ import annotations

import argparse
import json
import time

from benchutil import paired_median_times

from workcell.cell import compile_cell
from workcell.examples import conveyor as cv
from workcell.sim import Simulator


def beam_times(dt: float) -> list[float]:
    """When the beam broke in the demo (s), box by box."""
    sim = cv.run("path", dt)
    return [e.t for e in sim.events if e.kind == "signal" and e.detail.startswith("beam = true")]


def timed_programs(times: list[float]) -> dict:
    """The demo's programs with each ``wait_signal("beam")`` replaced by a wait until the
    time the beam broke in the demo."""

    def until(sim, t: float) -> None:
        if t > sim.sim_time:
            sim.wait(t - sim.sim_time)

    def robot(sim):
        pick = cv.pick_position()
        for k, place in enumerate(cv.stack_positions()[: cv.BOXES]):
            sim.move_end_effector(cv.ROBOT, cv._above(pick))
            until(sim, times[k])
            sim.move_linear(cv.ROBOT, cv.tool_down(pick), speed=cv.TOOL_SPEED)
            sim.close_gripper(cv.ROBOT)
            sim.move_linear(cv.ROBOT, cv._above(pick), speed=cv.TOOL_SPEED)
            sim.move_end_effector(cv.ROBOT, cv._above(place))
            sim.move_linear(cv.ROBOT, cv.tool_down(place), speed=cv.TOOL_SPEED)
            sim.open_gripper(cv.ROBOT)
            sim.move_linear(cv.ROBOT, cv._above(place), speed=cv.TOOL_SPEED)
            sim.set_signal("placed", True)
        sim.move_joints_absolute(cv.ROBOT, "home")

    def controller(sim):
        for k in range(cv.BOXES):
            until(sim, times[k])
            sim.set_signal("run", False)
            sim.wait_signal("placed", True)
            sim.set_signal("placed", False)
            sim.set_signal("run", True)

    return {cv.ROBOT: robot, "controller": controller}


def motions(sim) -> None:
    """The demo robot's moves, one after another (no grippers, no waits)."""
    pick = cv.pick_position()
    for place in cv.stack_positions()[: cv.BOXES]:
        sim.move_end_effector(cv.ROBOT, cv._above(pick))
        sim.move_linear(cv.ROBOT, cv.tool_down(pick), speed=cv.TOOL_SPEED)
        sim.move_linear(cv.ROBOT, cv._above(pick), speed=cv.TOOL_SPEED)
        sim.move_end_effector(cv.ROBOT, cv._above(place))
        sim.move_linear(cv.ROBOT, cv.tool_down(place), speed=cv.TOOL_SPEED)
        sim.move_linear(cv.ROBOT, cv._above(place), speed=cv.TOOL_SPEED)
    sim.move_joints_absolute(cv.ROBOT, "home")


def cell_without_sensors():
    cell = cv.build()
    cell.remove("beam")
    return cell


def cell_with_more_sensors():
    cell = cv.build()
    x, y, z = cv.BELT_END - 0.3, cv.BELT_Y, cv.BELT_TOP + 0.025
    for k, dx in enumerate((0.0, -0.4)):
        cell.add_sensor(f"beam{k}", "beam", start=(x + dx, y - 0.2, z), end=(x + dx, y + 0.2, z))
        cell.add_sensor(f"zone{k}", "presence", center=(x + dx - 0.2, y, z), size=(0.2, 0.2, 0.1))
    cell.add_sensor(
        "gap",
        "proximity",
        origin=(x - 0.6, y, 1.0),
        direction=(0, 0, -1),
        range=1.0,
        threshold=0.55,
    )
    return cell


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--dt", type=float, default=0.01)
    args = ap.parse_args()
    dt = args.dt
    times = beam_times(dt)
    base, plain, more = cv.build(), cell_without_sensors(), cell_with_more_sensors()
    compiled = {id(c): compile_cell(c) for c in (base, plain, more)}
    frames = {}

    def run(cell, programs):
        def go():
            sim = Simulator(cell, dt=dt, profile="jerk", compiled=compiled[id(cell)])
            sim.run_programs(programs)
            frames[id(cell), id(programs)] = sim.frames

        return go

    demo, timed = cv.programs(), timed_programs(times)
    t_beam, t_none = paired_median_times(run(base, demo), run(plain, timed), args.repeat)
    t_more, _ = paired_median_times(run(more, timed), run(plain, timed), args.repeat)
    n_beam, n_none = frames[id(base), id(demo)], frames[id(plain), id(timed)]
    n_more = frames[id(more), id(timed)]

    def together():
        sim = Simulator(plain, dt=dt, profile="jerk", compiled=compiled[id(plain)])
        sim.run_programs({cv.ROBOT: motions})
        frames["together"] = sim.frames

    def direct():
        sim = Simulator(plain, dt=dt, profile="jerk", compiled=compiled[id(plain)])
        motions(sim)
        frames["direct"] = sim.frames

    t_together, t_direct = paired_median_times(together, direct, args.repeat)
    out = {
        "dt_s": dt,
        "demo_frames_with_beam": n_beam,
        "frames_without_sensors": n_none,
        "frames_per_s_with_beam": n_beam / t_beam,
        "frames_per_s_without_sensors": n_none / t_none,
        "sensor_cost_beam": (n_none / t_none) / (n_beam / t_beam),
        "frames_per_s_with_six_sensors": n_more / t_more,
        "sensor_cost_six_sensors": (n_none / t_none) / (n_more / t_more),
        "run_programs_frames": frames["together"],
        "direct_frames": frames["direct"],
        "run_programs_s": t_together,
        "direct_s": t_direct,
        "run_programs_overhead": t_together / t_direct,
    }
    print(json.dumps(out, indent=1))
    print(
        f"\nsensors: {out['sensor_cost_beam']:.2f}x with the beam, "
        f"{out['sensor_cost_six_sensors']:.2f}x with six sensors (target <= 1.3x); "
        f"run_programs: {out['run_programs_overhead']:.2f}x the direct run (target <= 1.2x)"
    )


if __name__ == "__main__":
    t0 = time.perf_counter()
    main()
    print(f"({time.perf_counter() - t0:.1f} s)")
