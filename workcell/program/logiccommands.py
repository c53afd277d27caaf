"""The command vocabulary, cell logic: devices, signals, programs that run together, results.

- cell edits (refused while the cell is simulated, like every cell edit): ``add_signal``,
  ``add_sensor``, ``add_conveyor``, ``add_source``, ``add_sink``
  (:mod:`workcell.cell.devices`);
- signals of the running simulation: ``set_signal``, ``wait_signal``, ``signal`` (one
  value), ``signals`` (all), ``distance`` (a proximity sensor's);
- programs that run together (:mod:`workcell.logic`): ``program`` names a ``.wcl`` file
  as a robot's program (a name that is a robot's) or a controller's (any other name),
  ``programs`` lists them, ``run_programs`` runs them (or the ``programs`` mapping it is
  given: name -> ``.wcl`` file) until they end or ``until`` s of simulated time;
- results: ``throughput`` (the cell's, :mod:`workcell.sim.throughput`), ``gantt`` (the Gantt
  chart as a PNG, :mod:`workcell.record.gantt`).

SI arguments (m, m/s, s). File names are the session's (inside a server's root folder).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from workcell.checks import is_finite_number, shown
from workcell.errors import ProgramError
from workcell.program import args as a
from workcell.program.args import arg
from workcell.program.base import Command
from workcell.program.cellcommands import _editable
from workcell.program.runcommands import call_sim

if TYPE_CHECKING:
    from workcell.program.session import Session

__all__ = [
    "AddConveyor",
    "AddSensor",
    "AddSignal",
    "AddSink",
    "AddSource",
    "Distance",
    "Gantt",
    "Program",
    "Programs",
    "RunPrograms",
    "SetSignal",
    "Signal",
    "Signals",
    "Throughput",
    "WaitSignal",
    "format_logic",
    "signal_value",
]

_opt_vec3 = a.optional(a.sized(3))
_opt_number = a.optional(a.number)
_opt_name = a.optional(a.name)


def signal_value(v: object, what: str) -> bool | int | float:
    """A signal value: true or false, a whole number or a finite number."""
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if is_finite_number(v):
        return float(v)  # type: ignore[arg-type]
    raise ProgramError(f"{what} must be true, false or a number, got {shown(v)}")


signal_value.label = "bool | int | number"  # type: ignore[attr-defined]


def _pose_or_point(v: object, what: str) -> tuple[Any, ...]:
    """A 4x4 pose (4 rows of 4) or a point (3 numbers)."""
    if isinstance(v, (list, tuple, np.ndarray)) and len(v) == 3:
        return a.sized(3)(v, what)
    return a.matrix(v, what)


_pose_or_point.label = "number[4][4] | number[3]"  # type: ignore[attr-defined]


def _programs(v: object, what: str) -> tuple[tuple[str, str], ...]:
    """A mapping of program names to ``.wcl`` file names."""
    if not isinstance(v, dict) or not v:
        raise ProgramError(
            f"{what} must be an object of program names to .wcl files, got {shown(v)}"
        )
    return tuple((a.name(k, f"{what} name"), a.file_name(f, f"{what} '{k}'")) for k, f in v.items())


_programs.label = "{name: file}"  # type: ignore[attr-defined]


def _bool_if_bool(session: Session, name: str, value: Any) -> Any:
    """1 and 0 as true and false for a bool signal (people type them)."""
    sim = session.sim
    signals = sim.signals() if sim is not None else {}
    if isinstance(signals.get(name), bool) and type(value) is int and value in (0, 1):
        return bool(value)
    return value


# ---------------------------------------------------------------- cell edits
@dataclass(frozen=True)
class AddSignal(Command, wire="add_signal"):
    """Declare a signal with its initial value (true/false, a whole number or a number: its kind)."""

    name: str = arg(a.name)
    initial: bool | int | float = arg(signal_value)

    def execute(self, session: Session) -> str:
        return _editable(session).add_signal(self.name, self.initial).name


@dataclass(frozen=True)
class AddSensor(Command, wire="add_sensor"):
    """Add a sensor driving the bool signal ``name``: ``kind`` beam (``start``, ``end``),
    presence (``center``, ``size``: full edges) or proximity (``origin``, ``direction``,
    ``range``, ``threshold``); m, world; ``robots``: robot links count too."""

    name: str = arg(a.name)
    kind: str = arg(a.choice("beam", "presence", "proximity"))
    start: tuple[float, ...] | None = arg(_opt_vec3, None, "m")
    end: tuple[float, ...] | None = arg(_opt_vec3, None, "m")
    center: tuple[float, ...] | None = arg(_opt_vec3, None, "m")
    size: tuple[float, ...] | None = arg(_opt_vec3, None, "m")
    origin: tuple[float, ...] | None = arg(_opt_vec3, None, "m")
    direction: tuple[float, ...] | None = arg(_opt_vec3, None)
    range: float | None = arg(_opt_number, None, "m")
    threshold: float | None = arg(_opt_number, None, "m")
    robots: bool = arg(a.boolean, False)

    def execute(self, session: Session) -> str:
        names = ("start", "end", "center", "size", "origin", "direction", "range", "threshold")
        params = {k: getattr(self, k) for k in names if getattr(self, k) is not None}
        cell = _editable(session)
        return cell.add_sensor(self.name, self.kind, robots=self.robots, **params).name


@dataclass(frozen=True)
class AddConveyor(Command, wire="add_conveyor"):
    """Add a belt: top surface centre line ``start`` -> ``end`` (m), ``width`` (m),
    ``speed`` (m/s), running while the bool signal ``run_signal`` is true (null: always)."""

    name: str = arg(a.name)
    start: tuple[float, ...] = arg(a.sized(3), doc="m")
    end: tuple[float, ...] = arg(a.sized(3), doc="m")
    width: float = arg(a.number, doc="m")
    speed: float = arg(a.number, doc="m/s")
    run_signal: str | None = arg(_opt_name, None)

    def execute(self, session: Session) -> str:
        cell = _editable(session)
        belt = cell.add_conveyor(
            self.name, start=self.start, end=self.end, width=self.width, speed=self.speed,
            run_signal=self.run_signal,
        )  # fmt: skip
        return belt.name


@dataclass(frozen=True)
class AddSource(Command, wire="add_source"):
    """Add a source of copies (``<part>_1``, ...) of movable ``part`` at ``at`` (the part
    frame's 4x4 world pose, or its position), every ``every`` s or on each rising edge of
    ``on_signal``, at most ``count`` copies."""

    name: str = arg(a.name)
    part: str = arg(a.name)
    at: tuple[Any, ...] = arg(_pose_or_point)
    every: float | None = arg(_opt_number, None, "s")
    count: int | None = arg(a.optional(a.count), None)
    on_signal: str | None = arg(_opt_name, None)

    def execute(self, session: Session) -> str:
        cell = _editable(session)
        src = cell.add_source(
            self.name, self.part, at=np.array(self.at), every=self.every, count=self.count,
            on_signal=self.on_signal,
        )  # fmt: skip
        return src.name


@dataclass(frozen=True)
class AddSink(Command, wire="add_sink"):
    """Add a sink: a box (``center``, full edge ``size``, m) removing and counting parts."""

    name: str = arg(a.name)
    center: tuple[float, ...] = arg(a.sized(3), doc="m")
    size: tuple[float, ...] = arg(a.sized(3), doc="m")

    def execute(self, session: Session) -> str:
        return _editable(session).add_sink(self.name, center=self.center, size=self.size).name


# ---------------------------------------------------------------- signals
@dataclass(frozen=True)
class SetSignal(Command, wire="set_signal"):
    """Give a signal its value now."""

    name: str = arg(a.name)
    value: bool | int | float = arg(signal_value)

    def execute(self, session: Session) -> None:
        call_sim(session, "set_signal", self.name, _bool_if_bool(session, self.name, self.value))


@dataclass(frozen=True)
class WaitSignal(Command, wire="wait_signal"):
    """Let simulated time pass until the signal has ``value``; at most ``timeout`` s
    (SignalTimeout then, the time having passed)."""

    name: str = arg(a.name)
    value: bool | int | float = arg(signal_value, True)
    timeout: float | None = arg(_opt_number, None, "s")

    def execute(self, session: Session) -> None:
        value = _bool_if_bool(session, self.name, self.value)
        call_sim(session, "wait_signal", self.name, value, timeout=self.timeout)


@dataclass(frozen=True)
class Signal(Command, wire="signal"):
    """A signal's value now."""

    name: str = arg(a.name)

    def execute(self, session: Session) -> Any:
        return {self.name: call_sim(session, "signal", self.name)}


@dataclass(frozen=True)
class Signals(Command, wire="signals"):
    """Every signal's value now, by name."""

    def execute(self, session: Session) -> Any:
        return call_sim(session, "signals")


@dataclass(frozen=True)
class Distance(Command, wire="distance"):
    """A proximity sensor's distance (m) to the first surface on its ray (null: none)."""

    name: str = arg(a.name)

    def execute(self, session: Session) -> float:
        return call_sim(session, "distance", self.name)


# ---------------------------------------------------------------- programs
@dataclass(frozen=True)
class Program(Command, wire="program"):
    """Name the ``.wcl`` file ``path`` as program ``name``: a robot's name makes it that
    robot's program, any other a controller's (replaces a program of that name)."""

    name: str = arg(a.name)
    path: str = arg(a.file_name)

    def execute(self, session: Session) -> str:
        from workcell.files import read_text
        from workcell.program.interpreter import check_script

        path = session.path(self.path)  # inside a server's root, or refused
        if not self.path.endswith(".wcl"):
            raise ProgramError(f"program '{self.name}': {self.path!r} is no .wcl file")
        check_script(read_text(path, what="program", error=ProgramError), self.path)
        session.programs[self.name] = self.path
        return self.name


@dataclass(frozen=True)
class Programs(Command, wire="programs"):
    """The programs named so far (name -> file), in order."""

    def execute(self, session: Session) -> dict[str, str]:
        return dict(session.programs)


@dataclass(frozen=True)
class RunPrograms(Command, wire="run_programs"):
    """Run programs together (``programs``: name -> ``.wcl`` file; null: the ones named
    with ``program``) until they end or ``until`` s of simulated time; per program, how it
    ended and what it printed."""

    programs: tuple[tuple[str, str], ...] | None = arg(a.optional(_programs), None)
    until: float | None = arg(_opt_number, None, "s")

    def execute(self, session: Session) -> dict[str, Any]:
        from workcell.logic.scheduler import check_run, run_programs

        sim = session.require_sim()
        check_run(sim, self.until)
        given = dict(self.programs) if self.programs is not None else dict(session.programs)
        if not given:
            raise ProgramError(
                "run_programs: no programs: name them first ('program ROBOT FILE.wcl') or give them"
            )
        files = {
            k: (f if session.root is not None else str(session.path(f))) for k, f in given.items()
        }
        return run_programs(sim, files, until=self.until, root=session.root)


# ---------------------------------------------------------------- results
@dataclass(frozen=True)
class Throughput(Command, wire="throughput"):
    """The cell's results: parts per hour at each sink, bool signals' rises per hour,
    each robot's moving / waiting / idle fractions."""

    def execute(self, session: Session) -> dict[str, Any]:
        return call_sim(session, "throughput")


@dataclass(frozen=True)
class Gantt(Command, wire="gantt"):
    """Write the Gantt chart of the run (every robot and controller program over time) as
    a PNG; returns its path."""

    path: str = arg(a.file_name)

    def execute(self, session: Session) -> str:
        from workcell.errors import RenderError
        from workcell.files import check_writable
        from workcell.record.gantt import save_gantt

        p = session.path(self.path)  # inside a server's root, or refused
        sim = session.require_sim()
        check_writable(p, error=RenderError)
        return str(save_gantt(sim, p))


# ---------------------------------------------------------------- for people
def format_logic(command: Command, result: Any) -> str | None:
    """The text the shell prints for a command of this module (None: not one of them)."""
    from workcell.sim.devices import format_value

    if isinstance(command, (Signal, Signals)):
        return "\n".join(f"{k} = {format_value(v)}" for k, v in result.items()) or "no signals"
    if isinstance(command, Distance):
        return (
            "nothing within range"
            if result is None or result == float("inf")
            else f"{result:.6g} m"
        )
    if isinstance(command, Programs):
        return "\n".join(f"{k}: {f}" for k, f in result.items()) or "no programs named yet"
    if isinstance(command, RunPrograms):
        lines = []
        for name, r in result.items():
            t = "" if r["t_end"] is None else f" at t = {r['t_end']:.6g} s"
            lines.append(f"program {name}: {r['state']}{t}")
            lines += [f"  {line}" for line in r.get("output", [])]
        return "\n".join(lines)
    if isinstance(command, Throughput):
        from workcell.sim.throughput import format_throughput

        return format_throughput(result)
    return None
