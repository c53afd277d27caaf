"""Benchmark collision-free planning over seeded random scenes, measured in one run.

For each seed: a Puma 260 on a table with one to three boxes, a start and a goal where
the direct joint move collides (``workcell.examples.plan_problems.random_problem``). The
planner (``move_joints_absolute(..., plan=True)``'s search: goal check, RRT-Connect,
shortening) is timed; the path is run through the simulator's frames (dt 0.01 s) and
every frame interval is re-checked at 10x the frame density with a plain MuJoCo collision
loop on the exported MJCF (``workcell.examples.plan_problems.penetrations``). Reported:
success rate, median and p90 planning time, penetrating samples (targets: >= 95 % solved, median <= 0.5 s
here, zero penetrations), and as a baseline the same searches at OMPL's default motion
resolution (1 % of the joint box's extent) re-checked the same way.

Usage: python scripts/bench_plan.py [--scenes 50] [--seed 0] [--no-baseline] [--json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time

import numpy as np

from workcell.errors import PlanningError
from workcell.examples.plan_problems import ROBOT, penetrations, random_problem
from workcell.sim import Simulator


def run_one(problem, *, baseline: bool) -> dict:
    """Plan one problem (``baseline``: at OMPL's default motion resolution), run the path
    through the simulator and re-check its frames."""
    sim = Simulator(problem.cell, dt=0.01)
    t0 = time.perf_counter()
    try:  # OMPL's default motion resolution: 1 % of the joint box's extent
        planned = sim._plan_joint_path(
            ROBOT, [problem.goal], "bench", resolution=0.01 if baseline else None
        )
    except PlanningError as exc:
        return {"seed": problem.seed, "solved": False, "error": str(exc)}
    seconds = time.perf_counter() - t0
    sim._run_waypoints(ROBOT, planned.waypoints, "bench", planned)
    samples, bad, found = penetrations(sim, density=10)
    return {
        "seed": problem.seed,
        "solved": True,
        "seconds": seconds,
        "waypoints": len(planned.waypoints),
        "frames": sim.frames,
        "samples": samples,
        "penetrating": bad,
        "first": found[:1],
        "events": sum(1 for e in sim.events if e.kind == "collision"),
    }


def summary(rows: list[dict]) -> dict:
    solved = [r for r in rows if r["solved"]]
    times = sorted(r["seconds"] for r in solved)
    p90 = times[min(len(times) - 1, int(np.ceil(0.9 * len(times))) - 1)] if times else float("nan")
    return {
        "scenes": len(rows),
        "solved": len(solved),
        "success_rate": len(solved) / len(rows) if rows else 0.0,
        "median_s": statistics.median(times) if times else float("nan"),
        "p90_s": p90,
        "samples": sum(r["samples"] for r in solved),
        "penetrating_samples": sum(r["penetrating"] for r in solved),
        "paths_with_penetrations": sum(1 for r in solved if r["penetrating"]),
        "collision_events": sum(r["events"] for r in solved),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=50)
    ap.add_argument("--seed", type=int, default=0, help="first seed")
    ap.add_argument("--no-baseline", action="store_true", help="skip OMPL's default resolution")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    t0 = time.perf_counter()
    problems = [random_problem(s) for s in range(args.seed, args.seed + args.scenes)]
    t_gen = time.perf_counter() - t0
    ours = [run_one(p, baseline=False) for p in problems]
    out = {"ours": summary(ours), "generation_s": t_gen}
    if not args.no_baseline:
        base = [run_one(p, baseline=True) for p in problems]
        out["ompl_default_resolution"] = summary(base)
    if args.json:
        print(json.dumps(out))
        return 0
    s = out["ours"]
    print(f"collision-free planning, {s['scenes']} seeded random scenes (Puma 260, 1-3 boxes, ")
    print(f"direct move collides in every one); problems generated in {t_gen:.1f} s\n")
    print(f"solved {s['solved']}/{s['scenes']} ({100 * s['success_rate']:.0f} %; target >= 95 %)")
    print(f"planning time: median {s['median_s']:.3f} s (target <= 0.5 s), p90 {s['p90_s']:.3f} s")
    print(
        f"re-check at 10x the frame density on the exported MJCF (plain MuJoCo): "
        f"{s['penetrating_samples']} penetrating of {s['samples']} samples (target 0); "
        f"simulator collision events {s['collision_events']}"
    )
    failed = [r for r in ours if not r["solved"]]
    for r in failed:
        print(f"  seed {r['seed']}: {r['error']}")
    for r in ours:
        if r["solved"] and r["penetrating"]:
            print(f"  seed {r['seed']}: {r['penetrating']} penetrating samples, e.g. {r['first']}")
    if "ompl_default_resolution" in out:
        b = out["ompl_default_resolution"]
        print(
            f"\nbaseline, OMPL's default motion resolution: solved {b['solved']}/{b['scenes']}, "
            f"median {b['median_s']:.3f} s, {b['paths_with_penetrations']} path(s) with "
            f"penetrations ({b['penetrating_samples']} samples)"
        )
        if b["median_s"] > 0:
            print(
                f"planning time ratio ours / default resolution: {s['median_s'] / b['median_s']:.2f}"
            )
    ok = s["success_rate"] >= 0.95 and s["penetrating_samples"] == 0
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
