"""The run's clock (a mixin of :class:`~workcell.logic.scheduler.Run`): when the next
thing happens, which programs wake then, the frames up to it (the scheduler's module doc,
3.) and the moves recorded as they end, or cut at ``until``. Times in seconds.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell import limits
from workcell.cell.devices import TIME_EPS, same_value
from workcell.logic.programs import Program

if TYPE_CHECKING:
    from workcell.logic.block import ProgramBlock

__all__ = ["CHUNK", "RunClock"]

Array = NDArray[np.float64]
CHUNK = 16384  # frames made at once


class RunClock:
    """The time of a run: :meth:`advance` makes the frames, :meth:`_next_time` says up to
    when, :meth:`_wake` who is ready then (a mixin; the run supplies ``sim``,
    ``programs``, ``flight`` and ``block``)."""

    sim: Any
    programs: list[Program]
    flight: dict[str, list[int]]
    block: ProgramBlock

    def _flying(self) -> bool:
        return any(self.flight.values())

    def _move_end(self, i: int) -> float:
        """The simulated time (s) at which move ``i`` of the block ends."""
        return float(self.block.moves[i].times[-1])

    def _next_time(self) -> float:
        """The earliest timed thing after now (inf when nothing is timed)."""
        best = math.inf
        for p in self.programs:
            if p.state == "time":
                best = min(best, p.wake)
            elif p.state == "signal" and p.deadline is not None:
                best = min(best, p.deadline)
        for moves in self.flight.values():
            if moves:
                best = min(best, self._move_end(moves[-1]))
        return best

    def _watched(self) -> dict[str, list[Any]]:
        out: dict[str, list[Any]] = {}
        for p in self.programs:
            if p.state == "signal":
                out.setdefault(p.waits_for[0], []).append(p.waits_for[1])
        return out

    def _wake(self) -> None:
        now = self.sim.sim_time
        values = None if self.sim._logic is None else self.sim._logic.values
        for p in self.programs:
            timed = p.state == "time" and p.wake <= now + TIME_EPS
            if timed or (p.state == "robot" and not self.flight.get(p.robot)):
                p.state = "ready"
            elif p.state == "signal":
                if same_value(values[p.waits_for[0]], p.waits_for[1]):
                    p.state, p.matched = "ready", True
                elif p.deadline is not None and p.deadline <= now + TIME_EPS:
                    p.state, p.matched = "ready", False

    def _show_now(self) -> None:
        """The simulator's data shows the last frame (a planned move left its robot at
        its target)."""
        sim = self.sim
        sim.data.qpos[:] = sim.timeline.frame(-1)[2]
        mujoco.mj_kinematics(sim.model, sim.data)

    def advance(self, t_stop: float) -> None:
        """Make the frames from now to ``t_stop`` (module doc, 3.)."""
        sim = self.sim
        self._show_now()
        while sim.sim_time < t_stop - TIME_EPS:
            now = sim.sim_time
            ends = [self._move_end(i) for ms in self.flight.values() for i in ms]
            t_win = min([t_stop, *(e for e in ends if e > now + TIME_EPS)])
            times = self._frame_times(now, t_win)
            limits.check("max_frames_per_command", len(times), "run_programs: frames at once")
            sim.timeline.reserve(len(times), "run_programs")
            Q = self._rows(now, times)
            carried = [c for r in sim._holds for c in sim._carried_safe(r)]
            stopped = False
            for lo in range(0, len(times), CHUNK):
                part = times[lo : lo + CHUNK]
                k = sim._emit(part, Q[lo : lo + len(part)], carried)
                if k < len(part):
                    stopped = True
                    break
            self._finish_moves(sim.sim_time)
            if stopped:
                return

    def _frame_times(self, now: float, t_win: float) -> Array:
        """The frames in (now, t_win]: the moving robots' own sample times and t_win;
        while the cell is alive, gaps longer than dt between them are filled every dt (and
        at the timed sources' times, :meth:`Simulator._time_grid`)."""
        sim = self.sim
        parts = [np.array([t_win])]
        for ms in self.flight.values():
            for i in ms:
                t = self.block.moves[i].times
                parts.append(t[(t > now + TIME_EPS) & (t <= t_win + TIME_EPS)])
        times = _merged(parts, now, t_win)
        logic = sim._logic
        if logic is not None and logic.alive():
            edges = np.concatenate([[now], times])
            gaps = np.flatnonzero(np.diff(edges) > sim.dt + TIME_EPS)
            if len(gaps):
                fill = [sim._time_grid(edges[g], edges[g + 1]) for g in gaps]
                times = _merged([times, *fill], now, t_win)
        return times

    def _rows(self, now: float, times: Array) -> Array:
        """Full qpos rows at ``times``: the robots along their moves, the rest as now."""
        sim = self.sim
        base = sim.data.qpos
        Q = np.repeat(base[None, :], len(times), axis=0)
        for robot, ms in self.flight.items():
            if not ms:
                continue
            adr = sim._qadr[robot]
            T = [np.array([now])]
            V = [base[adr][None, :]]
            for i in ms:
                mv = self.block.moves[i]
                sel = mv.times > now + TIME_EPS
                T.append(mv.times[sel])
                V.append(mv.rows[sel])
            T_all, V_all = np.concatenate(T), np.vstack(V)
            for c, a in enumerate(adr):
                Q[:, a] = np.interp(times, T_all, V_all[:, c])
        return Q

    def _finish_moves(self, now: float, *, cut: bool = False) -> None:
        """Record the moves that have ended by ``now`` (``cut``: all, stopped at now)."""
        sim = self.sim
        done = []
        for ms in self.flight.values():
            while ms and (cut or self._move_end(ms[0]) <= now + TIME_EPS):
                done.append(ms.pop(0))
        for i in sorted(done, key=lambda i: (min(self._move_end(i), now), i)):
            mv = self.block.moves[i]
            end = self._move_end(i)
            rec = None if mv.record is None else dict(mv.record)
            start = rec["t_start"] if rec is not None else float(mv.times[0])
            detail = f"{mv.command} {mv.detail}: {len(mv.times)} frames, {end - start:.6g} s"
            t_ev = end
            if cut and end > now + TIME_EPS:
                t_ev = now
                detail += f"; stopped at until ({now:.6g} s)"
                if rec is not None:
                    rec["duration_s"] = max(now - rec["t_start"], 0.0)
                    rec["note"] = "stopped at until"
            sim.timeline.add_event(t_ev, mv.robot, "move", detail, data=rec)
            pend = sim._pending.get(mv.robot)
            if pend is not None and pend.block_move == i:
                sim._pending.pop(mv.robot)
            self.block.moves[i] = dataclasses.replace(mv, times=mv.times[-1:], rows=mv.rows[-1:])

    def _stop_at_until(self) -> None:
        sim, now = self.sim, self.sim.sim_time
        running = []
        for p in self.programs:
            if p.state in ("done", "failed"):
                continue
            what = {"time": "waiting", "signal": "waiting for a signal", "robot": "moving"}
            running.append(f"'{p.name}' ({what.get(p.state, p.state)})")
            if p.state in ("time", "signal"):
                command = "wait" if p.state == "time" else "wait_signal"
                rec = sim._command_record(p.robot, command, p.since, now - p.since, "wait")
                rec.update(program_name=p.name, note="stopped at until")
                if p.waits_for is not None:
                    rec.update(signal=p.waits_for[0], value=p.waits_for[1])
                sim.timeline.add_event(
                    now, p.robot, command, f"{command}: stopped at until", data=rec
                )
            p.t_end = now
        self._finish_moves(now, cut=True)
        sim.timeline.add_event(
            now, None, "stop",
            f"run_programs: until {now:.6g} s reached; still running: {', '.join(running) or 'none'}",
        )  # fmt: skip


def _merged(parts: list[Array], now: float, end: float) -> Array:
    """The sorted times of ``parts`` in (now, end], those closer than TIME_EPS as one,
    the last exactly ``end``."""
    times = np.unique(np.concatenate(parts))
    times = times[times > now + TIME_EPS]
    times = times[np.concatenate([np.diff(times) > TIME_EPS, [True]])]
    times[-1] = end
    return times
