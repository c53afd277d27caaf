"""Benchmark the simulator on the thesis's example 1, measured in one run.

For each mode at dt (default 1 ms): frames, simulated time, wall time, real-time factor,
and the ratio of our whole run to a bare Python loop over the same frames of
``mj_kinematics`` (what the kinematic simulator does per frame today) and of
``mj_kinematics + mj_collision`` (what it will do once collisions are checked; issue 4's
target is our loop <= 2x that one).

Usage: python scripts/bench_sim.py [--dt 0.001] [--repeat 5]
"""

from __future__ import annotations

import argparse
import statistics
import time

import mujoco
import numpy as np

from workcell.examples import thesis_joints


def bare_loop(model: mujoco.MjModel, Q: np.ndarray, collide: bool) -> float:
    """Seconds for a plain loop setting qpos and running kinematics (+ collision) per frame."""
    d = mujoco.MjData(model)
    t0 = time.perf_counter()
    for q in Q:
        d.qpos[:] = q
        mujoco.mj_kinematics(model, d)
        if collide:
            mujoco.mj_collision(model, d)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dt", type=float, default=0.001)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    print(f"thesis example 1 (one Puma 260, 0.3 rad/s) at dt = {args.dt} s")
    head = f"{'mode':15s} {'frames':>7s} {'sim s':>7s} {'wall ms':>8s} {'x real time':>11s} {'/kin':>6s} {'/kin+col':>8s}"
    print(head)
    for mode in ("path", "joint-by-joint", "playback"):
        walls, sims = [], []
        for _ in range(args.repeat):
            sim = thesis_joints.run(mode, args.dt)
            walls.append(sim.wall_time)  # the simulator's own wall clock of the program
            sims.append(sim)
        sim = sims[-1]
        wall = statistics.median(walls)
        Q = sim.timeline.qpos(0, sim.frames)
        kin = statistics.median(bare_loop(sim.model, Q, False) for _ in range(args.repeat))
        col = statistics.median(bare_loop(sim.model, Q, True) for _ in range(args.repeat))
        print(
            f"{mode:15s} {sim.frames:7d} {sim.sim_time:7.3f} {wall * 1e3:8.2f} "
            f"{sim.sim_time / wall:11.0f} {wall / kin:6.2f} {wall / col:8.2f}"
        )
    print("(wall: the simulator's own wall clock of the program, without building the cell)")


if __name__ == "__main__":
    main()
