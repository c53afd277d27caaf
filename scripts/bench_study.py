"""Benchmark studies: candidates per second on one core, 2 processes and Ray with 2 CPUs.

The study: the thesis's pick-and-place cell (example 2) with the robot's base over a
15 x 14 grid (210 candidates, about half of them feasible), its own program, headless.
Each backend runs the whole study in one call (its own start included: the process
pool's fork server and workers, Ray's workers; not ``ray.init``, which a cluster has
already done), in this order: serial, process pool, Ray; then the tables are compared
bit for bit. Targets (issue 13): 2 processes >= 1.7x serial, Ray (2 CPUs) >= 1.5x serial.
Also: the peak memory of each worker process, and with ``--curve`` candidates per second
against the process pool's worker count (1 to 4 on this machine).

The machine is shared and noisy: the ratios are what one run measured, the three
backends one after another.

Usage: python scripts/bench_study.py [--nx 15 --ny 14] [--curve] [--no-ray]
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time

import numpy as np
import pyarrow as pa

from workcell.study import Study
from workcell.study.runner import execute


def study(nx: int, ny: int) -> Study:
    return Study(
        cell="pick-place",
        vary={"puma.base.x": f"-0.1:0.12:{nx}", "puma.base.y": f"-0.12:0.1:{ny}"},
    )


def timed(s: Study, backend: str, workers: int | None = None) -> tuple[float, pa.Table, dict]:
    t0 = time.perf_counter()
    out = execute(s, None, backend_name=backend, workers=workers, progress=False)
    return time.perf_counter() - t0, out.table, out.backend.memory_mb


def same_bits(a: pa.Table, b: pa.Table) -> bool:
    if a.schema != b.schema or a.num_rows != b.num_rows:
        return False
    for name in a.column_names:
        x, y = a.column(name).combine_chunks(), b.column(name).combine_chunks()
        if pa.types.is_floating(x.type):
            xb = np.asarray(x.fill_null(np.nan)).view(np.uint64)
            yb = np.asarray(y.fill_null(np.nan)).view(np.uint64)
            if not (np.array_equal(xb, yb) and x.is_valid().equals(y.is_valid())):
                return False
        elif not x.equals(y):
            return False
    return True


def memory(mb: dict[int, float]) -> str:
    return ", ".join(f"{v:.0f}" for v in sorted(mb.values())) + " MB"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nx", type=int, default=15)
    ap.add_argument("--ny", type=int, default=14)
    ap.add_argument("--curve", action="store_true", help="also 1..4 process workers")
    ap.add_argument("--no-ray", action="store_true")
    args = ap.parse_args()
    s = study(args.nx, args.ny)
    n = s.size
    print(f"study: example 2, base over a {args.nx} x {args.ny} grid = {n} candidates")
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start")

    t_serial, serial, mem_serial = timed(s, "serial")
    feasible = sum(serial.column("feasible").to_pylist())
    print(f"\nserial:       {t_serial:6.1f} s  {n / t_serial:6.2f} cand/s  ({feasible} feasible)")
    print(f"  this process's peak memory: {memory(mem_serial)}")

    t_proc, proc, mem_proc = timed(s, "process", 2)
    print(
        f"2 processes:  {t_proc:6.1f} s  {n / t_proc:6.2f} cand/s  "
        f"{t_serial / t_proc:.2f}x serial (target >= 1.7x)  identical: {same_bits(proc, serial)}"
    )
    print(f"  workers' peak memory: {memory(mem_proc)}")

    if not args.no_ray:
        import ray

        os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
        os.environ.setdefault("RAY_AUTH_MODE", "disabled")
        tmp = tempfile.mkdtemp(prefix="ray-")
        t0 = time.perf_counter()
        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, _temp_dir=tmp)
        t_init = time.perf_counter() - t0
        try:
            t_ray, by_ray, mem_ray = timed(s, "ray")
        finally:
            ray.shutdown()
            shutil.rmtree(tmp, ignore_errors=True)
        print(
            f"Ray, 2 CPUs:  {t_ray:6.1f} s  {n / t_ray:6.2f} cand/s  "
            f"{t_serial / t_ray:.2f}x serial (target >= 1.5x)  identical: {same_bits(by_ray, serial)}"
            f"  (ray.init {t_init:.1f} s, not counted)"
        )
        print(f"  Ray workers' peak memory: {memory(mem_ray)}")

    if args.curve:
        print("\ncandidates/s against process workers (this machine has 2 cores):")
        for w in (1, 2, 3, 4):
            t, _, _ = timed(s, "process", w)
            print(f"  {w} worker(s): {n / t:6.2f} cand/s  ({t_serial / t:.2f}x serial)")


if __name__ == "__main__":
    main()
