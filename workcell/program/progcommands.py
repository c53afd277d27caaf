"""The command vocabulary, robot-program part: a robot's program out to a vendor language
and a vendor program in (:mod:`workcell.robotprog`, docs/robot-programs.md).

File names resolve as every command's do (a server keeps them inside its root folder).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from workcell.errors import ProgramError
from workcell.program import args as a
from workcell.program.args import arg
from workcell.program.base import Command

if TYPE_CHECKING:
    from workcell.program.session import Session

__all__ = ["ExportProgram", "RunRobotProgram"]

LANGUAGES = ("urscript", "krl", "rapid", "fanuc_ls")


def _signals(v: object, what: str) -> tuple[tuple[str, int], ...]:
    """Signal names to I/O numbers: an object {name: number >= 0} (or [name, number] pairs)."""
    if isinstance(v, (list, tuple)) and all(
        isinstance(x, (list, tuple)) and len(x) == 2 for x in v
    ):
        v = dict(v)
    if not isinstance(v, dict):
        raise ProgramError(f"{what} must be an object of signal names and I/O numbers, got {v!r}")
    out = []
    for k, n in v.items():
        if (
            not isinstance(k, str)
            or not k
            or isinstance(n, bool)
            or not isinstance(n, int)
            or n < 0
        ):
            raise ProgramError(f"{what}: {k!r}: {n!r} must be a signal name and a number >= 0")
        out.append((k, n))
    return tuple(out)


_signals.label = "object"  # type: ignore[attr-defined]


@dataclass(frozen=True)
class ExportProgram(Command, wire="export_program"):
    """Write the program `robot` ran in this simulation to `path` in `language` ("urscript", "krl", "rapid", "fanuc_ls"; null: from the suffix .script, .src, .mod, .ls), `signals` naming I/O numbers; returns the files written (KRL: .src and .dat)."""

    robot: str = arg(a.name)
    path: str = arg(a.file_name)
    language: str | None = arg(a.optional(a.choice(*LANGUAGES)), None)
    signals: tuple[tuple[str, int], ...] = arg(_signals, ())

    def execute(self, session: Session) -> list[str]:
        from pathlib import Path

        from workcell.robotprog import export, language_of

        target = session.path(self.path)
        if language_of(target, self.language) == "krl":  # the .dat beside it: inside too
            session.path(str(Path(self.path).with_suffix(".dat")))
        sim = session.require_sim()
        return export(sim, self.robot, target, language=self.language, signals=dict(self.signals))


@dataclass(frozen=True)
class RunRobotProgram(Command, wire="run_robot_program"):
    """Run the robot program in file `path` (URScript, KRL with its .dat, RAPID, FANUC LS; `language` null: from the suffix) on `robot`; returns the simulated clock (s) and the outputs it set."""

    robot: str = arg(a.name)
    path: str = arg(a.file_name)
    language: str | None = arg(a.optional(a.choice(*LANGUAGES)), None)

    def execute(self, session: Session) -> dict[str, Any]:
        from pathlib import Path

        from workcell.robotprog import language_of, load

        path = session.path(self.path)
        if language_of(path, self.language) == "krl":  # the .dat it reads: inside too
            for p in path.parent.glob("*"):
                if p.stem.lower() == path.stem.lower() and p.suffix.lower() == ".dat":
                    session.path(str(Path(self.path).parent / p.name))
        sim = session.require_sim()
        program = load(path, language=self.language)
        vm = program.run(sim, self.robot)
        return {
            "sim_time_s": sim.sim_time,
            "outputs": {str(k): v for k, v in vm.motion.outputs.items()},
        }
