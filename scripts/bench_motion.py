"""Benchmark motion planning and report the cycle times it gives, measured in one run.

1. Planning time per move kind (median of --repeat runs after a warm-up):
   - a jerk-limited 6-axis joint move (ruckig, rest to rest; target <= 0.2 ms), and the
     same move with its frame times (``plan_move``);
   - a 0.5 m linear move of a Puma 560 at 250 mm/s (target <= 20 ms): the plan (IK
     samples, exact path derivatives, toppra's time law), then its frames at dt (exact IK
     of each frame), and the whole ``move_linear`` command (plan, frames, emission);
   - a circular move (a 0.3 m arc) and a corner of two blended lines, the same way.
   Each line also gives the ratio to the target (< 1: within it). The machine is shared:
   absolute times vary, the medians and ratios are what to read.
2. The cycle time (simulated s) of the thesis's three programs (ch. 5) under the thesis's
   constant speed ("linear", 0.3 rad/s), the trapezoid (0.3 rad/s, 2 rad/s^2) and the
   jerk-limited profile (each joint's own speed, acceleration and jerk limits), side by
   side.

Robots: the library's own limits (``workcell.robots``: published speeds, derived
accelerations and jerks). A robot without finite limits gets this script's own where
they are missing: speeds (150, 150, 180, 300, 300, 400) deg/s, each joint reaching its
top speed in 0.25 s (acceleration = speed / 0.25 s) and its top acceleration in 0.1 s
(jerk = acceleration / 0.1 s).

Usage: python scripts/bench_motion.py [--repeat 20] [--dt 0.01]
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import statistics
import sys
import time

import numpy as np

from workcell import Workcell, compile_cell
from workcell.cell.workcell import Workcell as _Workcell
from workcell.robots import puma560
from workcell.robots.robot import Robot
from workcell.sim import Simulator
from workcell.sim.cartesian import path_joints
from workcell.sim.grasp import tool_down
from workcell.sim.jerk import joint_limits, plan_jerk
from workcell.sim.paths import CartesianPath, Line, arc_through
from workcell.sim.planning import plan_move
from workcell.sim.profiles import step_times
from workcell.sim.timing import sample_params, time_path
from workcell.spatial import invert, translation

JOINT_TARGET = 0.2e-3  # s
LINE_TARGET = 20e-3  # s
PUMA560_SPEEDS = np.radians([150.0, 150.0, 180.0, 300.0, 300.0, 400.0])
EXAMPLES = {
    "1 joints": "workcell.examples.thesis_joints",
    "2 pick-place": "workcell.examples.thesis_pick_place",
    "3 handoff": "workcell.examples.thesis_handoff",
}


def with_limits(robot: Robot, speeds: np.ndarray | None = None) -> Robot:
    """``robot`` with finite limits: its own where finite, else the module doc's."""
    v = (
        robot.max_speeds
        if speeds is None
        else np.where(np.isfinite(robot.max_speeds), robot.max_speeds, speeds)
    )
    a = np.where(np.isfinite(robot.max_accelerations), robot.max_accelerations, v / 0.25)
    j = np.where(np.isfinite(robot.max_jerks), robot.max_jerks, a / 0.1)
    joints = tuple(
        dataclasses.replace(jt, max_speed=float(x), max_acceleration=float(y), max_jerk=float(z))
        for jt, x, y, z in zip(robot.joints, v, a, j, strict=True)
    )
    return robot.with_(joints=joints)


def limited_cell(cell: _Workcell) -> _Workcell:
    """The cell with every robot given finite limits (module doc), in the same order."""
    placements = list(cell.robots.values())
    for p in placements:
        cell.remove(p.name)
    for p in placements:  # the robot as built carries its gripper already
        cell.add_robot(p.name, with_limits(p.robot), base=p.base, q=p.q)
    return cell


def report(label: str, seconds: float | tuple[float, float], target: float | None = None) -> None:
    """A line: the median (and the fastest run) in ms, and the median's ratio to target."""
    med, best = seconds if isinstance(seconds, tuple) else (seconds, None)
    ratio = f"   {med / target:5.2f} x target ({target * 1e3:g} ms)" if target else ""
    fastest = f" (fastest {best * 1e3:.3f})" if best is not None else ""
    print(f"  {label:46s} {med * 1e3:9.3f} ms{fastest}{ratio}")


def med_best(fn: object, repeat: int) -> tuple[float, float]:
    """(median, fastest) wall time (s) of ``fn()`` over ``repeat`` runs after a warm-up."""
    fn()  # type: ignore[operator]
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()  # type: ignore[operator]
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts), min(ts)


