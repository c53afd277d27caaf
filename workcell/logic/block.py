"""The run's block (:class:`ProgramBlock`): how the simulator's commands reach the run
of :mod:`workcell.logic.scheduler` while programs run together (``Simulator._block``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from workcell.logic.scheduler import Run

Simulator = Any  # the simulator it is handed (workcell.sim sits above: it calls this module)

__all__ = ["ProgramBlock"]


class ProgramBlock:
    """The run's block (module doc): like a ``concurrently()`` block
    (:mod:`workcell.sim.concurrent`: ``start``, ``base``, ``clocks``, ``moves``), moves
    kept per robot, but commands other than motions wait for the program's robot to stop
    instead of being refused."""

    def __init__(self, run: Run) -> None:
        self.start = run.sim.sim_time
        self.base = run.sim.data.qpos.copy()
        self.clocks: dict[str, float] = {}
        self.moves: list[Any] = []  # the simulator's PlannedMove records
        self.run = run
        self.releases = 0  # times control went back to the scheduler (frames.py reads it)

    def refuse(self, sim: Simulator, command: str) -> None:
        self.run.sync()

    def clock(self, sim: Simulator, robot: str) -> float:
        """The simulated time (s) at which ``robot``'s next move starts: after its moves
        already planned, never before now."""
        return max(self.clocks.get(robot, sim.sim_time), sim.sim_time)

    def add(self, sim: Simulator, move: Any) -> None:
        run = self.run
        if run.current is not None:
            run.owns(run.current, move.robot, move.command)
            if move.record is not None:
                move.record["program_name"] = run.current.name
        self.moves.append(move)
        run.flight.setdefault(move.robot, []).append(len(self.moves) - 1)

    def robot_of_program(self) -> str | None:
        cur = self.run.current
        return None if cur is None else cur.robot

    def tag(self, record: dict[str, Any]) -> None:
        if self.run.current is not None:
            record["program_name"] = self.run.current.name

    def wait(self, sim: Simulator, seconds: float) -> None:
        self.run.wait(seconds)

    def wait_signal(self, sim: Simulator, name: str, value: Any, timeout: float | None) -> None:
        self.run.wait_signal(name, value, timeout)

    def signal_set(self, sim: Simulator, name: str) -> None:
        self.run.wake_signals()
