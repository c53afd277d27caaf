"""Benchmark the rerun recorder (``workcell.record.record``), measured in one run.

1. For the thesis's example 1 (and example 3 when ``workcell.examples.thesis_handoff``
   exists) at dt (default 1 ms), path mode: frames, the time of the simulation alone
   (``run(mode, dt)``: build, compile and run the program; and the simulator's own
   stopwatch of the program), the time of recording its timeline to an ``.rrd`` file, the
   ratio recording / simulation (target: <= 1, i.e. recording adds at most the
   simulation's own time) and the file size. Times are medians, simulation and recording
   measured in alternation.
2. Peak memory of a long program (default one hour of simulated time at 1 kHz:
   example 1's program repeated) recorded in chunks, in a fresh subprocess: peak RSS
   after simulating (the timeline spills to disk past its memory limit) and after
   recording (target: < 300 MB), with the times and the file size.

Usage: python scripts/bench_record.py [--dt 0.001] [--repeat 3] [--hours 1.0] [--skip-long]
       [--sim-memory-mb MB ...]
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from workcell.examples import thesis_joints
from workcell.record import record
from workcell.sim import Simulator


def peak_rss_mb() -> float:
    """Peak resident set size of this process so far (MB).

    Linux: ``VmHWM`` of /proc/self/status, which starts afresh at exec (``ru_maxrss``
    carries the parent's peak over fork + exec); elsewhere ``getrusage``.
    """
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024  # kB
    except OSError:
        pass
    scale = 1024 * 1024 if sys.platform == "darwin" else 1024  # bytes on macOS, else kB
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / scale


def examples() -> list[tuple[str, object]]:
    """(label, module) of the examples that exist."""
    out: list[tuple[str, object]] = [("example 1 (joints)", thesis_joints)]
    try:
        out.append(
            ("example 3 (handoff)", importlib.import_module("workcell.examples.thesis_handoff"))
        )
    except ImportError:
        print("(workcell.examples.thesis_handoff not found: example 3 skipped)")
    return out


def bench_examples(dt: float, repeat: int, folder: Path) -> None:
    print(f"recording against simulation, path mode, dt = {dt} s (medians of {repeat})")
    print(
        f"{'':20s} {'frames':>7s} {'sim run s':>9s} {'program s':>9s} {'record s':>8s} "
        f"{'rec/run':>7s} {'rec/prog':>8s} {'us/frame':>8s} {'MB':>7s}"
    )
    path = folder / "bench.rrd"
    for label, mod in examples():
        record(mod.run("path", dt), path, progress=False)  # warm-up
        runs, programs, recs = [], [], []
        for _ in range(repeat):  # alternate: both under the same background load
            path.unlink()
            t0 = time.perf_counter()
            sim = mod.run("path", dt)
            t1 = time.perf_counter()
            record(sim, path, progress=False)
            recs.append(time.perf_counter() - t1)
            runs.append(t1 - t0)
            programs.append(sim.wall_time)
        run, program, rec = (statistics.median(v) for v in (runs, programs, recs))
        print(
            f"{label:20s} {sim.frames:7d} {run:9.3f} {program:9.3f} {rec:8.3f} "
            f"{rec / run:7.2f} {rec / program:8.2f} {rec / sim.frames * 1e6:8.2f} "
            f"{path.stat().st_size / 1e6:7.1f}"
        )
    print(
        "(sim run: build + compile + program; program: the simulator's own stopwatch of "
        "the program; target rec/run <= 1)"
    )


def long_child(hours: float, dt: float, folder: str, memory_mb: float | None) -> None:
    """In a fresh process: simulate ``hours`` of example 1's program, record it, print JSON.

    ``memory_mb``: the timeline's in-memory limit (None: the simulator's default)."""
    base = peak_rss_mb()
    t0 = time.perf_counter()
    limit = {} if memory_mb is None else {"memory_limit": int(memory_mb * 2**20)}
    sim = Simulator(thesis_joints.build(), "path", dt=dt, **limit)
    while sim.sim_time < hours * 3600:
        thesis_joints.program(sim)
    t_sim = time.perf_counter() - t0
    rss_sim = peak_rss_mb()
    path = Path(folder) / "hour.rrd"
    stats = record(sim, path, progress=sys.stderr.isatty())
    out = {
        "frames": sim.frames,
        "sim_time_s": sim.sim_time,
        "spilled_blocks": sim.timeline.spilled_blocks,
        "simulate_s": t_sim,
        "record_s": stats.seconds,
        "file_mb": path.stat().st_size / 1e6,
        "rss_start_mb": base,
        "rss_after_sim_mb": rss_sim,
        "rss_peak_mb": peak_rss_mb(),
    }
    path.unlink()
    print(json.dumps(out))


def bench_long(hours: float, dt: float, folder: Path, memory_mb: float | None) -> None:
    which = "default" if memory_mb is None else f"{memory_mb:g} MB"
    print(
        f"\n{hours:g} h program at {1 / dt:g} Hz recorded in chunks (fresh subprocess; "
        f"timeline memory limit: {which})"
    )
    cmd = [sys.executable, __file__, "--child-long", str(hours), "--dt", str(dt), str(folder)]
    cmd += [] if memory_mb is None else ["--sim-memory-mb", str(memory_mb)]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    res = subprocess.run(cmd, check=True, stdout=subprocess.PIPE, text=True, env=env)
    r = json.loads(res.stdout.strip().splitlines()[-1])
    print(f"  frames           {r['frames']:,} ({r['sim_time_s']:.0f} s simulated)")
    print(f"  simulate         {r['simulate_s']:.1f} s ({r['spilled_blocks']} blocks spilled)")
    print(f"  record           {r['record_s']:.1f} s, file {r['file_mb']:.0f} MB")
    print(
        f"  peak RSS         {r['rss_start_mb']:.0f} MB after imports, "
        f"{r['rss_after_sim_mb']:.0f} MB after simulating, {r['rss_peak_mb']:.0f} MB after recording"
    )
    print(f"  recording added  {r['rss_peak_mb'] - r['rss_after_sim_mb']:.0f} MB")
    print(f"  target < 300 MB: {'met' if r['rss_peak_mb'] < 300 else 'MISSED'}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dt", type=float, default=0.001)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--hours", type=float, default=1.0)
    ap.add_argument("--skip-long", action="store_true", help="skip the long-program memory run")
    ap.add_argument(
        "--sim-memory-mb",
        type=float,
        action="append",
        help="the long program's timeline memory limit (MB); repeat for several runs "
        "(default: the simulator's default)",
    )
    ap.add_argument("--child-long", type=float, help=argparse.SUPPRESS)
    ap.add_argument("folder", nargs="?", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child_long is not None:
        long_child(args.child_long, args.dt, args.folder, (args.sim_memory_mb or [None])[0])
        return
    with tempfile.TemporaryDirectory(prefix="bench_record.") as tmp:
        bench_examples(args.dt, args.repeat, Path(tmp))
        for memory_mb in [] if args.skip_long else (args.sim_memory_mb or [None]):
            bench_long(args.hours, args.dt, Path(tmp), memory_mb)


if __name__ == "__main__":
    main()