def bench_planning(repeat: int, dt: float) -> None:
    print(f"Planning time per move (median of {repeat})")
    robot = with_limits(puma560(), PUMA560_SPEEDS)
    lim = joint_limits(robot)
    rng = np.random.default_rng(7)
    lo, hi = robot.lower * 0.6, robot.upper * 0.6
    pairs = [(rng.uniform(lo, hi), rng.uniform(lo, hi)) for _ in range(64)]
    k = iter(range(10**9))

    def one_jerk() -> None:
        q0, q1 = pairs[next(k) % len(pairs)]
        plan_jerk(q0, q1, lim)

    def one_jerk_frames() -> None:
        q0, q1 = pairs[next(k) % len(pairs)]
        plan_move(q0, q1, speed=1.0, dt=dt, profile="jerk", limits=lim)

    report("jerk-limited joint move: ruckig plan", med_best(one_jerk, repeat * 10), JOINT_TARGET)
    report(f"  with its frame times (dt {dt:g} s)", med_best(one_jerk_frames, repeat * 10))

    cell = Workcell("bench_motion")
    cell.add_robot("puma", robot, q=np.radians([0.0, 45.0, -180.0, 0.0, 45.0, 0.0]))
    cc = compile_cell(cell)
    placement = cell.robots["puma"]
    base_inv = invert(placement.base)
    P0 = tool_down(np.array([0.5, -0.25, 0.6]))
    P1 = translation(0.0, 0.5, 0.0) @ P0
    sim = Simulator(cell, compiled=cc, dt=dt, check_collisions=False)
    sim.move_end_effector("puma", P0, config="ru")
    q0 = sim.joints("puma")

    def plan_path(path: CartesianPath, speed: float) -> object:
        s = sample_params(path, 0.005)
        Q = np.vstack(
            [q0, path_joints(placement, q0, path.poses(s[1:]), s[1:] / path.span, max_jump=0.17)]
        )
        ends = np.array([0.0, path.span])
        return time_path(
            robot, base_inv, path, Q, s, limits=lim,
            speed=(ends, np.array([speed, speed])), acceleration=(ends, np.array([1.2, 1.2])),
        )  # fmt: skip

    line = CartesianPath([Line(P0[:3, 3], P1[:3, 3], P0[:3, :3], P1[:3, :3])])
    law = plan_path(line, 0.25)
    t = step_times(law.duration, dt)
    report(
        "0.5 m linear move: plan (IK samples + toppra)",
        med_best(lambda: plan_path(line, 0.25), repeat),
        LINE_TARGET,
    )
    report(f"  its {len(t)} frames (exact IK each)", med_best(lambda: law.positions(t), repeat))

    def whole(move: str) -> None:
        s2 = Simulator(cell, compiled=cc, dt=dt, check_collisions=False)
        s2.move_end_effector("puma", P0, config="ru")
        t0 = time.perf_counter()
        if move == "line":
            s2.move_linear("puma", P1, speed=0.25)
        elif move == "arc":
            s2.move_circular("puma", P0[:3, 3] + [0.15, 0.25, 0.0], P1, speed=0.25)
        else:
            s2.move_linear("puma", translation(0, 0.25, 0) @ P0, speed=0.25, zone=0.05)
            s2.move_linear("puma", translation(0.2, 0.25, 0) @ P0, speed=0.25)
        whole.last = time.perf_counter() - t0  # type: ignore[attr-defined]

    def timed(move: str) -> tuple[float, float]:
        out = []
        for _ in range(max(3, repeat // 4)):
            whole(move)
            out.append(whole.last)  # type: ignore[attr-defined]
        return statistics.median(out), min(out)

    report("  the whole move_linear command", timed("line"))
    arc = CartesianPath(
        [arc_through(P0[:3, 3], P0[:3, 3] + [0.15, 0.25, 0.0], P1[:3, 3], P0[:3, :3], P1[:3, :3])]
    )
    report(f"{arc.length:.2f} m arc: plan", med_best(lambda: plan_path(arc, 0.25), repeat))
    report("  the whole move_circular command", timed("arc"))
    report("0.25 m and 0.2 m lines blended (50 mm zone), both", timed("corner"))


def bench_cycle_times(dt: float) -> None:
    print("\nCycle time of the thesis's programs (simulated s)")
    print(
        f"  {'program':14s} {'thesis (linear)':>16s} {'trapezoid':>10s} {'jerk':>8s}   jerk vs thesis"
    )
    for label, module in EXAMPLES.items():
        ex = importlib.import_module(module)
        cell = limited_cell(ex.build())
        cc = compile_cell(cell)
        times = []
        for profile in ("linear", "trapezoid", "jerk"):
            sim = Simulator(cell, compiled=cc, dt=dt, profile=profile)
            ex.program(sim)
            times.append(sim.sim_time)
        print(
            f"  {label:14s} {times[0]:16.3f} {times[1]:10.3f} {times[2]:8.3f}   "
            f"{times[2] / times[0]:.2f} x"
        )


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeat", type=int, default=20)
    p.add_argument("--dt", type=float, default=0.01)
    args = p.parse_args(argv)
    bench_planning(args.repeat, args.dt)
    bench_cycle_times(args.dt)
    return 0


if __name__ == "__main__":
    sys.exit(main())
