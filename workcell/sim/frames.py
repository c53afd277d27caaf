"""Frames of the simulator: applying them, collision events, undo, replay (a mixin of
:class:`~workcell.sim.simulator.Simulator`).

Every command ends in :meth:`FrameRunner._emit`: in path and joint-by-joint mode each
frame is shown (``mj_kinematics``) as it is computed, in playback mode frames are only
stored (:meth:`FrameRunner.play` replays them); carried parts are posed at gripper pose x
relative pose in every frame, and both clocks advance.

Collisions (``check_collisions``, default on): after each frame's ``mj_kinematics``,
``mj_collision`` runs and every pair of things overlapping by more than
``contact_tolerance`` (m) that was not overlapping in the previous frame becomes a
``collision`` event (time, pair, depth); a held part against its own gripper is skipped.
``stop_on_collision`` raises :class:`CollisionError` at the first one (the command is
undone). :meth:`Simulator.clearance <workcell.sim.simulator.Simulator.clearance>` gives
the minimum distance between two named things.

Undo (:meth:`FrameRunner._transaction`): an exception while frames are applied restores
joints, parts, grasps, clocks, speeds, timeline and the devices' state
(:meth:`~workcell.sim.devices.CellLogic.rebuild`) as they were before the command; inside
``run_programs``, a command during which other programs ran (:mod:`workcell.logic`) is not
undone: what the others did stays, and so does what it did before it failed.

Devices (:mod:`workcell.sim.devices`): in a cell with belts, sensors, sources or sinks,
every frame is computed (playback mode too) and the devices are evaluated on it.

Listeners (``Simulator.frame_listeners``): callables ``f(frame, t)`` called each time
``sim.data`` shows a frame: after each applied frame (its kinematics, carried parts and
contacts done; ``frame`` is the timeline index it has or is about to get, ``t`` its
simulated time (s)), for each replayed frame, and after an undo or a replay put the last
frame back. In playback mode without carried parts or collision checks only a
command's last frame is applied, so only it is announced. Listeners observe (the live
view, :mod:`workcell.view`); they must not raise or change the simulator, and cost
nothing when the list is empty. Events have their own listeners
(``Simulator.event_listeners``, :class:`~workcell.sim.timeline.Timeline`).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.errors import CollisionError, ProgramError
from workcell.sim.contacts import Penetration
from workcell.sim.gripping import Carried

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["FrameRunner"]

Array = NDArray[np.float64]


class FrameRunner:
    """Applying, checking, undoing and replaying frames (module doc)."""

    def play(self: Simulator, realtime: bool | None = None, start: int = 0) -> int:
        """Replay the stored frames from ``start`` on (any mode; meant for playback).

        Each frame is shown (``mj_kinematics``); with ``realtime`` (default: the
        simulator's) frame i is shown when the wall clock has run ``t_i - t_start`` since
        the replay began (the thesis's wait of dT per frame). The frames' wall times are
        overwritten with their display times. Returns the number of frames shown.
        """
        rt = self.realtime if realtime is None else bool(realtime)
        n = len(self.timeline)
        if not 0 <= start < n:
            raise ProgramError(f"play: start must be a frame in 0..{n - 1}, got {start!r}")
        m, d = self.model, self.data
        qpos, kin, clock, sleep = d.qpos, mujoco.mj_kinematics, time.perf_counter, time.sleep
        final = d.qpos.copy()
        w0 = self._wall
        t_first = self.timeline.frame(start)[0]
        c0 = clock()
        try:
            for i, rows in self.timeline.iter_blocks(start):
                walls = np.empty(len(rows))
                for k, row in enumerate(rows):
                    if rt:
                        lag = c0 + (row[0] - t_first) - clock()
                        if lag > 0:
                            sleep(lag)
                    qpos[:] = row[2:]
                    kin(m, d)
                    for listener in self.frame_listeners:
                        listener(i + k, float(row[0]))
                    walls[k] = clock()
                self.timeline.set_wall_times(i, w0 + (walls - c0))
        finally:
            qpos[:] = final
            kin(m, d)
            self._wall = w0 + (clock() - c0)
            self._shown()
        return n - start

    # ------------------------------------------------------------------ internals
    def _emit(
        self: Simulator,
        times: Array,
        Q: Array,
        carried: list[Carried],
        mover: str | None = None,
    ) -> int:
        """Apply (path, joint-by-joint) or store (playback) frames; advance both clocks.

        Carried parts are posed at gripper x relative pose in every frame (their columns
        of Q are overwritten); with collision checks every frame is computed and checked
        (a collision involving ``mover``, the robot that moves, is charged to it). With
        devices (:mod:`workcell.sim.devices`) each frame is computed and the devices
        evaluated on it; the frames may stop early when a watched signal takes its value.
        Returns the number of frames made (``len(times)`` unless stopped early).
        """
        k = len(times)
        if k == 0:
            return 0
        m, d = self.model, self.data
        clock = time.perf_counter
        w0 = self._wall
        c0 = clock()
        check = self.check_collisions
        first = len(self.timeline)  # frame j of this batch becomes timeline frame first + j
        logic = self._logic  # the cell's devices (None: none that act on frames)
        if logic is not None and not (logic.movers or logic.sensors):
            logic = None  # signals only: nothing to evaluate on a frame
        if self.mode == "playback" and not carried and not check and logic is None:
            walls = np.full(k, clock())
            d.qpos[:] = Q[-1]
            mujoco.mj_kinematics(m, d)
            for listener in self.frame_listeners:
                listener(first + k - 1, float(times[-1]))
        else:
            walls = np.empty(k)
            qpos, kin, collide, mul = (
                d.qpos,
                mujoco.mj_kinematics,
                mujoco.mj_collision,
                mujoco.mju_mulPose,
            )
            xpos, xquat = d.xpos, d.xquat
            p, q = np.empty(3), np.empty(4)
            movers = logic is not None and logic.movers
            if logic is not None:
                logic.stop = False
            listeners = self.frame_listeners
            for j in range(k):
                if movers:  # parts keep the poses the devices gave them
                    logic.carry_over(qpos, Q[j])
                else:
                    qpos[:] = Q[j]
                kin(m, d)
                if carried:
                    for g, adr, rp, rq in carried:
                        mul(p, q, xpos[g], xquat[g], rp, rq)
                        qpos[adr : adr + 3] = p
                        qpos[adr + 3 : adr + 7] = q
                        Q[j, adr : adr + 7] = qpos[adr : adr + 7]
                    kin(m, d)
                if logic is not None:
                    logic.frame(float(times[j]), first + j)
                    Q[j] = qpos
                if check:
                    collide(m, d)
                    if d.ncon or self._touching:
                        pens = self.contacts.penetrations(d)
                        self._contact_events(float(times[j]), pens, mover=mover, frame=first + j)
                for listener in listeners:
                    listener(first + j, float(times[j]))
                walls[j] = clock()
                if logic is not None and logic.stop:  # a watched signal took its value
                    k = j + 1
                    break
        self.timeline.extend(times[:k], w0 + (walls[:k] - c0), Q[:k])
        self.sim_time = float(times[k - 1])
        self._wall = w0 + (clock() - c0)
        return k

    def _contact_events(
        self: Simulator,
        t: float,
        pens: list[Penetration],
        *,
        stop: bool = True,
        mover: str | None = None,
        frame: int = 0,
    ) -> None:
        """Log the pairs that start overlapping at ``t`` in timeline ``frame`` (the colliding
        frame, which the event carries); raise if stopping on collisions."""
        if not pens and not self._touching:
            return
        now = {(a, b) for a, b, _ in pens}
        onset = [p for p in pens if (p[0], p[1]) not in self._touching]
        self._touching = now
        for a, b, depth in onset:
            holder = {h.part: r for r, h in self._holds.items()}
            involved = [self.contacts.robot_of(x) or holder.get(x) for x in (a, b)]
            robot = mover if mover in involved else (involved[0] or involved[1])
            detail = f"{a} with {b}: depth {depth * 1e3:.3g} mm"
            self.timeline.add_event(t, robot, "collision", detail, frame=frame)
            if stop and self.stop_on_collision:
                raise CollisionError(f"collision at t = {t:.6g} s: {detail}")

    @contextmanager
    def _transaction(self: Simulator) -> Iterator[None]:
        """Undo everything (joints, parts, grasps, clocks, speeds, timeline) if the body raises."""
        qpos = self.data.qpos.copy()
        saved = (
            self.sim_time,
            self._wall,
            dict(self._speed),
            self.timeline.mark(),
            len(self.grasps),
            dict(self._holds),
            {p: list(r) for p, r in self._holders.items()},
            set(self._touching),
            set(self.contacts.excluded),
            self.data.eq_active.copy(),
            self.model.eq_data.copy(),
        )
        hold = getattr(self._block, "releases", None)  # programs run together
        try:
            yield
        except BaseException:
            if hold is not None and getattr(self._block, "releases", None) != hold:
                raise  # other programs ran meanwhile: what happened stays (logic/scheduler)
            (
                self.sim_time,
                self._wall,
                self._speed,
                mark,
                n_grasps,
                self._holds,
                self._holders,
                self._touching,
                self.contacts.excluded,
                self.data.eq_active[:],
                self.model.eq_data[:],
            ) = saved
            self.timeline.truncate(mark)
            del self.grasps[n_grasps:]
            self.data.qpos[:] = qpos
            mujoco.mj_kinematics(self.model, self.data)
            if self._logic is not None:
                self._logic.rebuild()
            self._shown()
            raise

    def _shown(self: Simulator) -> None:
        """Tell the frame listeners that ``data`` shows the timeline's last frame again
        (after an undo or a replay)."""
        for listener in self.frame_listeners:
            listener(len(self.timeline) - 1, self.sim_time)
