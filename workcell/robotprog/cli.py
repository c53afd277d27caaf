"""``workcell run CELL --robot-program R=FILE``: robot programs run on a cell (the ``run``
subcommand of :mod:`workcell.program.cli` calls :func:`run_robot_programs`).
"""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["run_robot_programs"]


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
