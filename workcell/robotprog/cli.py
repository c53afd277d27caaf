"""The ``export-program`` subcommand and ``workcell run CELL --robot-program R=FILE``.

Top-level imports stay light: ``workcell --help`` imports this module.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from workcell.examples import CELL_HELP

__all__ = ["register", "run_robot_programs"]

LANGUAGES = ("urscript", "krl", "rapid", "fanuc_ls")
_SUFFIX = {"urscript": ".script", "krl": ".src", "rapid": ".mod", "fanuc_ls": ".ls"}


def _signals(items: list[str] | None) -> dict[str, int]:
    from workcell.errors import ProgramError

    out: dict[str, int] = {}
    for item in items or []:
        name, _, n = item.partition("=")
        if not name or not n.strip().isdigit():
            raise ProgramError(f"--signal takes NAME=NUMBER (e.g. gripper=3), got {item!r}")
        out[name] = int(n)
    return out


def _export_program(args: argparse.Namespace) -> int:
    from workcell.examples import load_cell
    from workcell.robotprog import export
    from workcell.sim import Simulator
    from workcell.study.program import ScriptProgram

    signals = _signals(args.signal)
    cell = load_cell(args.cell)
    program = ScriptProgram.read(args.program)
    sim = Simulator(cell, mode=program.mode or "path", dt=program.dt or 0.01)
    program.run(sim)
    name = Path(args.program).stem
    target = Path(args.out) / f"{name}{_SUFFIX[args.language]}"
    for path in export(sim, args.robot, target, language=args.language, signals=signals):
        print(f"written {path}")
    print(f"simulated cycle time {sim.sim_time:.6f} s")
    return 0


def run_robot_programs(args: argparse.Namespace, keep: list[Any]) -> Any:
    """``workcell run CELL --robot-program R=FILE ...``: run each robot's program on the
    cell, one after another in the order given (every file is read and checked first).
    The simulator is appended to ``keep`` before anything runs (the caller writes what
    ran when a program fails); returns it."""
    from workcell.errors import ProgramError, WorkcellError
    from workcell.examples import load_cell
    from workcell.robotprog import load
    from workcell.sim import Simulator

    pairs = []
    for item in args.robot_program:
        robot, _, path = item.partition("=")
        if not robot or not path:
            raise ProgramError(f"--robot-program takes ROBOT=FILE, got {item!r}")
        pairs.append((robot, load(path)))
    sim = Simulator(load_cell(args.script))
    keep.append(sim)
    for robot, program in pairs:
        try:
            program.run(sim, robot)
        except WorkcellError as exc:
            sim._log_error(exc, robot if robot in sim.robots else None)
            raise
    print(f"simulated cycle time {sim.sim_time:.6f} s")
    return sim


def register(sub: Any) -> None:
    """Add ``export-program`` to the argparse subparsers ``sub``."""
    p = sub.add_parser(
        "export-program",
        help="write a robot's program, as it ran in a simulation, in URScript, KRL, RAPID "
        "or FANUC TP (docs/robot-programs.md)",
        description="Run FILE.wcl on CELL and write what robot R did as a program in the "
        "robot language: workcell export-program cell.json --program pick.wcl --robot puma "
        "--language krl --out out/ (writes out/pick.src and out/pick.dat).",
    )
    p.add_argument("cell", metavar="CELL", help=CELL_HELP)
    p.add_argument("--program", metavar="FILE.wcl", required=True, help="the program to run")
    p.add_argument("--robot", metavar="R", required=True, help="the robot whose program to write")
    p.add_argument("--language", choices=LANGUAGES, required=True)
    p.add_argument("--out", metavar="DIR", required=True, help="the folder to write into")
    p.add_argument(
        "--signal",
        action="append",
        metavar="NAME=N",
        help="the I/O number of a signal (gripper=3); others are numbered from 1",
    )
    p.set_defaults(func=_export_program)
