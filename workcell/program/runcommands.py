"""The command vocabulary, simulation run control (thesis §4.5): ``simulate`` starts a
:class:`~workcell.sim.Simulator` on the session's cell, ``stop_simulation`` ends it;
``set_mode``, ``wait`` (simulated time, s), ``play`` (replay) and the
``concurrently_begin``/``concurrently_end`` block. :func:`call_sim` is how every
simulation command calls its Simulator method. All are re-exported by
:mod:`workcell.program.simcommands`.
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

__all__ = [
    "MODES",
    "ConcurrentlyBegin",
    "ConcurrentlyEnd",
    "Play",
    "SetMode",
    "Simulate",
    "StopSimulation",
    "Wait",
    "call_sim",
]

MODES = ("path", "joint-by-joint", "playback")


def call_sim(session: Session, method: str, *args: Any, **kw: Any) -> Any:
    """Call the session simulator's ``method``; ProgramError when it has none."""
    sim = session.require_sim()
    fn = getattr(sim, method, None)
    if fn is None:
        raise ProgramError(f"{method}: this simulator does not provide {method} yet")
    return fn(*args, **kw)


@dataclass(frozen=True)
class Simulate(Command, wire="simulate"):
    """Start simulating the cell in ``mode`` with sampling interval ``dt`` (s); replaces
    any running simulation (its clock and timeline start anew)."""

    mode: str = arg(a.choice(*MODES), "path")
    dt: float = arg(a.number, 0.01, "s")
    realtime: bool = arg(a.boolean, False)

    def execute(self, session: Session) -> str:
        from workcell.sim.simulator import Simulator

        cell = session.require_cell()
        session.sim = Simulator(cell, mode=self.mode, dt=self.dt, realtime=self.realtime)
        return f"simulating cell '{cell.name}': {self.mode} mode, dt {self.dt:g} s"


@dataclass(frozen=True)
class StopSimulation(Command, wire="stop_simulation"):
    """End the simulation (the cell stays and can be edited again)."""

    def execute(self, session: Session) -> None:
        session.require_sim()
        session.sim = None


@dataclass(frozen=True)
class SetMode(Command, wire="set_mode"):
    """Switch the simulation mode: path, joint-by-joint or playback."""

    mode: str = arg(a.choice(*MODES))

    def execute(self, session: Session) -> None:
        call_sim(session, "set_mode", self.mode)


@dataclass(frozen=True)
class Wait(Command, wire="wait"):
    """Let ``seconds`` of simulated time pass."""

    seconds: float = arg(a.number, doc="s")

    def execute(self, session: Session) -> None:
        call_sim(session, "wait", self.seconds)


@dataclass(frozen=True)
class Play(Command, wire="play"):
    """Replay the stored frames (playback mode); ``realtime`` null: the simulator's setting.
    Returns the number of frames shown."""

    realtime: bool | None = arg(a.optional(a.boolean), None)

    def execute(self, session: Session) -> int:
        return call_sim(session, "play", self.realtime)


@dataclass(frozen=True)
class ConcurrentlyBegin(Command, wire="concurrently_begin"):
    """Start a block of motion commands that run at the same time (the Simulator's
    ``concurrently()``), ended by ``concurrently_end``."""

    def execute(self, session: Session) -> None:
        sim = session.require_sim()
        if session.block is not None:
            raise ProgramError("concurrently_begin: a block is open already; blocks do not nest")
        block = sim.concurrently()
        block.__enter__()  # refuses (joint-by-joint mode) before anything changes
        session.block = (sim, block)


@dataclass(frozen=True)
class ConcurrentlyEnd(Command, wire="concurrently_end"):
    """End the block: with ``commit`` run its motions together, else drop them all."""

    commit: bool = arg(a.boolean, True)

    def execute(self, session: Session) -> None:
        if session.block is None:
            raise ProgramError("concurrently_end: no block is open (concurrently_begin starts one)")
        (_sim, block), session.block = session.block, None
        if self.commit:
            block.__exit__(None, None, None)  # an error undoes the whole block and is raised
            return
        stop = ProgramError("the block was abandoned")
        block.__exit__(ProgramError, stop, None)  # undoes the block
