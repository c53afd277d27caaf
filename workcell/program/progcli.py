"""The ``export-program`` subcommand (added to ``workcell`` by ``register``): run a
``.wcl`` program on a cell and write what one robot did in a robot language.

Top-level imports stay light: ``workcell --help`` imports this module.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from workcell.examples import CELL_HELP

__all__ = ["register"]

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
    from workcell.program.interpreter import run_script
    from workcell.program.session import Session
    from workcell.program.simcommands import Simulate
    from workcell.robotprog import export

    signals = _signals(args.signal)
    session = Session(base_dir=Path(args.program).parent)
    session.set_cell(load_cell(args.cell))
    session.execute(Simulate("path", 0.01))
    run_script(args.program, session, out=lambda text: None)
    if session.sim is None:
        from workcell.errors import ProgramError

        raise ProgramError(f"{args.program}: the script ended its simulation ('simulate stop')")
    name = Path(args.program).stem
    target = Path(args.out) / f"{name}{_SUFFIX[args.language]}"
    for path in export(session.sim, args.robot, target, language=args.language, signals=signals):
        print(f"written {path}")
    print(f"simulated cycle time {session.sim.sim_time:.6f} s")
    return 0


def register(sub: Any) -> None:
    """Add ``export-program`` to the argparse subparsers ``sub``."""
    p = sub.add_parser(
        "export-program",
        help="write a robot's program, as it ran in a simulation, in URScript, KRL, RAPID "
        "or FANUC TP (docs/robot-programs.md)",
        description="Load CELL, start simulating it (path mode, dt 0.01 s), run FILE.wcl "
        "(a script that loads or builds its own cell and starts its own simulation uses "
        "those) and write what robot R did in the robot language: workcell export-program "
        "cell.json --program pick.wcl --robot puma --language krl --out out/ (writes "
        "out/pick.src and out/pick.dat).",
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
