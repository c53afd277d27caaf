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
- ``mujoco.mj_kinematics`` on each robot's kinematic model (calls/s): the floor;
- redundant, hard-limit arms (the Panda, compiled from rtb-data's xacro with xacrodoc,
  and rtb-data's LBR iiwa 14 URDF; test-only packages): ``Robot.ik`` over random
  reachable targets ``fk(q)``, q uniform within the limits (success >= 99 %, every
  success re-verified here by ``Robot.fk`` within the tolerances: no false success),
  against today's solver (``ik_mink`` as it was at commit ``BASELINE``, read from git)
  on the same targets, alternately, in the same run: success rates and the ratio of
  the median times.

Usage: python scripts/bench_kinematics.py [--n-ik N] [--n-batch N] [--n-single N] [--repeat R]
       [--n-redundant N]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
import types
import warnings
from pathlib import Path

import mujoco
import numpy as np
from benchutil import median_time, paired_median_times

from workcell.robots import Robot, from_urdf, get
from workcell.robots.ik_closed import ik_all, ik_batch
from workcell.robots.mjcf import kinematic_model

ROBOTS = ("puma560", "puma260", "ur5e", "kuka_kr6_r700")
BASELINE = "8012137"  # main before the redundant-arm work (issue 20 item 6): "today's solver"


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


def redundant_arms(folder: Path) -> dict[str, Robot]:
    """The Panda (rtb-data xacro, compiled with xacrodoc) and the LBR iiwa 14 (rtb-data
    URDF), kinematics only; {} when the test-only packages are missing."""
    try:
        import rtbdata
        from xacrodoc import XacroDoc, packages
    except ImportError:
        return {}
    xacro = Path(rtbdata.__path__[0]) / "xacro"
    frankie = xacro / "qut_frankie_description"
    packages.update_package_cache({"qut_frankie_description": str(frankie)})
    doc = XacroDoc.from_file(frankie / "robots/panda_arm.urdf.xacro", resolve_packages=False)
    panda = folder / "panda_arm.urdf"
    panda.write_text(doc.to_urdf_string())
    iiwa = xacro / "kuka_description/kuka_lbr_iiwa/urdf/lbr_iiwa_14_r820.urdf"
    with warnings.catch_warnings():  # the files' missing visual meshes
        warnings.simplefilter("ignore")
        return {
            "panda": from_urdf(panda, geometry=False),
            "lbr_iiwa_14_r820": from_urdf(iiwa, geometry=False),
        }


def todays_solver():
    """``_solve_mink`` of ``workcell/robots/ik_mink.py`` at commit ``BASELINE`` (from git),
    or None when git or that commit is not at hand."""
    root = Path(__file__).resolve().parent.parent
    try:
        src = subprocess.run(
            ["git", "show", f"{BASELINE}:workcell/robots/ik_mink.py"],
            cwd=root, capture_output=True, text=True, check=True,
        ).stdout  # fmt: skip
    except (OSError, subprocess.CalledProcessError):
        return None
    mod = types.ModuleType("ik_mink_baseline")
    sys.modules[mod.__name__] = mod  # dataclasses look their module up
    exec(compile(src, f"ik_mink.py@{BASELINE}", "exec"), mod.__dict__)
    return mod._solve_mink


def redundant_stats(robot: Robot, targets: np.ndarray, baseline) -> None:
    """Ours and today's solver, alternately on the same targets: success, false successes
    (re-verified by ``Robot.fk``), median and p90 ms, and the ratio of the medians."""
    from workcell.robots.ik_common import DEFAULT_MAX_ITERATIONS, DEFAULT_RESTARTS, _start

    tol = 1e-6  # m and rad: Robot.ik's defaults
    q0 = _start(robot, None)
    iters, restarts = DEFAULT_MAX_ITERATIONS["mink"], DEFAULT_RESTARTS["mink"]
    solvers = {"ours": lambda T: robot.ik(T)}
    if baseline is not None:
        solvers["today"] = lambda T: baseline(
            robot, T, q0, None, tol, tol, iters, restarts, np.random.default_rng(0)
        )
    stats = {k: {"ok": 0, "false": 0, "t": []} for k in solvers}
    for solve in solvers.values():
        solve(targets[0])  # warm-up: builds the caches
    for T in targets:
        for name, solve in solvers.items():
            t0 = time.perf_counter()
            sol = solve(T)
            stats[name]["t"].append(time.perf_counter() - t0)
            if sol.success:
                D = robot.fk(sol.q) - T
                exact = np.linalg.norm(D[:3, 3]) <= tol and robot.within_limits(sol.q)
                exact &= _angle(robot.fk(sol.q)[:3, :3], T[:3, :3]) <= tol
                stats[name]["ok" if exact else "false"] += 1
    n = len(targets)
    med = {}
    for name, st in stats.items():
        t = np.array(st["t"]) * 1e3
        med[name] = float(np.median(t))
        line = (
            f"Robot.ik {'(today)' if name == 'today' else '       '}  {100 * st['ok'] / n:>11.1f} %  "
            f"success on {n} reachable targets; false successes {st['false']}; "
            f"median {med[name]:.2f} ms, p90 {np.percentile(t, 90):.2f} ms, max {t.max():.1f} ms"
        )
        if name == "ours":
            good = st["ok"] >= 0.99 * n and st["false"] == 0
            line += f" (target >= 99 %, no false success: {'ok' if good else 'MISSED'})"
        print(line)
    if "today" in med:
        print(
            f"median time ours / today's      {med['ours'] / med['today']:>12.2f}x   "
            f"(today's solver: ik_mink at {BASELINE})"
        )
    else:
        print("today's solver                 (not measured: git or the baseline commit missing)")


def _angle(Ra: np.ndarray, Rb: np.ndarray) -> float:
    return float(np.arccos(np.clip((np.trace(Ra.T @ Rb) - 1.0) / 2.0, -1.0, 1.0)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-ik", type=int, default=200, help="random IK targets (default 200)")
    ap.add_argument("--n-batch", type=int, default=100_000, help="poses per batch (default 1e5)")
    ap.add_argument("--n-single", type=int, default=2000, help="single calls timed (default 2000)")
    ap.add_argument("--repeat", type=int, default=5, help="timed repeats (median, default 5)")
    ap.add_argument(
        "--n-redundant", type=int, default=500, help="targets per redundant arm (default 500)"
    )
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

    baseline = todays_solver()
    with tempfile.TemporaryDirectory() as tmp:
        arms = redundant_arms(Path(tmp))
    if not arms:
        print("\n(redundant arms skipped: rtb-data and xacrodoc are test-only packages)")
    for name, robot in arms.items():
        print(f"\n== {name} ({robot.dof} joints, {robot.ik_family} family) ==")
        rng = np.random.default_rng(2024)
        Q = rng.uniform(robot.lower, robot.upper, size=(args.n_redundant, robot.dof))
        redundant_stats(robot, robot.fk_batch(Q), baseline)


if __name__ == "__main__":
    main()
