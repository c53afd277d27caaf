"""Run command-language lines and ``.wcl`` scripts on a session.

A script is read as a whole and every line's syntax is checked first (keywords, numbers,
units), so a typo on line 40 is reported before line 1 moves anything. Then the lines
run one after another, each parsed against the session as it is by then (so names
created by earlier lines are known and checked). The first error stops the script, as
an error stops the thesis's programs: it is raised with its own type (JointLimitError,
ModelError, ...) and its message starts with ``FILE:LINE:``; what the earlier lines did
stays done, and the failed command itself changed nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

from workcell.errors import ProgramError, WorkcellError
from workcell.files import read_text
from workcell.program.base import Command
from workcell.program.format import format_result
from workcell.program.keytree import CommandSyntaxError
from workcell.program.language import Meta, help_text, parse_line
from workcell.program.lexer import split_lines
from workcell.program.runcommands import Simulate, StopSimulation
from workcell.program.session import Session

__all__ = [
    "Interpreter",
    "QuitRequest",
    "ScriptSplit",
    "check_script",
    "run_script",
    "split_at_simulate",
]


class QuitRequest(Exception):  # noqa: N818 - a request, not an error
    """Raised by the ``quit`` command to end the shell."""


def _locate(exc: WorkcellError, where: str, line: str) -> WorkcellError:
    if isinstance(exc, CommandSyntaxError):
        return exc.locate(where, line)
    exc.args = (f"{where}{exc}",)
    return exc


class Interpreter:
    """Parses and runs lines on ``session``; ``out`` receives the text of each result,
    ``clear`` is called for the ``clear`` command (the shell clears a terminal's screen)."""

    def __init__(
        self,
        session: Session,
        out: Callable[[str], Any] = print,
        clear: Callable[[], Any] = lambda: None,
    ) -> None:
        self.session, self.out, self.clear = session, out, clear

    def run_line(self, line: str, where: str = "") -> list[Any]:
        """Run every command on ``line``; returns their results.

        Raises the command's WorkcellError (message prefixed by ``where``) at the first
        failure; QuitRequest for ``quit``.
        """
        results = []
        parsed = parse_line(line, self.session)  # the line's syntax is checked here, then
        while True:  # each command's names when it comes, after the ones before it ran
            try:
                item = next(parsed, None)
            except WorkcellError as exc:
                raise _locate(exc, where, line) from None
            if item is None:
                return results
            if isinstance(item, Meta):
                if item.kind == "quit":
                    raise QuitRequest
                if item.kind == "clear":
                    self.clear()
                else:
                    self.out(help_text(item.topic))
                results.append(None)
                continue
            results.append(self.run_command(item, where, line))

    def run_command(self, command: Command, where: str = "", line: str = "") -> Any:
        """Run one command, print its result; errors get ``where`` in front."""
        try:
            result = self.session.execute(command)
        except WorkcellError as exc:
            raise _locate(exc, where, line) from None
        text = format_result(command, result, self.session)
        if text:
            self.out(text)
        return result


def check_script(text: str, name: str = "<script>") -> int:
    """Check the syntax of every line of a script (no names); returns the command count.

    Raises the first CommandSyntaxError (or ProgramError) with ``name:line:`` in front.
    """
    n = 0
    for i, line in enumerate(split_lines(text), 1):
        try:
            n += len(list(parse_line(line)))
        except WorkcellError as exc:
            raise _locate(exc, f"{name}:{i}: ", line) from None
    return n


class ScriptSplit(NamedTuple):
    """A script cut at its first ``simulate`` command (:func:`split_at_simulate`)."""

    lines: list[tuple[int, str]]  # (line number from 1, text): every line of the script
    at: int  # the line of the first simulate command (0: none)
    simulate: Simulate | None  # that command (its mode and dt)
    again: int  # the first line after it that starts or stops a simulation (0: none)


def split_at_simulate(text: str) -> ScriptSplit:
    """Where the script ``text`` (its syntax checked: :func:`check_script`) starts its
    simulation, and where it starts or stops another after that: the lines before and at
    ``at`` build or load the cell, those after it run on the simulation."""
    lines = list(enumerate(split_lines(text), 1))
    at, first = 0, None
    for i, line in lines:
        commands = list(parse_line(line))
        sims = [c for c in commands if isinstance(c, Simulate)]
        if sims and not at:
            at, first = i, sims[0]
        elif at and any(isinstance(c, (Simulate, StopSimulation)) for c in commands):
            return ScriptSplit(lines, at, first, i)
    return ScriptSplit(lines, at, first, 0)


def run_script(
    path: str | Path,
    session: Session | None = None,
    *,
    out: Callable[[str], Any] = print,
    echo: bool = False,
) -> Session:
    """Run the ``.wcl`` script at ``path`` on ``session`` (default: a new session whose
    relative file names are taken from the script's folder); returns the session.

    ``echo`` prints each line before its output, as ``> line``. A ``quit`` line ends the
    script early.
    """
    p = Path(path)
    text = read_text(p, what="script", error=ProgramError)
    check_script(text, str(p))
    if session is None:
        session = Session(base_dir=p.parent)
    interp = Interpreter(session, out)
    for i, line in enumerate(split_lines(text), 1):
        if echo and line.strip() and not line.lstrip().startswith("#"):
            out(f"> {line}")
        try:
            interp.run_line(line, f"{p}:{i}: ")
        except QuitRequest:
            break
    return session
