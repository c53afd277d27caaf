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


def _run_on_cell(program: str, cell: Any) -> Any:
    """Run the script ``program`` on ``cell``: its lines up to its first ``simulate`` (which
    build or load a cell) are skipped and that line's mode and dt start the simulation
    (path, 0.01 s without one); returns the simulator."""
    from workcell.errors import ProgramError
    from workcell.files import read_text
    from workcell.program.interpreter import Interpreter, check_script, split_at_simulate
    from workcell.program.session import Session
    from workcell.sim import Simulator

    text = read_text(program)
    check_script(text, program)
    split = split_at_simulate(text)
    if split.again:
        raise ProgramError(
            f"{program}:{split.again}: export-program runs one simulation; this line starts or "
            "stops another"
        )
    first = split.simulate
    mode, dt = ("path", 0.01) if first is None else (first.mode, first.dt)
    sim = Simulator(cell, mode=mode, dt=dt)
    interp = Interpreter(Session(sim=sim, base_dir=Path(program).parent), lambda text: None)
    for i, line in split.lines:
        if i > split.at:
            interp.run_line(line, f"{program}:{i}: ")
    return sim


def _export_program(args: argparse.Namespace) -> int:
    from workcell.examples import load_cell
    from workcell.robotprog import export

    signals = _signals(args.signal)
    sim = _run_on_cell(args.program, load_cell(args.cell))
    name = Path(args.program).stem
    target = Path(args.out) / f"{name}{_SUFFIX[args.language]}"
    for path in export(sim, args.robot, target, language=args.language, signals=signals):
        print(f"written {path}")
    print(f"simulated cycle time {sim.sim_time:.6f} s")
    return 0


def register(sub: Any) -> None:
    """Add ``export-program`` to the argparse subparsers ``sub``."""
    p = sub.add_parser(
        "export-program",
        help="write a robot's program, as it ran in a simulation, in URScript, KRL, RAPID "
        "or FANUC TP (docs/robot-programs.md)",
        description="Run FILE.wcl on CELL (the script's lines up to its first 'simulate', "
        "which build or load a cell, are skipped; that line's mode and dt are used) and "
        "write what robot R did in the robot language: workcell export-program "
        "cell.json --program pick.wcl --robot puma --language krl --out out/ (writes "
        "out/pick.src and out/pick.dat).",
    )
    p.add_argument("cell", metavar="CELL", help=CELL_HELP)
    p.add_argument("--program", metavar="FILE.wcl", required=True, help="the program to run")
    p.add_argument("--robot", metavar="R", required=True, help="the robot whose program to write")
    p.add_argument("--language", choices=tuple(_SUFFIX), required=True)
    p.add_argument("--out", metavar="DIR", required=True, help="the folder to write into")
    p.add_argument(
        "--signal",
        action="append",
        metavar="NAME=N",
        help="the I/O number of a signal (gripper=3); others are numbered from 1",
    )
    p.set_defaults(func=_export_program)
