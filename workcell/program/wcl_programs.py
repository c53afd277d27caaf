"""``.wcl`` files as programs of ``run_programs`` (:mod:`workcell.logic`).

:func:`program_body` reads a ``.wcl`` file and checks its syntax whole (before any
program runs), and returns the program's body: its lines, run one after another on a
:func:`program_session` of the program's view of the simulator
(:class:`~workcell.logic.programs.ProgramSim`), what they print kept in the program's
``output``. The scheduler sits below the command language, so the language plugs this
loader in (:data:`workcell.logic.programs.PROGRAM_FILES`, when :mod:`workcell.program` is
imported; the installed package also names it as an entry point).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from workcell.errors import ProgramError
from workcell.files import read_text
from workcell.logic.programs import PROGRAM_FILES
from workcell.program.interpreter import Interpreter, QuitRequest, check_script
from workcell.program.lexer import split_lines
from workcell.program.session import Session

__all__ = ["program_body", "program_session"]


def program_body(path: Path, root: str | os.PathLike | None, name: str) -> Callable[[Any], None]:
    """The body of the ``.wcl`` program at ``path`` (``name``: how the run calls the
    file); its syntax is checked now (ProgramError with ``FILE:LINE:``)."""
    text = read_text(path, what="program", error=ProgramError)
    check_script(text, name)

    def body(view: Any) -> None:
        session = program_session(view, base_dir=path.parent, root=root)
        interp = Interpreter(session, view._program.output.append)
        for i, line in enumerate(split_lines(text), 1):
            try:
                interp.run_line(line, f"{path}:{i}: ")
            except QuitRequest:
                return

    return body


class _ProgramSession(Session):
    """A session that refuses to replace its cell or simulator once made."""

    _locked = False

    def __setattr__(self, name: str, value: Any) -> None:
        if self._locked and name in ("sim", "cell", "_model"):
            raise ProgramError(
                "this cannot run inside a program of run_programs: it would replace the "
                "cell or the simulation all programs share"
            )
        super().__setattr__(name, value)


def program_session(view: Any, *, base_dir: Path, root: Any) -> Session:
    """A :class:`~workcell.program.session.Session` on a program's view of the simulator
    that refuses to replace its cell or simulator."""
    s = _ProgramSession(sim=view, base_dir=base_dir, root=root)
    s._locked = True
    return s


PROGRAM_FILES[".wcl"] = program_body
