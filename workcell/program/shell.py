"""``workcell shell``: the interactive command line (the thesis's key tree matcher at a prompt).

On a terminal it uses prompt_toolkit: Tab completes keywords and the names the session
knows (entities, relations, robots, parts), Up/Down walk the history (kept in a file),
``help`` explains, ``clear`` clears the screen, ``quit`` or ``exit`` (or Ctrl-D) leaves.
When standard input is not a terminal it reads lines from it, one
command line at a time, the same way (this is how tests and pipes drive it). An error
is printed with its type and the shell goes on, as the thesis's matcher returns to the
prompt; the exit status is 1 when any command failed, else 0.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from pathlib import Path
from typing import TextIO

from workcell.errors import WorkcellError
from workcell.program.interpreter import Interpreter, QuitRequest
from workcell.program.session import Session

__all__ = ["BANNER", "PROMPT", "run_shell"]

PROMPT = "workcell> "
BANNER = (
    "workcell shell: type 'help' for the commands, 'help WORDS' for one; Tab completes;\n"
    "'quit' or 'exit' leaves.\n"
    "Angles in degrees and lengths in metres unless a unit says otherwise."
)


def _report(exc: WorkcellError, err: TextIO) -> None:
    print(f"{type(exc).__name__}: {exc}", file=err)


def _run_lines(
    lines: Iterable[str], interp: Interpreter, out: TextIO, err: TextIO, echo: bool
) -> int:
    failed = False
    for line in lines:
        line = line.rstrip("\n")
        if echo:
            print(f"{PROMPT}{line}", file=out)
            out.flush()  # before any error message on stderr
        try:
            interp.run_line(line)
        except QuitRequest:
            break
        except WorkcellError as exc:
            failed = True
            _report(exc, err)
        out.flush()
    return 1 if failed else 0


def run_shell(
    session: Session | None = None,
    *,
    stdin: TextIO | None = None,
    stdout: TextIO | None = None,
    stderr: TextIO | None = None,
    history: str | Path | None = None,
    echo: bool = False,
    interactive: bool | None = None,
) -> int:
    """Run the shell on ``session`` until ``quit``/``exit`` or end of input; returns the exit
    status.

    ``history``: the history file of the terminal prompt (None: ``~/.workcell_history``).
    ``echo``: without a terminal, print each line after the prompt before its output (a
    transcript). ``interactive``: use the prompt_toolkit prompt (None: when standard
    input and output are terminals).
    """
    session = Session() if session is None else session
    stdin = sys.stdin if stdin is None else stdin
    out = sys.stdout if stdout is None else stdout
    err = sys.stderr if stderr is None else stderr

    def write(text: str) -> None:
        print(text, file=out)

    if interactive is None:
        interactive = stdin.isatty() and out.isatty()
    if not interactive:  # 'clear' does nothing in a pipe or a transcript
        return _run_lines(stdin, Interpreter(session, write), out, err, echo)
    from prompt_toolkit import PromptSession
    from prompt_toolkit.history import FileHistory
    from prompt_toolkit.shortcuts import clear

    interp = Interpreter(session, write, clear=clear)

    from workcell.program.completion import WorkcellCompleter

    path = Path(history) if history is not None else Path.home() / ".workcell_history"
    prompt = PromptSession(
        history=FileHistory(str(path)),
        completer=WorkcellCompleter(session),
        complete_while_typing=False,
    )
    print(BANNER, file=out)
    failed = False
    while True:
        try:
            line = prompt.prompt(PROMPT)
        except KeyboardInterrupt:
            continue
        except EOFError:
            break
        try:
            interp.run_line(line)
        except QuitRequest:
            break
        except WorkcellError as exc:
            failed = True
            _report(exc, err)
    return 1 if failed else 0
