"""``run_programs``: several programs on one simulated clock, each blocking only itself.

A discrete-event scheduler that drives the simulator it is handed (``Simulator.run_programs``
calls it; it works through that object and imports nothing of the simulator's package,
which sits above it in the import layers, as the planners of :mod:`workcell.plan` do). Each program (:mod:`workcell.logic.programs`)
runs in its own thread, but only one thread ever runs at a time: the scheduler hands
control to one program, which runs at the current simulated time until it *blocks* (a
motion, ``wait``, ``wait_signal``, or the end), and hands it back. Threads rather than
generators, because a program is ordinary code (``sim.move_linear(...)`` in a Python
function, a line of a ``.wcl`` file), and a command may block deep inside the simulator
(``pick`` moves, then grips: its robot must have stopped first), where only a thread can
stop and resume; handing control over one at a time keeps it deterministic: the same
programs give the same timeline, event for event, every run.

How it runs (the simulator's clock is the run's clock, ``now``):

1. every *ready* program runs, in the order given, at ``now``, until it blocks (again
   from the first one when one of them made another ready, e.g. by setting a signal);
   what a program does at ``now`` (grips, sets signals) happens at ``now``;
2. a motion command does not run at once: as in ``concurrently()``
   (:mod:`workcell.sim.concurrent`) the simulator plans it and keeps it in the run's
   block (:class:`ProgramBlock`) from its robot's clock on; the program then waits until
   its robot has stopped (a zone move lets it go on at once, so the next motion can blend
   out of it, :mod:`workcell.sim.blending`; any other command first waits for the stop);
3. when no program is ready, the next time something happens is the earliest of: a
   robot's move ending, a ``wait`` ending, a ``wait_signal`` timing out, ``until``; the
   scheduler makes the frames up to it (:meth:`Run.advance`): every robot along its own
   planned moves (joints linear between its own samples; frames at the union of their
   sample times, and every ``dt`` while the cell is alive), carried parts with their
   grippers, the devices on every frame (:mod:`workcell.sim.devices`), collisions; the
   frames stop early at the frame where a signal takes a value a program waits for;
4. the programs whose wait is over become ready, at the frame's time, and 1. again.

When no program is ready, nothing is timed and the cell cannot change anything by itself
(no belt moves a part, no source is due), every program still running waits for a signal
nothing can change: :class:`~workcell.errors.DeadlockError` names each one and what it
waits for. ``until`` (s, simulated time) stops everything there: robots stop where they
are, the moves they were making are recorded up to ``until`` (note "stopped at until"), a
``stop`` event lists what was still running. A program that raises stops the run: the
error is raised again with the program's name in front (a WorkcellError keeps its type;
other exceptions get a note); what happened up to it stays on the timeline (a command
during which other programs ran is not undone), with an ``error`` event.

Robot programs attribute their time: motion records (``summary()["commands"]``), waits and
``wait_signal`` records carry the robot and ``program_name``; :mod:`workcell.sim.throughput`
turns them into moving / waiting / idle fractions and :mod:`workcell.record.gantt` into a
Gantt chart. Times in seconds.
"""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Mapping
from typing import Any

from workcell import limits
from workcell.cell.devices import TIME_EPS, format_value, same_value
from workcell.checks import is_finite_number, shown
from workcell.errors import DeadlockError, ProgramError, WorkcellError
from workcell.logic.block import ProgramBlock
from workcell.logic.clock import CHUNK, RunClock
from workcell.logic.programs import MAX_CALLS_AT_ONE_TIME, Program, ProgramSim, programs_of

Simulator = Any  # the simulator it is handed (workcell.sim sits above: it calls this module)

__all__ = ["ProgramBlock", "Run", "check_run", "run_programs"]

_SCHEDULER = "\0scheduler"
_MAX_TURNS_AT_ONE_TIME = 100_000  # program turns without simulated time passing


class _Stop(BaseException):
    """Unwinds a program's thread when the run ends."""


def run_programs(
    sim: Simulator,
    programs: Mapping[str, Any],
    *,
    until: float | None = None,
    root: str | os.PathLike | None = None,
) -> dict[str, dict[str, Any]]:
    """Run ``programs`` together on ``sim`` (module doc); ``root``: ``.wcl`` file names
    resolve inside it. Returns per program ``state`` ("done" or "stopped"), ``t_end``
    (s), ``robot`` and, for ``.wcl`` programs, ``output`` (the lines they printed)."""
    check_run(sim, until)
    progs = programs_of(sim, programs, root=root)
    return Run(sim, progs, None if until is None else float(until)).execute()


def check_run(sim: Simulator, until: float | None) -> None:
    """ProgramError when ``sim`` cannot run programs now or ``until`` is no time after now."""
    if sim._block is not None:
        raise ProgramError("run_programs cannot run inside concurrently() or another run")
    if sim.mode == "joint-by-joint":
        raise ProgramError(
            "run_programs: joint-by-joint mode moves one joint at a time; use path or playback mode"
        )
    if until is not None:
        if not (is_finite_number(until) and float(until) > sim.sim_time):
            raise ProgramError(
                f"run_programs: until must be a simulated time (s) after now ({sim.sim_time:.6g} s), "
                f"got {shown(until)}"
            )
        limits.check("max_sim_time", float(until), "run_programs: until")


