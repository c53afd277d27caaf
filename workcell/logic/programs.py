"""The programs ``run_programs`` runs: what each one is, and the simulator it sees.

A program is a Python callable ``f(sim)`` or a ``.wcl`` file of the command language,
under a name: a robot's name makes it that robot's program (it alone moves and grips
with that robot), any other name a *controller* program (it moves no robot; it sets and
waits for signals, waits, reads). :func:`programs_of` checks the mapping before anything
runs (a ``.wcl`` file is read and its syntax checked whole).

Each program sees the simulator through a :class:`ProgramSim`: every public method and
property of :class:`~workcell.sim.simulator.Simulator`, with these differences:

- a command for another program's robot is refused (ProgramError), and so are
  ``concurrently``, ``handover`` (two robots), ``set_mode``, ``play`` and
  ``run_programs`` (they belong outside);
- after a motion command the program waits until its robot has stopped, unless the
  move has a zone: then the program goes on at once (its robot is on its way, shown at
  the target), so that its next motion blends out of it; any other command first waits
  for the robot to stop;
- a program that makes :data:`MAX_CALLS_AT_ONE_TIME` calls without simulated time passing
  (a busy loop) gets a ProgramError.

A ``.wcl`` program runs in the command language on that view
(:mod:`workcell.program.wcl_programs`: lines that would replace the session's cell or
simulator, ``cell load``, ``simulate``, are refused; what its lines print is kept in the
run's result). The language lives above the simulator, so this package does not import
it: it plugs its loader into :data:`PROGRAM_FILES` (and names it as an entry point of
the installed package).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from workcell.checks import shown
from workcell.errors import ProgramError

if TYPE_CHECKING:
    from workcell.logic.scheduler import Run

__all__ = [
    "MAX_CALLS_AT_ONE_TIME",
    "MAX_PROGRAMS",
    "PROGRAM_FILES",
    "ROBOT_COMMANDS",
    "Program",
    "ProgramSim",
    "file_loader",
    "programs_of",
]

PROGRAM_FILES: dict[str, Callable[..., Callable[[Any], object]]] = {}
"""Loaders of program files by suffix: ``loader(path, root, name)`` checks the file (its
syntax, whole) and returns the program's body (a callable given the program's
:class:`ProgramSim`); the command language registers ".wcl" (:mod:`workcell.program`)."""
MAX_PROGRAMS = 64  # programs one run_programs may run
MAX_CALLS_AT_ONE_TIME = 100_000  # calls a program may make without simulated time passing
ROBOT_COMMANDS = frozenset(
    {
        "set_speed", "set_override", "move_joints_absolute", "move_joints_relative",
        "move_end_effector", "move_straight_line", "move_linear", "move_circular",
        "close_gripper", "open_gripper", "pick", "place", "jog",
    }
)  # fmt: skip
_OUTSIDE = {
    "concurrently": "programs run together already; give each robot its own program",
    "handover": "it moves two robots, and a program moves only its own; hand over with "
    "close_gripper and open_gripper in the two robots' programs and a signal between them",
    "set_mode": "the mode is the whole run's; set it before run_programs",
    "play": "replay after run_programs",
    "run_programs": "programs do not nest",
}


@dataclass
class Program:
    """One program of a run: its ``name``, the ``robot`` it drives (None: a controller),
    its ``body`` (called in its own thread with its :class:`ProgramSim`), ``file`` (a
    ``.wcl`` program's path), its ``output`` lines, and its state while it runs (see
    :mod:`workcell.logic.scheduler`)."""

    name: str
    robot: str | None
    body: Callable[[Any], object]
    file: Path | None = None
    output: list[str] = field(default_factory=list)
    state: str = "ready"
    wake: float = float("inf")
    waits_for: tuple[str, Any] | None = None
    deadline: float | None = None
    matched: bool = False
    since: float = 0.0
    error: BaseException | None = None
    t_end: float | None = None
    calls: int = 0
    calls_at: float = -1.0
    thread: Any = None


def programs_of(
    sim: Any,
    programs: object,
    *,
    root: str | os.PathLike | None = None,
) -> list[Program]:
    """The programs of ``programs`` (name -> callable or ``.wcl`` path), checked: names
    are strings, at most :data:`MAX_PROGRAMS`, a ``.wcl`` file exists and its syntax is
    right. ``root``: file names resolve inside it (a server's folder)."""
    if not isinstance(programs, Mapping) or not programs:
        raise ProgramError(
            "run_programs: programs must be a non-empty mapping of names to callables f(sim) "
            f"or .wcl files, got {shown(programs)}"
        )
    if len(programs) > MAX_PROGRAMS:
        raise ProgramError(
            f"run_programs: {len(programs)} programs; at most {MAX_PROGRAMS} run together"
        )
    out = []
    for name, body in programs.items():
        if not isinstance(name, str) or not name or len(name) > 100:
            raise ProgramError(
                f"run_programs: a program name must be a short string, got {shown(name)}"
            )
        robot = name if name in sim.robots else None
        if callable(body):
            out.append(Program(name, robot, body))
            continue
        if not isinstance(body, (str, os.PathLike)) or not str(body).endswith(".wcl"):
            raise ProgramError(
                f"run_programs: program '{name}' must be a callable f(sim) or a .wcl file, "
                f"got {shown(body)}"
            )
        path = _resolve(body, root)
        loader = file_loader(".wcl")
        if loader is None:
            raise ProgramError(
                f"run_programs: program '{name}': .wcl files run in the command language, "
                "which is not loaded: import workcell.program first (or install the package)"
            )
        out.append(Program(name, robot, loader(path, root, str(body)), file=path))
    return out


def _resolve(path: str | os.PathLike, root: str | os.PathLike | None) -> Path:
    if root is not None:
        from workcell.files import resolve_inside

        return resolve_inside(Path(root), str(path), error=ProgramError)
    return Path(path).expanduser()


def file_loader(suffix: str) -> Callable[..., Callable[[Any], object]] | None:
    """The loader of program files ending in ``suffix`` (".wcl"): registered in
    :data:`PROGRAM_FILES` by the layer that runs them (the command language,
    :mod:`workcell.program`, when it is imported), else found through the installed
    package's entry points (group ``workcell.program_files``), else None."""
    loader = PROGRAM_FILES.get(suffix)
    if loader is None:
        from importlib.metadata import entry_points

        for ep in entry_points(group="workcell.program_files"):
            if f".{ep.name}" == suffix:
                PROGRAM_FILES[suffix] = loader = ep.load()
    return loader


class ProgramSim:
    """What one program sees of the simulator (module doc)."""

    def __init__(self, run: Run, program: Program) -> None:
        object.__setattr__(self, "_run", run)
        object.__setattr__(self, "_program", program)

    def __getattr__(self, name: str) -> Any:
        run, prog = self._run, self._program
        value = getattr(run.sim, name)
        if name.startswith("_") or not callable(value):
            return value
        if name in _OUTSIDE:
            why = _OUTSIDE[name]

            def refused(*args: Any, **kwargs: Any) -> None:
                raise ProgramError(f"program '{prog.name}': {name} cannot run in a program: {why}")

            return refused

        def call(*args: Any, **kwargs: Any) -> Any:
            run.count_call(prog)
            if name in ROBOT_COMMANDS:
                robot = args[0] if args else kwargs.get("robot")
                run.owns(prog, robot, name)
            result = value(*args, **kwargs)
            run.after_command(prog)
            return result

        call.__name__ = name
        call.__doc__ = value.__doc__
        return call

    def __setattr__(self, name: str, value: Any) -> None:
        raise ProgramError(
            f"program '{self._program.name}': the simulator's {name!r} is read-only here"
        )

    def __dir__(self) -> list[str]:
        return [n for n in dir(self._run.sim) if not n.startswith("_")]

    def __repr__(self) -> str:
        return f"ProgramSim(program '{self._program.name}' of {self._run.sim!r})"
