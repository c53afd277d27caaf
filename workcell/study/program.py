"""The program a study runs on every candidate: a Python function or a ``.wcl`` script.

A function program is called as ``program(sim)`` on the candidate's simulator; it must be
defined at module level (worker processes import it by name; Ray ships functions of a
notebook or script by value).

A script is read and syntax-checked once, in the process that sets the study up, and its
text travels to the workers (a Ray cluster's machines need not see the file). It splits
at its first ``simulate`` command:

- the *setup*, the lines up to and including that command, builds the cell and starts
  the simulation; a study given a cell of its own (an example or a cell file) skips the
  setup, and a study given none builds its cell by running the setup once;
- the ``simulate`` line gives the mode and dt (unless the study sets them);
- the *body*, the lines after it, runs on each candidate's simulator. It may not start
  or stop simulations (``simulate``), which would leave the study's simulator.

A script without ``simulate`` is all body. Relative file names in the script are taken
from its folder, as ``workcell run`` does.
"""

from __future__ import annotations

import abc
import hashlib
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from workcell.errors import StudyError, WorkcellError
from workcell.files import read_text

if TYPE_CHECKING:
    from workcell.cell.workcell import Workcell
    from workcell.sim.simulator import Simulator

__all__ = ["FunctionProgram", "Program", "ScriptProgram", "program_of"]


class Program(abc.ABC):
    """What runs on each candidate's simulator."""

    mode: str | None = None  # from a script's simulate line
    dt: float | None = None

    @abc.abstractmethod
    def run(self, sim: Simulator) -> None:
        """Run the program on ``sim`` (raises the failing command's WorkcellError)."""

    @abc.abstractmethod
    def describe(self) -> dict[str, Any]:
        """What identifies the program (for the study's fingerprint)."""


@dataclass(frozen=True)
class FunctionProgram(Program):
    """A Python function ``function(sim)``."""

    function: Callable[[Simulator], object]

    def run(self, sim: Simulator) -> None:
        self.function(sim)

    def describe(self) -> dict[str, Any]:
        f = self.function
        name = f"{getattr(f, '__module__', '?')}.{getattr(f, '__qualname__', repr(f))}"
        return {"function": name}


def _quiet(_: str) -> None:
    return None


@dataclass
class ScriptProgram(Program):
    """A command-language script (module doc): its ``name`` (the path as given), ``text``
    and the folder relative file names start from."""

    name: str
    text: str
    base_dir: str
    setup: list[tuple[int, str]] = field(default_factory=list)
    body: list[tuple[int, str]] = field(default_factory=list)
    mode: str | None = None
    dt: float | None = None
    _parsed: list[tuple[int, str, list[Any]]] | None = field(default=None, repr=False)

    @classmethod
    def read(cls, path: str | os.PathLike) -> ScriptProgram:
        """Read and check the script at ``path``; StudyError or the syntax error otherwise."""
        from workcell.program.interpreter import check_script, split_at_simulate

        p = Path(path)
        if p.suffix != ".wcl":
            raise StudyError(f"a study's program file is a .wcl script, got '{p}'")
        text = read_text(p, what="program", error=StudyError)
        check_script(text, str(p))
        prog = cls(str(p), text, str(p.parent.resolve()))
        split = split_at_simulate(text)
        if split.again:
            raise StudyError(
                f"{p}:{split.again}: a study's program runs on the study's simulator: it may "
                f"start one simulation (line {split.at}) before its motion commands, and no other"
            )
        if split.simulate is not None:
            prog.mode, prog.dt = split.simulate.mode, split.simulate.dt
        prog.setup = [(i, ln) for i, ln in split.lines if i <= split.at]
        prog.body = [(i, ln) for i, ln in split.lines if i > split.at]
        return prog

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state["_parsed"] = None  # parsed again in each process
        return state

    def build_cell(self) -> Workcell:
        """The cell the script's setup builds (StudyError when it builds none)."""
        from workcell.program.interpreter import Interpreter
        from workcell.program.session import Session

        session = Session(base_dir=self.base_dir)
        interp = Interpreter(session, _quiet)
        for i, line in self.setup:
            interp.run_line(line, f"{self.name}:{i}: ")
        if session.cell is None:
            raise StudyError(
                f"program '{self.name}' builds no cell before its 'simulate' line; "
                "give the study a cell (--cell FILE or --example NAME)"
            )
        return session.cell

    def run(self, sim: Simulator) -> None:
        from workcell.program.interpreter import Interpreter
        from workcell.program.language import Meta, parse_line
        from workcell.program.session import Session

        if self._parsed is None:
            self._parsed = [(i, ln, list(parse_line(ln))) for i, ln in self.body]
        interp = Interpreter(Session(sim=sim, base_dir=self.base_dir), _quiet)
        for i, line, commands in self._parsed:
            for c in commands:
                if isinstance(c, Meta):
                    if c.kind == "quit":
                        return
                    continue
                interp.run_command(c, f"{self.name}:{i}: ", line)

    def describe(self) -> dict[str, Any]:
        digest = hashlib.sha256(self.text.encode("utf-8")).hexdigest()
        return {"script": self.name, "sha256": digest}


def program_of(program: object, example: str | None) -> Program:
    """The :class:`Program` for a study's ``program`` (a path, a function or None: the
    example's own program)."""
    if isinstance(program, Program):
        return program
    if isinstance(program, (str, os.PathLike)):
        return ScriptProgram.read(program)
    if callable(program):
        return FunctionProgram(program)
    if program is None and example is not None:
        from workcell.examples import example as example_module

        try:
            return FunctionProgram(example_module(example).program)
        except WorkcellError as exc:
            raise StudyError(str(exc)) from exc
    raise StudyError(
        "a study needs a program: a .wcl script or a function program(sim) "
        "(an example cell brings its own)"
    )
