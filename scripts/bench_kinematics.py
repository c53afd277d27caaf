"""Benchmark the robot kinematics, measured in one run, against MuJoCo and the Rust OPW solver.

For the Puma 560, the Puma 260, the UR5e and the KUKA KR 6 R700 (targets in brackets):

- FK single (``Robot.fk``) and batched (``Robot.fk_batch``, poses/s, >= 1,000,000);
- closed-form IK, all solutions of one pose (``ik_closed.ik_all``, us) and batched
  (``ik_closed.ik_batch``, poses/s, >= 100,000);
- for the KR 6 R700, the Rust OPW solver's Python wheel (py-opw-kinematics, bench-only)
  on the same poses, measured alternately with ours: one call (``Robot.inverse``, its
  solutions of one pose; ours <= 10x its time, aiming at 6x) and batched (``batch_inverse``, one
  solution per pose; ours, all solutions, >= its throughput);
- ``Robot.ik`` (mink, and ``method="newton-gauss"``) over random full-range reachable
  targets ``fk(q)`` for the Pumas: success rate (>= 99.5 %), median and p90 ms (mink
  median <= 2 ms);
- ``mujoco.mj_kinematics`` on each robot's kinematic model (calls/s): the floor.

Usage: python scripts/bench_kinematics.py [--n-ik N] [--n-batch N] [--n-single N] [--repeat R]
"""

from __future__ import annotations

import argparse
import time

import mujoco
import numpy as np
from benchutil import median_time, paired_median_times

from workcell.robots import Robot, get
from workcell.robots.ik_closed import ik_all, ik_batch
from workcell.robots.mjcf import kinematic_model

ROBOTS = ("puma560", "puma260", "ur5e", "kuka_kr6_r700")


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


def rust_kr6():
    """The Rust OPW solver with the published KR 6 R700 sixx parameter set, or None."""
    try:
        from py_opw_kinematics import KinematicModel
        from py_opw_kinematics import Robot as RustRobot
    except ImportError:
        return None
    km = KinematicModel(
        a1=0.025, a2=-0.035, b=0.0, c1=0.400, c2=0.315, c3=0.365, c4=0.080,
        offsets=(0, -np.pi / 2, 0, 0, 0, 0), flip_axes=(True, False, False, True, False, True),
    )  # fmt: skip
    return RustRobot(km, degrees=False)


def closed_form(robot: Robot, Ts: np.ndarray, Tb: np.ndarray, fk_us: float, repeat: int) -> None:
    """Ours, and for the KR 6 R700 the Rust solver alternately on the same poses."""
    rust = rust_kr6() if robot.name == "kuka_kr6_r700" else None

    def ours_single(Ts: np.ndarray = Ts) -> None:
        for T in Ts:
            ik_all(robot, T)

    def ours_batch(Tb: np.ndarray = Tb) -> None:
        ik_batch(robot, Tb)

    if rust is None:
        cf_us = median_time(ours_single, repeat) / len(Ts) * 1e6
        cfb = len(Tb) / median_time(ours_batch, repeat)
        print(
            f"ik_all, all solutions          {cf_us:>12.1f} us/pose   ({cf_us / fk_us:.1f}x Robot.fk)"
        )
        flag = "ok" if cfb >= 1e5 else "BELOW TARGET"
        print(
            f"ik_batch ({len(Tb):,})            {cfb:>12,.0f} poses/s   (target >= 100,000: {flag})"
        )
        return
    from scipy.spatial.transform import RigidTransform

    poses = [RigidTransform.from_matrix(T) for T in Ts]
    batch = RigidTransform.from_matrix(Tb)
    assert np.allclose(rust.forward(np.zeros(6)).as_matrix(), robot.fk(np.zeros(6)), atol=1e-9)

    def rust_single(poses: list = poses) -> None:
        for p in poses:
            rust.inverse(p)

    ours_t, rust_t = paired_median_times(ours_single, rust_single, repeat)
    cf_us, rs_us = ours_t / len(Ts) * 1e6, rust_t / len(Ts) * 1e6
    n_ours = np.mean([len(ik_all(robot, T)) for T in Ts[:200]])
    n_rust = np.mean([len(rust.inverse(p)) for p in poses[:200]])
    flag = "ok" if cf_us <= 10 * rs_us else "ABOVE TARGET"
    flag += "; aim <= 6x: " + ("ok" if cf_us <= 6 * rs_us else "missed")
    print(
        f"ik_all, all solutions          {cf_us:>12.1f} us/pose   ({n_ours:.2f} solutions/pose; "
        f"{cf_us / fk_us:.1f}x Robot.fk)"
    )
    print(
        f"py-opw-kinematics inverse      {rs_us:>12.1f} us/pose   ({n_rust:.2f} solutions/pose); "
        f"ours/Rust = {cf_us / rs_us:.1f}x (target <= 10x: {flag})"
    )
    ours_b, rust_b = paired_median_times(ours_batch, lambda: rust.batch_inverse(batch), repeat)
    cfb, rsb = len(Tb) / ours_b, len(Tb) / rust_b
    flag = "ok" if cfb >= rsb else "BELOW TARGET"
    print(f"ik_batch ({len(Tb):,}), all        {cfb:>12,.0f} poses/s   (8 slots per pose)")
    print(
        f"py-opw batch_inverse           {rsb:>12,.0f} poses/s   (1 solution per pose); "
        f"ours/Rust = {cfb / rsb:.2f}x (target >= 1: {flag})"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-ik", type=int, default=200, help="random IK targets (default 200)")
    ap.add_argument("--n-batch", type=int, default=100_000, help="poses per batch (default 1e5)")
    ap.add_argument("--n-single", type=int, default=2000, help="single calls timed (default 2000)")
    ap.add_argument("--repeat", type=int, default=5, help="timed repeats (median, default 5)")
    args = ap.parse_args()

    for name in ROBOTS:
        robot = get(name, geometry=False)
        rng = np.random.default_rng(2024)
        Qb = rng.uniform(robot.lower, robot.upper, size=(args.n_batch, robot.dof))
        Qs = Qb[: args.n_single]
        Ts = robot.fk_batch(Qs)
        print(f"\n== {robot.name} ({robot.ik_family} family) ==")

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
        closed_form(robot, Ts, robot.fk_batch(Qb), fk_us, args.repeat)

        if not name.startswith("puma"):
            continue
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
