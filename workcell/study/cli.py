"""The ``workcell study`` subcommand (added to ``workcell`` by ``register``).

Top-level imports stay light: ``workcell --help`` imports this module.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from workcell.examples import CELLS

__all__ = ["register"]

_EPILOG = """\
parameters (--vary NAME=VALUES, repeat for each):
  ROBOT.base.x|y|z (m), ROBOT.base.yaw (deg)   where the robot stands
  ROBOT.robot (names)                           which robot stands there
  ROBOT.speed (rad/s)                           its speed, pinned (the program's own
                                                speed commands for it are overridden)
  ROBOT.override (0..1)                         its speed override (set_override), pinned
  PART.x|y|z (m), PART.yaw (deg)                where a static or movable part is
values: LO:HI:N (N values), LO:HI (a range, with --sample), A,B,C (a list)

example:
  workcell study --example pick-place --vary puma.base.x=-0.1:0.1:5 \\
      --vary puma.base.y=-0.1:0.1:5 --out placement
"""


def _study(args: argparse.Namespace) -> int:
    from workcell.errors import StudyError
    from workcell.study.results import summary
    from workcell.study.runner import execute
    from workcell.study.spec import Study

    if args.cell and not args.program:
        raise StudyError("--cell needs --program FILE.wcl (the program to run on it)")
    if not (args.example or args.cell or args.program):
        raise StudyError("give --example NAME, or --cell FILE --program FILE.wcl")
    if not args.vary:
        raise StudyError("give at least one --vary NAME=VALUES (see workcell study --help)")
    study = Study(
        cell=args.example or args.cell,
        program=args.program,
        vary=args.vary,
        sample=args.sample,
        seed=args.seed,
        mode=args.mode,
        dt=args.dt,
    )
    try:
        outcome = execute(
            study,
            args.out,
            backend_name=args.backend,
            workers=args.workers,
            address=args.address,
            batch_size=args.batch_size,
            retries=args.retries,
            plots=not args.no_plots,
            record=args.record_best,
        )
    except KeyboardInterrupt:
        print(
            f"\ninterrupted: the rows done are in {args.out}/results.parquet; the same "
            "command again does the rest",
            file=sys.stderr,
        )
        return 130
    b = outcome.backend
    done = f"{outcome.evaluated} candidate(s) evaluated"
    if outcome.resumed:
        done += f", {outcome.resumed} already done"
    rate = f"{outcome.throughput:.2f}/s" if outcome.evaluated else "-"
    print(f"{done} in {outcome.wall_s:.1f} s ({rate}; backend {b.name}, {b.workers} worker(s))")
    print(summary(outcome.table, outcome.setup.parameters, top=args.top))
    print(f"results: {outcome.out / 'results.parquet'}")
    for what, path in outcome.files.items():
        print(f"{what}: {path}")
    if not args.no_plots and "histogram" not in outcome.files:
        print(
            f"no cycle-time histogram: none of the {outcome.table.num_rows} candidate(s) is "
            "feasible (results.parquet's error column says why)"
        )
    return 0


def register(sub: Any) -> None:
    """Add ``study`` to the argparse subparsers ``sub``."""
    p = sub.add_parser(
        "study",
        help="run a program over many variants of a cell (placements, robots, speeds)",
        description="Run a program on every candidate of a grid (or a random sample) of cell "
        "variants, headless, and write one row per candidate to OUT/results.parquet: "
        "feasible, cycle time, clearance, reach and joint-limit margins, the error when not "
        "feasible. A re-run into the same OUT skips the candidates done.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    g = p.add_mutually_exclusive_group()
    g.add_argument("--example", choices=tuple(CELLS), help="an example cell (and its program)")
    g.add_argument("--cell", metavar="FILE", help="a cell saved by Workcell.save (.json)")
    p.add_argument(
        "--program",
        metavar="FILE.wcl",
        help="the program (command language); its lines up to 'simulate' set the cell up "
        "and are skipped when --cell or --example is given",
    )
    p.add_argument(
        "--vary",
        action="append",
        metavar="NAME=VALUES",
        default=[],
        help="a parameter and its values (below); once per parameter",
    )
    p.add_argument("--sample", type=int, metavar="N", help="N random candidates, not the grid")
    p.add_argument("--seed", type=int, default=0, help="seed of --sample (0)")
    p.add_argument("--out", metavar="DIR", required=True, help="output folder")
    p.add_argument(
        "--backend",
        choices=("serial", "process", "ray"),
        default="process",
        help="one process, a local process pool (default) or Ray",
    )
    p.add_argument("--workers", type=int, metavar="N", help="processes or Ray CPUs (one per core)")
    p.add_argument("--address", metavar="auto|HOST:PORT", help="a running Ray cluster to use")
    p.add_argument("--batch-size", type=int, metavar="N", help="candidates per task")
    p.add_argument(
        "--retries", type=int, default=2, help="retries of a candidate whose worker dies"
    )
    p.add_argument("--mode", choices=("path", "joint-by-joint", "playback"), help="simulation mode")
    p.add_argument("--dt", type=float, metavar="SECONDS", help="sampling interval")
    p.add_argument("--top", type=int, default=5, help="best candidates to list (5)")
    p.add_argument("--record-best", metavar="FILE.rrd", help="record the best candidate's run")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    p.set_defaults(func=_study)