class Run(RunClock):
    """One ``run_programs`` (module doc; its clock: :mod:`workcell.logic.clock`)."""

    def __init__(self, sim: Simulator, programs: list[Program], until: float | None) -> None:
        self.sim, self.programs, self.until = sim, programs, until
        self.cond = threading.Condition()
        self.turn = _SCHEDULER
        self.current: Program | None = None
        self.stopping = False
        self.flight: dict[str, list[int]] = {}  # robot -> its moves not yet made (block indices)
        self.block = ProgramBlock(self)
        self.turns, self.turns_at = 0, -1.0

    # ------------------------------------------------------------------ the loop
    def execute(self) -> dict[str, dict[str, Any]]:
        sim = self.sim
        sim._pending.clear()
        sim._block = self.block
        try:
            for p in self.programs:
                p.thread = threading.Thread(
                    target=self._main, args=(p,), name=f"workcell program {p.name}", daemon=True
                )
                p.thread.start()
            self._loop()
        except BaseException as exc:
            self._stop_all()
            self._finish()
            raise self._reported(exc) from None
        self._stop_all()
        self._finish()
        return {
            p.name: {
                "state": p.state,
                "t_end": p.t_end,
                "robot": p.robot,
                **({"output": list(p.output)} if p.file is not None else {}),
            }
            for p in self.programs
        }

    def _loop(self) -> None:
        sim = self.sim
        while True:
            self._run_ready()
            if all(p.state in ("done", "failed") for p in self.programs) and not self._flying():
                return
            t_next = self._next_time()
            logic = sim._logic
            if math.isinf(t_next):
                if logic is None or not logic.alive():
                    raise DeadlockError(self._deadlock())
                t_next = sim.sim_time + CHUNK * sim.dt
            if self.until is not None:
                t_next = min(t_next, self.until)
            if logic is not None:
                logic.watch = self._watched()
            try:
                self.advance(t_next)
            finally:
                if logic is not None:
                    logic.watch = {}
            if self.until is not None and sim.sim_time >= self.until - TIME_EPS:
                self._stop_at_until()
                return
            self._wake()

    def _run_ready(self) -> None:
        """Give control to the ready programs, in order, until none is ready."""
        while True:
            ready = next((p for p in self.programs if p.state == "ready"), None)
            if ready is None:
                return
            now = self.sim.sim_time
            if now != self.turns_at:
                self.turns, self.turns_at = 0, now
            self.turns += 1
            if self.turns > _MAX_TURNS_AT_ONE_TIME:
                raise ProgramError(
                    f"run_programs: the programs passed control {_MAX_TURNS_AT_ONE_TIME:,} "
                    f"times at t = {now:.6g} s without time passing (signals set back and forth?)"
                )
            self._give(ready)
            self._show_now()
            if ready.state == "failed":
                raise ready.error  # type: ignore[misc]

    def _main(self, p: Program) -> None:
        """A program's thread."""
        with self.cond:
            while self.turn != p.name:
                self.cond.wait()
        try:
            if self.stopping:
                raise _Stop
            p.state = "running"
            p.body(ProgramSim(self, p))
            if p.robot is not None and self.flight.get(p.robot):
                self.sync()  # its robot's last moves end the program
            p.state = "done"
        except _Stop:
            p.state = "stopped"
        except BaseException as exc:  # the scheduler raises it again
            p.state, p.error = "failed", exc
        finally:
            if p.t_end is None:
                p.t_end = self.sim.sim_time
            with self.cond:
                self.turn = _SCHEDULER
                self.cond.notify_all()

    def _give(self, p: Program) -> None:
        """Hand control to program ``p`` and wait until it blocks or ends (or, while the
        run stops, until its thread is gone)."""
        self.current = p
        if not self.stopping:
            p.state = "running"
        with self.cond:
            self.turn = p.name
            self.cond.notify_all()
            while self.turn != _SCHEDULER and (not self.stopping or p.thread.is_alive()):
                self.cond.wait(timeout=None if not self.stopping else 1.0)
        self.current = None

    def _block_current(self) -> None:
        """The current program waits (its state says for what) until the scheduler gives
        it control again."""
        p = self.current
        assert p is not None
        self.block.releases += 1
        with self.cond:
            self.turn = _SCHEDULER
            self.cond.notify_all()
            while self.turn != p.name:
                self.cond.wait()
        if self.stopping:
            raise _Stop

    # ------------------------------------------------------------------ blocking commands
    def sync(self) -> None:
        """The current program's robot finishes its moves (the program waits); a zone
        move it could have blended out of becomes a stop."""
        p = self.current
        if p is None or p.robot is None:
            return
        if self.flight.get(p.robot):
            p.state, p.since = "robot", self.sim.sim_time
            self._block_current()
        self.sim._pending.pop(p.robot, None)

    def after_command(self, p: Program) -> None:
        """After a command of ``p``: wait for its robot, unless it may blend (module doc)."""
        r = p.robot
        if r is None or not self.flight.get(r):
            return
        pend = self.sim._pending.get(r)
        if pend is not None and pend.block_move == self.flight[r][-1]:
            return
        self.sync()

    def wait(self, seconds: float) -> None:
        """``wait`` of ``seconds`` (s) in a program: time passes for it alone."""
        p, sim = self.current, self.sim
        assert p is not None
        t0 = sim.sim_time
        if seconds > 0:
            p.state, p.wake, p.since = "time", t0 + seconds, t0
            self._block_current()
        asked = {"kind": "wait", "seconds": sim.sim_time - t0}
        rec = self.sim._command_record(
            p.robot, "wait", t0, sim.sim_time - t0, "wait", program=asked
        )
        rec["program_name"] = p.name
        sim.timeline.add_event(sim.sim_time, p.robot, "wait", f"wait {seconds:.6g} s", data=rec)

    def wait_signal(self, name: str, value: Any, timeout: float | None) -> None:
        """``wait_signal`` in a program (module doc of :mod:`workcell.sim.signals`)."""
        p, sim = self.current, self.sim
        assert p is not None
        t0 = sim.sim_time
        matched = same_value(sim._logic.values[name], value)
        if not matched:
            p.state, p.waits_for, p.since, p.matched = "signal", (name, value), t0, False
            p.deadline = None if timeout is None else t0 + timeout
            self._block_current()
            matched, p.waits_for, p.deadline = p.matched, None, None
        sim._waited(name, value, t0, timeout, matched, p.robot, self.block.tag)

    def wake_signals(self) -> None:
        """Programs waiting for a signal that now has their value become ready (now)."""
        values = self.sim._logic.values
        for p in self.programs:
            if p.state == "signal" and same_value(values[p.waits_for[0]], p.waits_for[1]):
                p.state, p.matched = "ready", True

    # ------------------------------------------------------------------ checks
    def owns(self, p: Program, robot: object, command: str) -> None:
        """ProgramError unless ``p`` is ``robot``'s program (names not of a robot are left
        to the simulator's own check)."""
        if not isinstance(robot, str) or robot not in self.sim.robots or robot == p.robot:
            return
        if p.robot is None:
            raise ProgramError(
                f"program '{p.name}' is a controller program (no robot has this name): "
                f"{command} '{robot}' belongs in the program named '{robot}'"
            )
        raise ProgramError(
            f"program '{p.name}' moves robot '{p.robot}' only: {command} '{robot}' belongs in "
            f"the program named '{robot}'"
        )

    def count_call(self, p: Program) -> None:
        now = self.sim.sim_time
        if now != p.calls_at:
            p.calls, p.calls_at = 0, now
        p.calls += 1
        if p.calls > MAX_CALLS_AT_ONE_TIME:
            raise ProgramError(
                f"program '{p.name}' made {MAX_CALLS_AT_ONE_TIME:,} calls at t = {now:.6g} s "
                "without simulated time passing (a busy loop? wait with wait_signal or wait)"
            )

    # ------------------------------------------------------------------ the end
    def _deadlock(self) -> str:
        values = self.sim._logic.values if self.sim._logic is not None else {}
        waits = []
        for p in self.programs:
            if p.state == "signal":
                name, value = p.waits_for
                waits.append(
                    f"'{p.name}' waits for signal '{name}' = {format_value(value)} (it is "
                    f"{format_value(values[name])})"
                )
        return (
            f"run_programs: deadlock at t = {self.sim.sim_time:.6g} s: every program still "
            f"running waits for a signal that nothing can change any more (no robot moves, no "
            f"belt moves a part, no source is due): {'; '.join(waits)}"
        )

    def _stop_all(self) -> None:
        """Unwind every program thread still waiting for control."""
        self.stopping = True
        for p in self.programs:
            t = p.thread
            if t is None or not t.is_alive():
                continue
            if p.state not in ("done", "failed", "stopped"):
                self._give(p)  # it raises _Stop where it waits, and ends
            t.join(timeout=5.0)

    def _finish(self) -> None:
        sim = self.sim
        for robot in list(self.flight):
            self.flight[robot] = []
        sim._block = None
        sim._pending.clear()
        self._show_now()
        if sim._logic is not None:
            sim._logic.watch = {}

    def _reported(self, exc: BaseException) -> BaseException:
        """The error that ends the run, with the program's name, and its ``error`` event."""
        failed = next((p for p in self.programs if p.error is exc), None)
        where = f"program '{failed.name}': " if failed is not None else ""
        if isinstance(exc, WorkcellError):
            if where:
                exc.args = (f"{where}{exc}",)
        elif failed is not None:
            exc.add_note(
                f"in program '{failed.name}' of run_programs, t = {self.sim.sim_time:.6g} s"
            )
        if not isinstance(exc, KeyboardInterrupt):
            robot = failed.robot if failed is not None else None
            self.sim.timeline.add_event(
                self.sim.sim_time, robot, "error", f"{type(exc).__name__}: {exc}"
            )
        return exc
