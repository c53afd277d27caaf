"""Benchmark the remote program interface, measured in one run.

1. Round trips per second of a small command (``sim_time``) from the Python client to a
   ``workcell serve`` process over loopback (target: >= 2,000/s).
2. The thesis's example 1 (and example 3, the two-robot handoff, when its cell exists)
   run remotely (client -> server process: load the example cell, start the simulation,
   run the example's own ``program`` function unchanged) against the same in-process
   (build the cell, make the Simulator, run ``program``); wall times measured in
   alternation, medians, ratio remote / in-process (target: <= 2).

Usage: python scripts/bench_server.py [--round-trips 5000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
import time

from benchutil import paired_median_times

from workcell.client import Client
from workcell.sim import Simulator

EXAMPLES = {
    "example 1 (joints)": ("joints", "workcell.examples.thesis_joints"),
    "example 3 (handoff)": ("handoff", "workcell.examples.thesis_handoff"),
}


def start_server() -> tuple[subprocess.Popen, int]:
    p = subprocess.Popen(
        # (warnings only: no log line per connection in the benchmark's output)
        [
            sys.executable,
            "-m",
            "workcell.program.cli",
            "serve",
            "--port",
            "0",
            "--log-level",
            "warning",
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    line = p.stdout.readline()
    if "listening on" not in line:
        p.kill()
        raise SystemExit(f"the server did not start: {line!r}")
    return p, int(line.split("127.0.0.1:")[1].split()[0])


def round_trips(port: int, n: int) -> float:
    with Client(port=port) as c:
        c.example_cell("joints")
        c.simulate("path", 0.01)
        for _ in range(200):  # warm up
            _ = c.sim_time
        t0 = time.perf_counter()
        for _ in range(n):
            _ = c.sim_time
        return n / (time.perf_counter() - t0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--round-trips", type=int, default=5000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    server, port = start_server()
    try:
        rates = [round_trips(port, args.round_trips) for _ in range(3)]
        rate = sorted(rates)[1]
        ok = "ok" if rate >= 2000 else "BELOW TARGET"
        print(
            f"round trips of sim_time over loopback: {rate:,.0f}/s (median of 3; target >= 2,000: {ok})"
        )
        print(f"  = {1e6 / rate:.0f} us per request and reply")
        print()
        print(f"{'program':22s} {'in-process ms':>14s} {'remote ms':>10s} {'remote / local':>15s}")
        client = Client(port=port)
        for label, (example, module_name) in EXAMPLES.items():
            try:
                module = importlib.import_module(module_name)
            except ModuleNotFoundError:
                print(f"{label:22s} (cell not available yet)")
                continue

            def local(module=module) -> None:
                module.program(Simulator(module.build(), mode="path", dt=0.01))

            def remote(example=example, module=module) -> None:
                client.example_cell(example)
                client.simulate("path", 0.01)
                module.program(client)

            t_remote, t_local = paired_median_times(remote, local, args.repeat)
            ratio = t_remote / t_local
            ok = "ok" if ratio <= 2 else "ABOVE TARGET"
            print(f"{label:22s} {t_local * 1e3:14.1f} {t_remote * 1e3:10.1f} {ratio:15.2f}  ({ok})")
        client.close()
        print("(both include building and compiling the cell; target remote / local <= 2)")
    finally:
        server.terminate()
        server.wait(10)


if __name__ == "__main__":
    main()
