"""Set a study up in the process that runs it: its cell, program, checks and fingerprint.

:func:`prepare` turns a :class:`~workcell.study.spec.Study` into the
:class:`~workcell.study.evaluation.Setup` the workers get, after checking every
parameter against the cell (robots and parts by name, robot choices by adding each
chosen robot once). Its ``key`` is a fingerprint of everything that decides the rows
(the cell or its file's contents, the program or its script's text, the parameters,
sample, seed, mode, dt, clearance settings and work limits): a re-run into an output folder holding
another study's results is refused, not mixed in.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path
from typing import Any

from workcell import limits
from workcell.cell.workcell import Workcell
from workcell.errors import StudyError, WorkcellError
from workcell.files import read_bytes
from workcell.study.evaluation import Setup
from workcell.study.program import Program, ScriptProgram, program_of
from workcell.study.spec import PART_FIELDS, ROBOT_FIELDS, Parameter, Study
from workcell.study.variants import rebuild

__all__ = ["FORMAT_VERSION", "describe", "prepare"]

FORMAT_VERSION = 1  # of the rows: bump when a column's meaning changes


def _cell_of(study: Study, program: Program) -> tuple[Workcell, dict[str, Any]]:
    """The study's cell and what identifies it."""
    from workcell.examples import CELLS, example

    cell = study.cell
    if isinstance(cell, Workcell):
        try:
            data = json.dumps(cell.to_dict(), sort_keys=True)
            return cell, {"cell": hashlib.sha256(data.encode()).hexdigest()}
        except WorkcellError:  # a custom robot: not saveable, identified by name only
            return cell, {"cell": cell.name, "saveable": False}
    if cell is None:
        if not isinstance(program, ScriptProgram):
            raise StudyError("a study needs a cell: an example name, a cell file or a Workcell")
        return program.build_cell(), {"cell": "built by the program"}
    if isinstance(cell, str) and cell in CELLS:
        return example(cell).build(), {"example": cell}
    path = Path(cell)
    if not path.is_file():
        raise StudyError(
            f"no cell file '{cell}' and no example cell of that name; examples: {', '.join(CELLS)}"
        )
    try:
        loaded = Workcell.load(path)
    except WorkcellError as exc:
        raise StudyError(str(exc)) from exc
    digest = hashlib.sha256(read_bytes(path, what="cell file", error=StudyError)).hexdigest()
    return loaded, {"file": str(path), "sha256": digest}


def _check(parameters: tuple[Parameter, ...], cell: Workcell) -> None:
    parts = [*cell.static_parts, *cell.movable_parts]
    for p in parameters:
        if p.target in cell.robots:
            if p.field not in ROBOT_FIELDS:
                raise StudyError(
                    f"parameter {p.name!r}: '{p.target}' is a robot; robot fields: "
                    f"{', '.join(ROBOT_FIELDS)}"
                )
        elif p.target in parts:
            if p.field not in PART_FIELDS:
                raise StudyError(
                    f"parameter {p.name!r}: '{p.target}' is a part; part fields: "
                    f"{', '.join(PART_FIELDS)}"
                )
        else:
            raise StudyError(
                f"parameter {p.name!r}: no robot or part '{p.target}' in cell '{cell.name}'; "
                f"robots: {', '.join(cell.robots) or 'none'}; parts: {', '.join(parts) or 'none'}"
            )
        if p.field == "robot":
            for name in p.values:
                try:
                    rebuild(cell, robots={p.target: str(name)})
                except WorkcellError as exc:
                    raise StudyError(f"parameter {p.name!r}: {exc}") from exc


def describe(study: Study, setup: Setup, cell_id: dict[str, Any]) -> dict[str, Any]:
    """The study as JSON-able data (what the fingerprint hashes)."""
    return {
        "format": FORMAT_VERSION,
        "cell": cell_id,
        "program": setup.program.describe(),
        "parameters": [p.to_dict() for p in setup.parameters],
        "sample": study.sample,
        "seed": study.seed if study.sample is not None else None,
        "mode": setup.mode,
        "dt": setup.dt,
        "clearance_cutoff": setup.clearance_cutoff,
        "clearance_tolerance": setup.clearance_tolerance,
        "limits": dataclasses.asdict(setup.limits),
    }


def prepare(study: Study) -> tuple[Setup, dict[str, Any]]:
    """The workers' :class:`Setup` of ``study`` and its description (module doc)."""
    from workcell.examples import CELLS
    from workcell.sim.simulator import MODES

    example = study.cell if isinstance(study.cell, str) and study.cell in CELLS else None
    program = program_of(study.program, example)
    cell, cell_id = _cell_of(study, program)
    _check(study.parameters, cell)
    mode = study.mode or program.mode or "path"
    if mode not in MODES:
        raise StudyError(f"unknown simulation mode {mode!r}; valid: {', '.join(MODES)}")
    dt = float(study.dt or program.dt or 0.01)
    setup = Setup(
        key="",
        cell=cell,
        program=program,
        parameters=study.parameters,
        mode=mode,
        dt=dt,
        clearance_cutoff=float(study.clearance_cutoff),
        clearance_tolerance=float(study.clearance_tolerance),
        limits=limits.current(),
    )
    info = describe(study, setup, cell_id)
    key = hashlib.sha256(json.dumps(info, sort_keys=True).encode()).hexdigest()[:16]
    return dataclasses.replace(setup, key=key), info
