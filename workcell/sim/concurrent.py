"""Robots moving at the same time (beyond the thesis, whose commands run one by one).

Inside ``with sim.concurrently():`` the motion commands (``move_joints_*``,
``move_end_effector``, ``move_straight_line``) are planned but not run: each robot's
commands start when the block starts and follow one another on that robot's own clock.
When the block ends, the robots' plans are merged on the union of their sample times
(each robot's joints interpolated linearly between its own samples, held before its first
and after its last), and the merged frames are run like any others: carried parts follow
their grippers, collisions between the moving robots are checked at every frame, and
each command's ``move`` event lands at its own end time. The simulated clock advances by
the longest robot's time, not the sum.

Grippers, ``wait`` and ``set_mode`` are refused inside a block (end it first), blocks do
not nest, and joint-by-joint mode has no concurrent form (its joints move one at a time).
An error inside the block or while its frames run undoes the whole block.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.errors import ProgramError

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["ConcurrentCommands", "PlannedMove"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class PlannedMove:
    """One command planned inside a block: ``robot``'s ``times`` (k,) (s, simulated) and
    joint ``rows`` (k, dof), with the text of its ``move`` event and its cycle-time
    ``record``."""

    robot: str
    times: Array
    rows: Array
    command: str
    detail: str
    record: dict[str, Any] | None = None


@dataclass
class _Block:
    """Motions planned but not run yet: a ``concurrently()`` block (``run_programs`` keeps
    one too, :mod:`workcell.logic.block`, whose ``refuse``, ``clock`` and ``add`` go their
    own way)."""

    start: float
    base: Array  # qpos when the block started
    clocks: dict[str, float] = field(default_factory=dict)
    moves: list[PlannedMove] = field(default_factory=list)

    def refuse(self, sim: Simulator, command: str) -> None:
        """A command other than a motion was given inside the block."""
        raise ProgramError(
            f"{command} cannot run inside concurrently(): only motion commands can; "
            "end the block first"
        )

    def clock(self, sim: Simulator, robot: str) -> float:
        """When the robot's next command starts (s)."""
        return self.clocks.get(robot, self.start)

    def add(self, sim: Simulator, move: PlannedMove) -> None:
        """Keep a planned move."""
        self.moves.append(move)


class ConcurrentCommands:
    """``concurrently()`` (a mixin of Simulator; see the module doc)."""

    _block: _Block | None = None

    @contextmanager
    def concurrently(self: Simulator) -> Iterator[None]:
        """Run the motion commands issued inside the block at the same time (module doc)."""
        if self._block is not None:
            raise ProgramError("concurrently(): blocks do not nest")
        if self.mode == "joint-by-joint":
            raise ProgramError(
                "concurrently(): joint-by-joint mode moves one joint at a time; use path or "
                "playback mode"
            )
        self._block = _Block(self.sim_time, self.data.qpos.copy())
        self._pending.clear()  # a block starts from rest (zones do not reach into it)
        try:
            with self._transaction():
                yield
                block, self._block = self._block, None
                self._merge(block)
        finally:
            self._block = None
            self._pending.clear()  # nor out of it

    # ------------------------------------------------------------------ internals
    def _not_in_block(self: Simulator, command: str) -> None:
        if self._block is not None:
            self._block.refuse(self, command)

    def _start_time(self: Simulator, robot: str) -> float:
        """When the robot's next command starts (s): its block clock, or the sim clock."""
        if self._block is None:
            return self.sim_time
        return self._block.clock(self, robot)

    def _defer(
        self: Simulator,
        robot: str,
        times: Array,
        rows: Array | Callable[[int, int], Array],
        command: str,
        detail: str,
        record: dict[str, Any] | None = None,
    ) -> None:
        """Keep a planned move for the block's end; the robot is left at its target."""
        if len(times) == 0:
            return
        self._carried(robot)  # refuse now if the robot may not move
        Q = rows(0, len(times)) if callable(rows) else np.asarray(rows)
        self._block.add(self, PlannedMove(robot, times, Q, command, detail, record))
        self._block.clocks[robot] = float(times[-1])
        self.data.qpos[self._qadr[robot]] = Q[-1]
        mujoco.mj_kinematics(self.model, self.data)

    def _merge(self: Simulator, block: _Block) -> None:
        """Run the block's moves together (module doc)."""
        self.data.qpos[:] = block.base
        mujoco.mj_kinematics(self.model, self.data)
        if not block.moves:
            return
        t_all = np.unique(np.concatenate([mv.times for mv in block.moves]))
        Q = np.repeat(block.base[None, :], len(t_all), axis=0)
        robots = list(dict.fromkeys(mv.robot for mv in block.moves))
        carried = []
        for robot in robots:
            adr = self._qadr[robot]
            own = [mv for mv in block.moves if mv.robot == robot]
            T = np.concatenate([[block.start], *(mv.times for mv in own)])
            V = np.concatenate([block.base[adr][None, :], *(mv.rows for mv in own)])
            for c, a in enumerate(adr):
                Q[:, a] = np.interp(t_all, T, V[:, c])
            carried += self._carried(robot)
        lo = 0
        for mv in sorted(block.moves, key=lambda m: float(m.times[-1])):
            hi = int(np.searchsorted(t_all, mv.times[-1], side="right"))
            for a in range(lo, hi, 16384):
                b = min(hi, a + 16384)
                self._emit(t_all[a:b], Q[a:b], carried, None)
            lo = hi
            self.timeline.add_event(
                float(mv.times[-1]),
                mv.robot,
                "move",
                f"{mv.command} {mv.detail}: {len(mv.times)} frames, "
                f"{mv.times[-1] - self._block_start(mv, block):.6g} s (concurrent)",
                data=mv.record,
            )

    def _block_start(self: Simulator, mv: PlannedMove, block: _Block) -> float:
        """Start time (s) of a planned move: the end of the robot's previous one, or the
        block's start."""
        before = [
            m.times[-1] for m in block.moves if m.robot == mv.robot and m.times[-1] < mv.times[0]
        ]
        return float(max(before, default=block.start))
