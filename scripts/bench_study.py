"""Benchmark studies: candidates per second on one core, 2 processes and Ray with 2 CPUs.

The study: the thesis's pick-and-place cell (example 2) with the robot's base over a
15 x 14 grid (210 candidates, about half of them feasible), its own program, headless.
Each backend runs the whole study in one call (its own start included: the process
pool's workers, Ray's workers' first tasks; not ``ray.init``, which a cluster has already
done), in this order: serial, process pool, Ray, and Ray again (its workers import the
simulator at their first task; a second study on the same workers, as on a running
cluster, does not); then the tables are compared bit for bit. Targets (issue 13):
2 processes >= 1.7x serial, Ray (2 CPUs) >= 1.5x serial.
Also: the peak memory of each worker process, the workers' CPU time per candidate (the
same in every backend when the workers do no extra work), and with ``--curve``
candidates per second against the process pool's worker count (1 to 4 on this machine).
A control before and after: how many times one busy loop's work two busy loops in two
processes do (2.0 on two idle cores): on a shared machine the speed-ups are bounded by it.

The machine is shared and noisy: the ratios are what one run measured, the three
backends one after another.

Usage: python scripts/bench_study.py [--nx 15 --ny 14] [--curve] [--no-ray]
       [--autogroup-nice -10]  (on a shared Linux machine, as root, with setsid)
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa

from workcell.study import Study
from workcell.study.backends import backend
from workcell.study.prepare import prepare
from workcell.study.results import ResultStore, schema


def study(nx: int, ny: int) -> Study:
    return Study(
        cell="pick-place",
        vary={"puma.base.x": f"-0.1:0.12:{nx}", "puma.base.y": f"-0.12:0.1:{ny}"},
    )


@dataclass
class Timing:
    """One backend's run: the whole time, the time to its first row, its table and
    its workers' peak memory (MB by pid)."""

    total: float
    first: float
    n: int
    table: pa.Table
    memory_mb: dict[int, float]
    cpu_s: dict[int, float]

    @property
    def steady(self) -> float:
        """Candidates per second after the first row (the start excluded)."""
        return (self.n - 1) / (self.total - self.first)


def timed(s: Study, name: str, workers: int | None = None) -> Timing:
    setup, info = prepare(s)
    runner = backend(name, workers=workers)
    store = ResultStore(None, schema(setup.parameters), info, setup.key)
    todo = s.candidates()
    t0 = time.perf_counter()
    first = None
    for row in runner.run(setup, todo):
        store.add([row])
        if first is None:
            first = time.perf_counter() - t0
    total = time.perf_counter() - t0
    method = getattr(runner, "start_method", "")
    if method:
        print(f"({name}: workers started by {method}; {threading.active_count()} thread(s) here)")
    return Timing(total, first or total, len(todo), store.table(), runner.memory_mb, runner.cpu_s)


def line(what: str, t: Timing, serial: Timing | None = None, target: float = 0.0) -> str:
    text = (
        f"{what:13s} {t.total:6.1f} s  {t.n / t.total:6.2f} cand/s  (first row {t.first:4.1f} s; "
        f"then {t.steady:6.2f} cand/s)"
    )
    cpu = sum(t.cpu_s.values())
    text += (
        f"\n{'':13s} CPU {1e3 * cpu / t.n:.1f} ms per candidate; the worker(s) had "
        f"{cpu / t.total:.2f} cores on average"
    )
    if serial is not None:
        text += (
            f"\n{'':13s} {serial.total / t.total:.2f}x serial (target >= {target}x), "
            f"{t.steady / serial.steady:.2f}x after the first row; "
            f"identical: {same_bits(t.table, serial.table)}"
        )
    return text


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


def _spin(n: int) -> int:
    x = 0
    for i in range(n):
        x += i * i
    return x


def capacity(n: int = 10_000_000) -> float:
    """How many times one process's work two plain busy processes do right now (2.0 on
    two idle cores; less when other work shares them): the control for the ratios."""
    import multiprocessing as mp

    with mp.get_context("fork").Pool(2) as pool:
        pool.map(_spin, [1000, 1000])  # started
        t0 = time.perf_counter()
        _spin(n)
        one = time.perf_counter() - t0
        t0 = time.perf_counter()
        pool.map(_spin, [n, n])
        two = time.perf_counter() - t0
    return 2 * one / two


def memory(mb: dict[int, float]) -> str:
    return ", ".join(f"{v:.0f}" for v in sorted(mb.values())) + " MB"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nx", type=int, default=15)
    ap.add_argument("--ny", type=int, default=14)
    ap.add_argument("--curve", action="store_true", help="also 1..4 process workers")
    ap.add_argument("--no-ray", action="store_true")
    ap.add_argument(
        "--autogroup-nice",
        type=int,
        metavar="N",
        help="Linux with autogroup scheduling shares the CPU per session, not per process: "
        "run in a new session (setsid) and give this session's group nice N (e.g. -10, as "
        "root) so that it gets the two cores the targets assume",
    )
    args = ap.parse_args()
    if args.autogroup_nice is not None:
        with open("/proc/self/autogroup", "w") as f:
            f.write(str(args.autogroup_nice))
        group = Path("/proc/self/autogroup").read_text().strip()
        print(f"this session's scheduling group: {group}")
    s = study(args.nx, args.ny)
    n = s.size
    print(f"study: example 2, base over a {args.nx} x {args.ny} grid = {n} candidates")
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start")

    before = capacity()
    print(f"control: 2 busy processes do {before:.2f}x the work of one right now (2.00 when idle)")
    serial = timed(s, "serial")
    feasible = sum(serial.table.column("feasible").to_pylist())
    print(f"({feasible} feasible)\n")
    print(line("serial:", serial))
    print(f"{'':13s} this process's peak memory: {memory(serial.memory_mb)}")
    proc = timed(s, "process", 2)
    print(line("2 processes:", proc, serial, 1.7))
    print(f"{'':13s} workers' peak memory: {memory(proc.memory_mb)}")

    if not args.no_ray:
        import ray

        os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
        os.environ.setdefault("RAY_AUTH_MODE", "disabled")
        tmp = tempfile.mkdtemp(prefix="ray-")
        t0 = time.perf_counter()
        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, _temp_dir=tmp)
        t_init = time.perf_counter() - t0
        try:
            by_ray = timed(s, "ray")
            warm = timed(s, "ray")  # a second study on the same workers
        finally:
            ray.shutdown()
            shutil.rmtree(tmp, ignore_errors=True)
        print(line("Ray, 2 CPUs:", by_ray, serial, 1.5))
        print(
            f"{'':13s} Ray workers' peak memory: {memory(by_ray.memory_mb)}; ray.init {t_init:.1f} s (not counted)"
        )
        print(line("  again:", warm, serial, 1.5))
        print(f"{'':13s} (a second study on the same Ray workers: the simulator imported already)")

    if args.curve:
        print("\ncandidates/s against process workers (this machine has 2 cores):")
        for w in (1, 2, 3, 4):
            t = timed(s, "process", w)
            print(
                f"  {w} worker(s): {t.n / t.total:6.2f} cand/s, {t.steady:6.2f} after the first row"
            )
    after = capacity()
    print(
        f"\ncontrol again: {after:.2f}x; load average at the end: {os.getloadavg()[0]:.1f}. The "
        "targets assume two free cores: compare the speed-ups with the controls."
    )


if __name__ == "__main__":
    main()
