"""Import times of real robot files: cold (an empty decomposition cache) and warm.

Every arm of rtb-data (the ROS-Industrial KUKA, ABB and Puma files, the Lynxmotion,
Trossen and Franka arms) and pybullet's iiwa and Panda is imported with ``from_urdf``
twice: cold, with a fresh ``WORKCELL_COACD_CACHE`` folder (every non-convex collision
mesh is checked against its hull and decomposed), then warm (everything from that
cache). The table says, per robot, how its non-convex link meshes came out (hulls that
fit, CoACD pieces, hulls after the time bound), the pieces, and both times: wall
seconds, and CPU seconds of this process and its CoACD children (what the import costs
whatever else the machine runs; spread over the cores, it is the wall time of an idle
machine).

The baseline (``--baseline``, default the KR 6 R900 of the issue) is the import as it was
before: CoACD's default setting (threshold 0.05, its default search), one mesh after the
other, within ``--cap`` seconds (printed as "> cap" when it runs longer); its ratio to
the cold import is measured in the same run. Times are wall times on this machine,
shared with whatever else runs: the load average is printed with the table.

    python scripts/bench_import.py [--robots a,b,...] [--baseline a,b,...] [--cap 300]
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
import warnings
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests" / "robots"))  # the real-robot registry

from robot_files import REAL_ROBOTS, real_robot  # noqa: E402

from workcell import decompose, limits  # noqa: E402
from workcell.robots import from_urdf, linkshapes  # noqa: E402


def cpu() -> float:
    """CPU seconds of this process and its finished children (the CoACD workers)."""
    me, kids = (resource.getrusage(w) for w in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def import_once(path: Path, kw: dict) -> tuple[float, float, object, list[str]]:
    """(wall seconds, CPU seconds, robot, warnings) of one import."""
    t0, c0 = time.perf_counter(), cpu()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = from_urdf(path, **kw)
    return time.perf_counter() - t0, cpu() - c0, robot, [str(w.message) for w in caught]


def methods_of(path: Path, kw: dict) -> tuple[Counter, int, int]:
    """(how the non-convex meshes came out, their pieces, how many) from the cache."""
    seen: list = []
    real = decompose.decompositions

    def spy(*args: object, **kwargs: object) -> list:
        out = real(*args, **kwargs)
        seen.extend(out)
        return out

    linkshapes.decompositions = spy
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            from_urdf(path, **kw)
    finally:
        linkshapes.decompositions = real
    pieces = sum(len(d.pieces) for d in seen if d.method == "coacd")
    return Counter(d.method for d in seen), pieces, len(seen)


def baseline(path: Path, kw: dict, cap: float) -> float | None:
    """Seconds of the import as it was (module doc); None over ``cap``."""
    meshes: list = []
    real = linkshapes.LinkBatch.run

    def collect(batch: linkshapes.LinkBatch) -> list:
        meshes.extend(batch.meshes)
        return [() for _ in batch.meshes]

    linkshapes.LinkBatch.run = collect
    try:
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            from_urdf(path, **kw)
        for mesh in meshes:  # one at a time, CoACD's defaults, as before
            left = cap - (time.perf_counter() - t0)
            if left <= 0:
                return None
            with limits.using(max_native_seconds=left):
                decompose.decompose_many([mesh], decompose.DEFAULT_CONCAVITY, on_done=lambda *a: 0)
        return time.perf_counter() - t0
    except limits.LimitError:
        return None
    finally:
        linkshapes.LinkBatch.run = real


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robots", default=",".join(REAL_ROBOTS), help="comma-separated names")
    ap.add_argument("--baseline", default="kr6r900sixx", help="robots to time as before")
    ap.add_argument("--cap", type=float, default=300.0, help="seconds a baseline may take")
    args = ap.parse_args()
    names = [n for n in args.robots.split(",") if n]
    base_names = {n for n in args.baseline.split(",") if n}
    with tempfile.TemporaryDirectory(prefix="bench_import_") as tmp:
        work = Path(tmp)
        os.environ[decompose.CACHE_ENV] = str(work / "warmup")
        path, kw = real_robot("kr16_2", work / "urdf")
        import_once(path, kw)  # load the libraries before anything is timed
        print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
        head = (
            f"{'robot':18s} {'dof':>3s} {'meshes':>6s} {'hull':>4s} {'coacd':>5s} "
            f"{'late':>4s} {'pieces':>6s} {'cold s':>7s} {'cpu s':>6s} {'warm s':>7s} "
            f"{'cpu s':>6s} {'before s':>9s} {'ratio':>6s}"
        )
        print(head)
        print("-" * len(head))
        worst_cold = worst_warm = 0.0
        for name in names:
            path, kw = real_robot(name, work / "urdf")
            os.environ[decompose.CACHE_ENV] = str(work / f"cache_{name}")
            cold, cold_cpu, robot, said = import_once(path, kw)
            warm, warm_cpu, _, _ = import_once(path, kw)
            how, pieces, n = methods_of(path, kw)
            worst_cold, worst_warm = max(worst_cold, cold), max(worst_warm, warm)
            before = ratio = ""
            if name in base_names:
                os.environ[decompose.CACHE_ENV] = str(work / f"baseline_{name}")
                b = baseline(path, kw, args.cap)
                before = f"> {args.cap:g}" if b is None else f"{b:.1f}"
                ratio = f"{(args.cap if b is None else b) / cold:.0f}x"
            print(
                f"{name:18s} {robot.dof:3d} {n:6d} {how['hull']:4d} {how['coacd']:5d} "
                f"{how['timeout'] + how['unsplit']:4d} {pieces:6d} {cold:7.1f} {cold_cpu:6.1f} "
                f"{warm:7.2f} {warm_cpu:6.2f} {before:>9s} {ratio:>6s}",
                flush=True,
            )
            for w in said:
                if "decomposition took over" in w:
                    print(f"  {w[:160]}")
        print(f"slowest cold {worst_cold:.1f} s, slowest warm {worst_warm:.2f} s")
        print(f"load average {os.getloadavg()[0]:.1f}")
        print(
            f"robot links: CoACD threshold {linkshapes.LINK_CONCAVITY}, "
            f"{linkshapes.LINK_OPTIONS}, hull fit {linkshapes.LINK_HULL_FIT}, "
            f"{linkshapes.LINK_SECONDS:g} s a link"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
