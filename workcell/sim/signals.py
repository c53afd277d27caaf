"""Signals, waits with the cell alive, sensors' distances and programs run together (a
mixin of :class:`~workcell.sim.simulator.Simulator`).

- ``signal(name)``, ``signals()``: the value of a signal (a declared one or a sensor's),
  all values;
- ``set_signal(name, value)``: gives the signal its value now (a bool signal takes a
  bool, an int one an int, a float one a number); one frame at the same time shows what
  follows (a source waiting for the signal's rising edge makes its copy there); a
  ``signal`` event, whose data is the command's record plus ``signal`` and ``value``;
- ``wait_signal(name, value=True, *, timeout=None)``: simulated time passes, the cell
  alive (belts run, sources make copies, sensors update; in ``run_programs`` the other
  programs go on), until the signal has ``value``; the ``wait_signal`` event's record
  says how long it waited. After ``timeout`` s the wait ends exactly there and
  :class:`~workcell.errors.SignalTimeout` is raised (the time has passed: the clock
  stands at the timeout). Alone, a wait for a signal nothing in the cell can change any
  more (no belt moves a part, no source is due) raises
  :class:`~workcell.errors.DeadlockError` and is undone;
- ``wait(seconds)`` (:class:`~workcell.sim.simulator.Simulator`): lets time pass with the
  cell alive: a frame every ``dt`` while something can change (and at each timed source's
  time), else one frame at the end, as before;
- ``distance(name)``: a proximity sensor's distance (m) to the first surface on its ray
  (inf when none within its range), as of the last frame;
- ``run_programs(programs, *, until=None)``: :mod:`workcell.logic`.

Bad input (an unknown signal, a value of the wrong kind, a negative timeout) raises
ProgramError and changes nothing.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from workcell import limits
from workcell.checks import is_finite_number, shown
from workcell.errors import DeadlockError, ProgramError, SignalTimeout
from workcell.sim.cycle import command_record
from workcell.sim.devices import TIME_EPS, format_value, same_value

if TYPE_CHECKING:
    from workcell.cell.devices import SignalValue
    from workcell.sim.simulator import Simulator

__all__ = ["SignalCommands"]

_CHUNK = 16384  # frames made at once while time passes


class SignalCommands:
    """Signals and waits (a mixin of Simulator; module doc)."""

    _command_record = staticmethod(command_record)  # for the scheduler below (workcell.logic)

    # ------------------------------------------------------------------ read-back
    def signal(self: Simulator, name: str) -> SignalValue:
        """The value of signal ``name`` (a declared signal or a sensor's)."""
        return self._logic_of("signal").values[self._signal_name(name, "signal")]

    def signals(self: Simulator) -> dict[str, SignalValue]:
        """Every signal's value, by name (declared signals, then sensors')."""
        return {} if self._logic is None else dict(self._logic.values)

    def distance(self: Simulator, name: str) -> float:
        """Proximity sensor ``name``'s distance (m) to the first surface along its ray,
        inf when there is none within its range (as of the last frame)."""
        logic = self._logic_of("distance")
        if name not in logic.distances:
            known = ", ".join(logic.distances) or "none"
            raise ProgramError(
                f"distance: no proximity sensor {shown(name)}; proximity sensors: {known}"
            )
        return float(logic.distances[name])

    # ------------------------------------------------------------------ commands
    def set_signal(self: Simulator, name: str, value: SignalValue) -> None:
        """Give signal ``name`` its ``value`` now (module doc)."""
        name = self._signal_name(name, "set_signal")
        v = self._signal_value(name, value, "set_signal")
        self._not_in_block("set_signal")  # refused in concurrently(); a program's robot stops
        block = self._block
        robot = None if block is None else block.robot_of_program()
        asked = {"kind": "set_signal", "name": name, "value": v}
        rec = command_record(robot, "set_signal", self.sim_time, 0.0, program=asked)
        rec.update(signal=name, value=v)
        if block is not None:
            block.tag(rec)
        with self._transaction():
            self._logic.set(name, v, self.sim_time, len(self.timeline), rec, always=True)
            self._emit(np.array([self.sim_time]), self.data.qpos[None, :].copy(), [], robot)
        if block is not None:
            block.signal_set(self, name)

    def wait_signal(
        self: Simulator, name: str, value: SignalValue = True, *, timeout: float | None = None
    ) -> None:
        """Let time pass until signal ``name`` has ``value``, at most ``timeout`` s
        (module doc)."""
        name = self._signal_name(name, "wait_signal")
        v = self._signal_value(name, value, "wait_signal")
        if timeout is not None and not (is_finite_number(timeout) and float(timeout) >= 0):
            raise ProgramError(
                f"wait_signal '{name}': timeout must be None or a number of seconds >= 0, "
                f"got {shown(timeout)}"
            )
        t_out = None if timeout is None else float(timeout)
        if t_out is not None:
            limits.check("max_sim_time", self.sim_time + t_out, f"wait_signal '{name}': the clock")
        self._not_in_block("wait_signal")
        if self._block is not None:  # run_programs: the scheduler lets time pass
            self._block.wait_signal(self, name, v, t_out)
            return
        logic, t0 = self._logic, self.sim_time
        matched = same_value(logic.values[name], v)
        if not matched:
            with self._transaction():  # a deadlock or a limit undoes the wait
                matched = self._wait_for(name, v, t_out)
        self._waited(name, v, t0, t_out, matched, None)

    # ------------------------------------------------------------------ programs
    def run_programs(
        self: Simulator,
        programs: Mapping[str, Callable[[Any], object] | str],
        *,
        until: float | None = None,
    ) -> dict[str, dict[str, Any]]:
        """Run ``programs`` together on one simulated clock (:mod:`workcell.logic`): a
        mapping of names to callables ``f(sim)`` or ``.wcl`` files; a name that is a robot's
        is that robot's program (it alone moves the robot), others are controllers.
        ``until`` (s): stop everything at that simulated time. Returns, per program, how
        it ended (``state``: "done", "stopped" at ``until``; ``t_end``, s)."""
        from workcell.logic.scheduler import run_programs

        return run_programs(self, programs, until=until)

    # ------------------------------------------------------------------ internals
    def _logic_of(self: Simulator, command: str) -> Any:
        if self._logic is None:
            raise ProgramError(
                f"{command}: cell '{self.cell.name}' has no signals (add_signal, add_sensor "
                "declare them)"
            )
        return self._logic

    def _signal_name(self: Simulator, name: object, command: str) -> str:
        logic = self._logic_of(command)
        if not isinstance(name, str) or name not in logic.values:
            known = ", ".join(logic.values) or "none"
            raise ProgramError(f"{command}: no signal {shown(name)}; signals: {known}")
        return name

    def _signal_value(self: Simulator, name: str, value: object, command: str) -> SignalValue:
        kind = type(self._logic.initial[name])
        if kind is bool and isinstance(value, (bool, np.bool_)):
            return bool(value)
        if (
            kind is int
            and isinstance(value, (int, np.integer))
            and not isinstance(value, (bool, np.bool_))
        ):
            return int(value)
        if kind is float and is_finite_number(value):
            return float(value)  # type: ignore[arg-type]
        want = {bool: "true or false", int: "a whole number", float: "a finite number"}[kind]
        raise ProgramError(
            f"{command} '{name}': a {kind.__name__} signal takes {want}, got {shown(value)}"
        )

    def _wait_for(self: Simulator, name: str, value: SignalValue, timeout: float | None) -> bool:
        """Let time pass until the signal has ``value`` (True) or ``timeout`` s are over
        (False); DeadlockError when nothing can change it any more."""
        logic = self._logic
        end = None if timeout is None else self.sim_time + timeout
        logic.watch = {name: [value]}
        try:
            while True:
                if not logic.alive():
                    if end is None:
                        raise DeadlockError(
                            f"wait_signal '{name}' = {format_value(value)}: nothing can change "
                            f"it any more (no program runs, no belt moves a part, no source is "
                            f"due); it is {format_value(logic.values[name])}"
                        )
                    self._pass_time(end - self.sim_time, "wait_signal")
                    return same_value(logic.values[name], value)
                stop = self.sim_time + _CHUNK * self.dt if end is None else end
                if self._pass_time(stop - self.sim_time, "wait_signal", chunk=True):
                    return True
                if end is not None and self.sim_time >= end - TIME_EPS:
                    return same_value(logic.values[name], value)
        finally:
            logic.watch = {}

    def _pass_time(self: Simulator, seconds: float, command: str, *, chunk: bool = False) -> bool:
        """Let ``seconds`` of simulated time pass, nothing of the robots moving: a frame
        every dt (and at each timed source's time) while the cell is alive, else one at
        the end. True when a watched signal took its value (the frames stop there)."""
        t0 = self.sim_time
        end = t0 + seconds
        logic = self._logic
        alive = logic is not None and logic.alive()
        times = self._time_grid(t0, end) if alive else np.array([end])
        limits.check("max_frames_per_command", len(times), command)
        limits.check("max_sim_time", end, f"{command}: the clock")
        self.timeline.reserve(len(times), command)
        row = self.data.qpos[None, :]
        carried = [c for r in self._holds for c in self._carried_safe(r)]
        for lo in range(0, len(times), _CHUNK):
            part = times[lo : lo + _CHUNK]
            k = self._emit(part, np.repeat(row, len(part), axis=0), carried)
            if k < len(part):
                return True
        return bool(logic is not None and logic.stop)

    def _time_grid(self: Simulator, t0: float, end: float) -> np.ndarray:
        """Frame times in (t0, end]: every dt from t0, the timed sources' times, and end."""
        n = max(math.ceil((end - t0) / self.dt - 1e-9), 1)
        times = t0 + self.dt * np.arange(1, n + 1)
        times[-1] = end
        extra = [] if self._logic is None else self._logic.source_times(t0, end)
        if extra:
            times = np.unique(np.concatenate([times, extra]))
            times = times[np.concatenate([np.diff(times) > TIME_EPS, [True]])]
            times[-1] = end
        return times

    def _carried_safe(self: Simulator, robot: str) -> list:
        """What ``robot`` carries, none when a second gripper holds it too."""
        hold = self._holds[robot]
        if len(self._holders[hold.part]) > 1:
            return []
        return self._carried(robot)

    def _waited(
        self: Simulator,
        name: str,
        value: SignalValue,
        t0: float,
        timeout: float | None,
        matched: bool,
        robot: str | None,
        tag: Callable[[dict[str, Any]], None] | None = None,
    ) -> None:
        """The ``wait_signal`` event (its record); SignalTimeout when it timed out."""
        dur = self.sim_time - t0
        asked = {"kind": "wait_signal", "name": name, "value": value, "timeout": timeout}
        rec = command_record(robot, "wait_signal", t0, dur, "signal", program=asked)
        rec.update(signal=name, value=value, timeout=timeout)
        if not matched:
            rec["note"] = "timed out"
        if tag is not None:
            tag(rec)
        want = f"{name} = {format_value(value)}"
        how = f"waited {dur:.6g} s" if matched else f"timed out after {dur:.6g} s"
        self.timeline.add_event(self.sim_time, robot, "wait_signal", f"{want}: {how}", data=rec)
        if not matched:
            raise SignalTimeout(
                f"wait_signal: signal '{name}' did not become {format_value(value)} within "
                f"{timeout:.6g} s (from t = {t0:.6g} s); it is "
                f"{format_value(self._logic.values[name])}"
            )
