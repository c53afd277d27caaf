"""Benchmark the simulator on the thesis's three examples, measured in one run.

For each example in each mode at dt (default 1 ms): frames, simulated time, the wall
time of the whole program (planning, IK, straight lines, grasps, frames with collision
checks every frame; playback includes the replay), the real-time factor, and the ratio
of that wall time to a bare Python loop over the same frames of ``mj_kinematics`` +
``mj_collision`` (issue 4's target: <= 2x), measured alternately in the same run.
Then a one-hour program at 1 kHz in playback mode (example 1 slowed down so that it
lasts an hour: 3.6 M frames), run in a subprocess to report its peak memory (target
< 300 MB).

Usage: python scripts/bench_sim.py [--dt 0.001] [--repeat 3] [--no-hour]
"""

from __future__ import annotations

import argparse
import importlib
import json
import statistics
import subprocess
import sys
import time

import mujoco
import numpy as np

from workcell.sim import Simulator

EXAMPLES = {
    "1 joints": "workcell.examples.thesis_joints",
    "2 pick-place": "workcell.examples.thesis_pick_place",
    "3 handoff": "workcell.examples.thesis_handoff",
}


def bare_loop(model: mujoco.MjModel, Q: np.ndarray) -> float:
    """Seconds for a plain loop setting qpos, mj_kinematics and mj_collision per frame."""
    d = mujoco.MjData(model)
    t0 = time.perf_counter()
    for q in Q:
        d.qpos[:] = q
        mujoco.mj_kinematics(model, d)
        mujoco.mj_collision(model, d)
    return time.perf_counter() - t0


def ours(module: str, mode: str, dt: float, compiled) -> tuple[float, Simulator]:
    """Wall seconds of the whole program (not the cell's compile) and the finished sim."""
    ex = importlib.import_module(module)
    cell = compiled[0]
    sim = Simulator(cell, mode=mode, dt=dt, compiled=compiled[1])
    t0 = time.perf_counter()
    ex.program(sim)
    if mode == "playback":
        sim.play()
    return time.perf_counter() - t0, sim


HOUR = """
import resource, time, numpy as np
from workcell.examples import thesis_joints as ex
from workcell.sim import Simulator
sim = Simulator(ex.build(), mode="playback", dt=0.001)
t0 = time.perf_counter()
ex.program(sim)  # at the thesis speed: 9.89 s of motion
speed = ex.SPEED * ex.expected_sim_time() / 3600.0  # slow it down to one hour
sim2 = Simulator(ex.build(), mode="playback", dt=0.001)
sim2.set_speed(ex.ROBOT, speed)
sim2.move_joints_relative(ex.ROBOT, np.radians(ex.RELATIVE_DEG))
sim2.move_joints_absolute(ex.ROBOT, np.radians(ex.ABSOLUTE_DEG))
sim2.move_joints_absolute(ex.ROBOT, np.radians(ex.START_DEG))
t1 = time.perf_counter()
sim2.play()
t2 = time.perf_counter()
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(__import__("json").dumps({"frames": sim2.frames, "sim_s": sim2.sim_time,
      "plan_s": t1 - t0, "play_s": t2 - t1, "peak_rss_mb": rss,
      }))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dt", type=float, default=0.001)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-hour", action="store_true", help="skip the one-hour memory run")
    args = ap.parse_args()
    print(f"the thesis's examples at dt = {args.dt} s, collisions checked every frame")
    print(
        f"{'example':13s} {'mode':15s} {'frames':>7s} {'sim s':>7s} {'wall ms':>8s} "
        f"{'x real time':>11s} {'bare ms':>8s} {'ours/bare':>9s}"
    )
    for label, module in EXAMPLES.items():
        ex = importlib.import_module(module)
        cell = ex.build()
        compiled = (cell, Simulator(cell).compiled)
        for mode in ("path", "joint-by-joint", "playback"):
            walls, bares = [], []
            for _ in range(args.repeat):  # alternate ours and the bare loop
                w, sim = ours(module, mode, args.dt, compiled)
                walls.append(w)
                bares.append(bare_loop(sim.model, sim.timeline.qpos(0, sim.frames)))
            wall, bare = statistics.median(walls), statistics.median(bares)
            print(
                f"{label:13s} {mode:15s} {sim.frames:7d} {sim.sim_time:7.2f} {wall * 1e3:8.1f} "
                f"{sim.sim_time / wall:11.0f} {bare * 1e3:8.1f} {wall / bare:9.2f}"
            )
    print("(wall: the whole program after the cell is compiled; playback includes the replay)")
    if not args.no_hour:
        print("\none-hour program at 1 kHz in playback mode (subprocess) ...", flush=True)
        out = subprocess.run(
            [sys.executable, "-c", HOUR], capture_output=True, text=True, check=True
        ).stdout
        r = json.loads(out)
        print(
            f"{r['frames']} frames, {r['sim_s']:.0f} s simulated; computed in {r['plan_s']:.1f} s, "
            f"replayed in {r['play_s']:.1f} s; peak RSS {r['peak_rss_mb']:.0f} MB (target < 300)"
        )


if __name__ == "__main__":
    main()
