"""Benchmark the robot kinematics, measured in one run, with MuJoCo's kinematics as the floor.

For the Puma 560 and the Puma 260 (targets in brackets):

- FK single (``Robot.fk``, poses/s) and batched (``Robot.fk_batch``, poses/s, >= 1,000,000);
- closed-form IK, all solutions of one pose (``ik_closed.puma_ik``, us, <= 50 us) and
  batched (``puma_ik_batch``, poses/s, >= 100,000), when ``workcell.robots.ik_closed``
  provides them;
- ``Robot.ik`` (mink) over random FULL-RANGE reachable targets ``fk(q)``, q uniform in
  the limits: success rate (>= 99.5 %), median and p90 ms (median <= 2 ms);
- ``Robot.ik(method="newton-gauss")`` on the same targets;
- ``mujoco.mj_kinematics`` on the robot's kinematic model (calls/s): the floor;
- ratios: each rate against mj_kinematics, IK time per target against one FK call.

Usage: python scripts/bench_kinematics.py [--n-ik N] [--n-batch N] [--n-single N] [--repeat R]
"""

from __future__ import annotations

import argparse
import importlib
import time

import mujoco
import numpy as np
from benchutil import median_time

from workcell.robots import Robot, puma260, puma560
from workcell.robots.mjcf import kinematic_model


def ik_stats(robot: Robot, targets: np.ndarray, method: str) -> dict[str, float]:
    """Success rate and per-target wall times (ms) of Robot.ik over ``targets``."""
    robot.ik(targets[0], method=method)  # warm-up: builds the caches
    times, ok, iters = [], 0, []
    for T in targets:
        t0 = time.perf_counter()
        sol = robot.ik(T, method=method)
        times.append(time.perf_counter() - t0)
        ok += sol.success
        iters.append(sol.iterations)
    t = np.array(times) * 1e3
    return {
        "success": ok / len(targets),
        "median_ms": float(np.median(t)),
        "p90_ms": float(np.percentile(t, 90)),
        "max_ms": float(t.max()),
        "iterations": float(np.median(iters)),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-ik", type=int, default=200, help="random IK targets (default 200)")
    ap.add_argument("--n-batch", type=int, default=100_000, help="poses per batch (default 1e5)")
    ap.add_argument("--n-single", type=int, default=2000, help="single calls timed (default 2000)")
    ap.add_argument("--repeat", type=int, default=5, help="timed repeats (median, default 5)")
    args = ap.parse_args()

    try:
        closed = importlib.import_module("workcell.robots.ik_closed")
    except ImportError:
        closed = None
    puma_ik = getattr(closed, "puma_ik", None)
    puma_ik_batch = getattr(closed, "puma_ik_batch", None)

    for robot in (puma560(geometry=False), puma260(geometry=False)):
        rng = np.random.default_rng(2024)
        Qb = rng.uniform(robot.lower, robot.upper, size=(args.n_batch, robot.dof))
        Qs = Qb[: args.n_single]
        Ts = robot.fk_batch(Qs)
        print(f"\n== {robot.name} ==")

        # the floor: MuJoCo's own forward kinematics of the same chain
        model = kinematic_model(robot)
        data = mujoco.MjData(model)

        def mj(Q: np.ndarray = Qs, model: mujoco.MjModel = model, data: mujoco.MjData = data):
            for q in Q:
                data.qpos[:] = q
                mujoco.mj_kinematics(model, data)

        mj_rate = len(Qs) / median_time(mj, args.repeat)
        print(f"mujoco.mj_kinematics           {mj_rate:>12,.0f} calls/s   (floor)")

        def fk_single(Q: np.ndarray = Qs, robot: Robot = robot) -> None:
            for q in Q:
                robot.fk(q)

        fk_rate = len(Qs) / median_time(fk_single, args.repeat)
        fk_us = 1e6 / fk_rate
        print(
            f"Robot.fk single                {fk_rate:>12,.0f} poses/s   "
            f"({fk_us:.1f} us; {fk_rate / mj_rate:.2f}x mj_kinematics)"
        )
        fkb_rate = len(Qb) / median_time(lambda Q=Qb, robot=robot: robot.fk_batch(Q), args.repeat)
        flag = "ok" if fkb_rate >= 1e6 else "BELOW TARGET"
        print(
            f"Robot.fk_batch ({len(Qb):,})      {fkb_rate:>12,.0f} poses/s   "
            f"({fkb_rate / mj_rate:.1f}x mj_kinematics; target >= 1,000,000: {flag})"
        )

        if puma_ik is None:
            print(
                "closed form                    skipped: workcell.robots.ik_closed.puma_ik missing"
            )
        else:

            def cf(Ts: np.ndarray = Ts, robot: Robot = robot) -> None:
                for T in Ts:
                    puma_ik(robot, T)

            cf_us = median_time(cf, args.repeat) / len(Ts) * 1e6
            flag = "ok" if cf_us <= 50 else "ABOVE TARGET"
            print(
                f"puma_ik, all solutions         {cf_us:>12.1f} us/pose   "
                f"({cf_us / fk_us:.1f}x Robot.fk; target <= 50 us: {flag})"
            )
        if puma_ik_batch is None:
            print("closed form batch              skipped: ik_closed.puma_ik_batch missing")
        else:
            Tb = robot.fk_batch(Qb)
            cfb_rate = len(Tb) / median_time(
                lambda Tb=Tb, robot=robot: puma_ik_batch(robot, Tb), args.repeat
            )
            flag = "ok" if cfb_rate >= 1e5 else "BELOW TARGET"
            print(
                f"puma_ik_batch ({len(Tb):,})       {cfb_rate:>12,.0f} poses/s   "
                f"({cfb_rate / mj_rate:.2f}x mj_kinematics; target >= 100,000: {flag})"
            )

        Qik = rng.uniform(robot.lower, robot.upper, size=(args.n_ik, robot.dof))
        targets = robot.fk_batch(Qik)
        for method in ("mink", "newton-gauss"):
            s = ik_stats(robot, targets, method)
            line = (
                f"Robot.ik {method:<13}         {100 * s['success']:>11.1f} %  success on "
                f"{args.n_ik} full-range targets; median {s['median_ms']:.2f} ms, "
                f"p90 {s['p90_ms']:.2f} ms, max {s['max_ms']:.1f} ms, "
                f"median iterations {s['iterations']:.0f}; "
                f"median = {s['median_ms'] * 1e3 / fk_us:,.0f} Robot.fk calls"
            )
            if method == "mink":
                good = s["success"] >= 0.995 and s["median_ms"] <= 2.0
                line += f" (targets >= 99.5 %, median <= 2 ms: {'ok' if good else 'MISSED'})"
            print(line)


if __name__ == "__main__":
    main()
