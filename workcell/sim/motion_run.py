"""The machinery behind the motion commands (a mixin of
:class:`~workcell.sim.simulator.Simulator`, see :mod:`workcell.sim.motion`): planning a
joint or Cartesian move, blending it out of the robot's pending zone move
(:mod:`workcell.sim.blending`), running its frames with its cycle-time record, and taking
a pending move's tail back (restored exactly if the new frames fail).
"""

from __future__ import annotations

import math
import sys
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from workcell import limits as work_limits
from workcell.checks import is_finite_number
from workcell.errors import JointLimitError, ProgramError, UnreachableError
from workcell.sim.blending import Blend, Pending, joint_blend, path_blend, tool_lengths
from workcell.sim.cartesian import path_joints
from workcell.sim.cycle import command_record
from workcell.sim.jerk import Limits, joint_limits, require_finite
from workcell.sim.pathlaw import PathMotion
from workcell.sim.paths import CartesianPath
from workcell.sim.planning import Motion, Rows, law_rows, plan_move
from workcell.sim.timeline import TimelineMark
from workcell.sim.timing import sample_params, timed_frames
from workcell.spatial import invert

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["DEFAULT_TOOL_ACCELERATION", "MotionRunner"]

Array = NDArray[np.float64]
DEFAULT_TOOL_ACCELERATION = 1.2  # m/s^2, UR's default tool acceleration
_STEP = 0.005  # m between the IK samples of a Cartesian path
_MAX_JUMP = math.radians(10)
_EMIT_CHUNK = 16384


class MotionRunner:
    """Planning, blending and running motions (module doc)."""

    def _limits(self: Simulator, name: str) -> Limits:
        return joint_limits(self.cell.robots[name].robot, self._override[name])

    def _tool_args(
        self: Simulator, command: str, name: str, speed: object, acceleration: object, zone: object
    ) -> tuple[float, float, float]:
        acc = DEFAULT_TOOL_ACCELERATION if acceleration is None else acceleration
        for what, value, unit in (("speed", speed, "m/s"), ("acceleration", acc, "m/s^2")):
            if not (is_finite_number(value) and float(value) > 0):  # type: ignore[arg-type]
                raise ProgramError(
                    f"{command} '{name}': {what} must be a number of {unit} > 0, got {value!r}"
                )
        return float(speed), float(acc), self._zone(command, name, zone)  # type: ignore[arg-type]

    def _zone(self: Simulator, command: str, name: str, zone: object) -> float:
        if not (is_finite_number(zone) and float(zone) >= 0):  # type: ignore[arg-type]
            raise ProgramError(f"{command} '{name}': zone must be a number of m >= 0, got {zone!r}")
        return float(zone)  # type: ignore[arg-type]

    def _plan(
        self: Simulator,
        name: str,
        q0: Array,
        target: Array,
        command: str,
        *,
        together: bool = False,
    ) -> Motion:
        """One joint move of robot ``name`` (see :mod:`workcell.sim.planning`), in local
        time; ``together``: all joints at once whatever the mode (a planned path's
        segments)."""
        f = self._override[name]
        limits = None
        if self.profile == "jerk":
            limits = self._limits(name)
            require_finite(limits, name, command)
        return plan_move(
            q0,
            target,
            speed=self._speed[name] * f,
            dt=self.dt,
            joint_by_joint=self.mode == "joint-by-joint" and not together,
            clock=self.joint_by_joint_clock,
            profile=self.profile,
            acceleration=self.acceleration * f * f,
            limits=limits,
            what=f"{command} '{name}'",
        )

    def _check_target(self: Simulator, name: str, target: Array, command: str) -> None:
        """JointLimitError when ``target`` (rad/m) is outside the robot's joint limits."""
        try:
            self.cell.robots[name].robot.check_limits(target)
        except JointLimitError as exc:
            raise JointLimitError(f"{command} '{name}': target refused: {exc}") from exc

    def _move(
        self: Simulator,
        name: str,
        target: Array,
        command: str,
        zone: float = 0.0,
        note: str = "",
        program: dict[str, Any] | None = None,
    ) -> None:
        """A joint move to ``target`` (rad/m), blending out of the robot's pending move;
        ``note`` is added to its event (why this target); ``program``: what the command was
        asked (its record's, :mod:`workcell.sim.cycle`)."""
        placement = self.cell.robots[name]
        self._check_target(name, target, command)
        z = self._zone(command, name, zone)
        q0 = self.joints(name)
        motion = self._plan(name, q0, target, command)
        deg = ", ".join(f"{v:.6g}" for v in np.degrees(target))
        pend, blend, length = self._blendable(name), None, 0.0
        if motion.law is not None and (z > 0 or pend is not None) and len(motion.t):
            length = float(tool_lengths(placement, motion.rows_of(), q0)[-1])
        if pend is not None and motion.law is not None:
            blend = joint_blend(pend, motion, length, placement, self._limits(name), self.dt)
        detail = f"to ({deg}) deg" + (f", {note}" if note else "")
        program = {"kind": "joint", **(program or {}), "q": target.tolist(), "zone": z}
        self._commit(name, command, detail, motion, z, blend, pend, length, program=program)

    def _path_move(
        self: Simulator,
        name: str,
        command: str,
        detail: str,
        path: CartesianPath,
        speed: float | None,
        acceleration: float | None,
        zone: float,
        *,
        step: float = _STEP,
        max_jump: float = _MAX_JUMP,
        program: dict[str, Any] | None = None,
    ) -> None:
        """A Cartesian move along ``path`` (tool limits before the override); ``program``:
        what the command was asked (its record's, :mod:`workcell.sim.cycle`)."""
        f = self._override[name]
        v = None if speed is None else speed * f
        a = None if acceleration is None else acceleration * f * f
        placement, limits = self.cell.robots[name], self._limits(name)
        pend = self._blendable(name)
        try:
            if pend is not None and isinstance(pend.law, PathMotion):
                blend = path_blend(
                    pend, path, v, a, placement, limits, self.dt,
                    step=step, max_jump=max_jump, command=command,
                )  # fmt: skip
                if blend is not None:
                    self._commit(
                        name, command, detail, None, zone, blend, pend, path.length, v, a,
                        program=program,
                    )  # fmt: skip
                    return
            q0 = self.joints(name)
            s = sample_params(path, step)
            Q = path_joints(
                placement, q0, path.poses(s[1:]), s[1:] / path.span, max_jump=max_jump, what=command
            )
            Q = np.vstack([q0, Q])
            ends = np.array([0.0, path.span])
            timed = timed_frames(
                placement.robot, invert(placement.base), path, Q, s, self.dt,
                f"{command} '{name}'", limits=limits,
                speed=None if v is None else (ends, np.array([v, v])),
                acceleration=None if a is None else (ends, np.array([a, a])), q_before=q0,
            )  # fmt: skip
            if timed is None:  # from rest to rest a time law always exists
                raise UnreachableError("no time law along the path")
            law, t, rows = timed
            motion = Motion(
                t, law_rows(law, t, Q[-1]) if rows is None else rows, law.activity(), law
            )
            blend = None
            if pend is not None and not isinstance(pend.law, PathMotion):  # a joint move
                blend = joint_blend(pend, motion, path.length, placement, limits, self.dt)
        except UnreachableError as exc:
            raise UnreachableError(f"{command} '{name}': {exc}") from exc
        self._commit(
            name, command, detail, motion, zone, blend, pend, path.length, v, a, program=program
        )

    def _blendable(self: Simulator, name: str) -> Pending | None:
        """The robot's pending zone move, if the next move may still blend out of it."""
        p = self._pending.get(name)
        if p is None:
            return None
        block = self._block
        if block is None:
            ok = p.block_move is None and self.timeline.mark() == p.end
        else:
            own = [i for i, mv in enumerate(block.moves) if mv.robot == name]
            ok = p.block_move is not None and bool(own) and own[-1] == p.block_move
        return p if ok else None

    def _commit(
        self: Simulator,
        name: str,
        command: str,
        detail: str,
        motion: Motion | None,
        zone: float,
        blend: Blend | None,
        pend: Pending | None,
        length: float,
        speed: float | None = None,
        acceleration: float | None = None,
        *,
        program: dict[str, Any] | None = None,
    ) -> None:
        """Run a planned move (or a corner and the move), then note it as pending;
        ``program`` goes on its record with the motion settings and the joints it ends at."""
        if program is not None:
            program = self._program_settings(name, program)
            if "q" not in program:
                law = motion.law if blend is None else blend.next_law  # type: ignore[union-attr]
                end = law.q_end if isinstance(law, PathMotion) else motion.rows_of()[-1]  # type: ignore[union-attr]
                program["q"] = np.asarray(end, dtype=np.float64).tolist()
        if blend is None:
            assert motion is not None
            start = self._start_time(name)
            note = ""
            if zone > 0 and motion.law is None:
                note = (
                    f"zone not used: profile '{self.profile}' joint moves stop (zones need 'jerk')"
                )
            rec = command_record(
                name, command, start, motion.duration, motion.activity, note=note, program=program
            )
            first = self._next_index(name)
            self._run(name, start + motion.t, motion.rows, command, detail, rec)
            law, t0, times, head, rested = motion.law, start, start + motion.t, {}, True
            activity, t_start = motion.activity, start
        else:
            assert pend is not None
            first, t_start = self._run_blend(name, pend, blend, command, detail, program)
            law, t0, rested = blend.next_law, blend.next_t0, False
            times = blend.b_times[blend.next_first :]
            first += blend.next_first
            activity, head = blend.b_activity, blend.extra.get("head", {})
        self._pending.pop(name, None)
        if zone > 0 and law is not None and len(times):
            self._pending[name] = Pending(
                name, command, detail, zone, law, t0, times, first, rested, t_start,
                activity, head, length, self.timeline.mark(), speed, acceleration,
                None if self._block is None else len(self._block.moves) - 1, program,
            )  # fmt: skip

    def _program_settings(self: Simulator, name: str, program: dict[str, Any]) -> dict[str, Any]:
        """``program`` with the motion settings in effect (:mod:`workcell.sim.cycle`)."""
        return {
            **program,
            "profile": self.profile,
            "robot_speed": self._speed[name],
            "profile_acceleration": self.acceleration,
            "override": self._override[name],
        }

    def _next_index(self: Simulator, name: str) -> int:
        """Where the next frame of ``name`` goes: a timeline frame index (0 in a block)."""
        return 0 if self._block is not None else len(self.timeline)

    def _run(
        self: Simulator,
        name: str,
        times: Array,
        Qr: Rows,
        command: str,
        detail: str,
        record: dict[str, Any] | None = None,
    ) -> None:
        """Emit a robot's planned frames (carrying what it holds) and log the move event
        with its ``record``. Frames are built and emitted ``_EMIT_CHUNK`` at a time."""
        if self._block is not None:  # inside concurrently(): run when the block ends
            self._defer(name, times, Qr, command, detail, record)
            return
        k = len(times)
        if k:  # before any work: the command's frames and its clock
            self._budget(name, command, k, float(times[-1]))
        carried = self._carried(name) if k else []
        rows = Qr if callable(Qr) else (lambda lo, hi: Qr[lo:hi])
        t_before = self.sim_time
        with self._transaction():
            self._emit_rows(name, times, rows, carried, command)
            self.timeline.add_event(
                self.sim_time,
                name,
                "move",
                f"{command} {detail}: {k} frames, {self.sim_time - t_before:.6g} s",
                data=record,
            )

    def _budget(self: Simulator, name: str, command: str, frames: int, end: float) -> None:
        """LimitError when a command's frames, the simulation's or its end time (s) are
        over the work budget (before any work)."""
        work_limits.check("max_frames_per_command", frames, f"{command} '{name}'")
        work_limits.check("max_sim_time", end, f"{command} '{name}': the clock")
        self.timeline.reserve(frames, f"{command} '{name}'")

    def _emit_rows(
        self: Simulator, name: str, times: Array, rows: Any, carried: list, command: str
    ) -> None:
        """Emit frames ``rows(lo, hi)`` of robot ``name`` at ``times`` in chunks (a progress
        bar for more than 100,000 frames)."""
        k = len(times)
        base, adr = self.data.qpos.copy(), self._qadr[name]
        show = k > 100_000 and (sys.stderr.isatty() if self.progress is None else self.progress)
        with tqdm(total=k, unit="frame", desc=command, leave=False, disable=not show) as bar:
            for lo in range(0, k, _EMIT_CHUNK):
                hi = min(k, lo + _EMIT_CHUNK)
                Q = np.repeat(base[None, :], hi - lo, axis=0)
                Q[:, adr] = rows(lo, hi)
                self._emit(times[lo:hi], Q, carried, name)
                bar.update(hi - lo)

    def _run_blend(
        self: Simulator,
        name: str,
        p: Pending,
        b: Blend,
        command: str,
        detail: str,
        program: dict[str, Any] | None = None,
    ) -> tuple[int, float]:
        """Take back the pending move's tail and run the corner and the new move (module
        doc of :mod:`workcell.sim.blending`). Returns the index of the new move's first
        frame (timeline, or row of its block move) and the new move's start time."""
        a_rec = command_record(
            name, p.command, p.t_start, b.a_end - p.t_start, b.a_activity, zone=b.zone,
            note=b.note, program=p.program,
        )  # fmt: skip
        b_dur = float(b.b_times[-1]) - b.a_end if len(b.b_times) else 0.0
        b_rec = command_record(name, command, b.a_end, b_dur, b.b_activity, program=program)
        a_detail = f"{p.command} {p.detail}, blended into {command} (zone {b.zone * 1e3:.4g} mm)"
        b_detail = f"{command} {detail}, out of a {b.zone * 1e3:.4g} mm zone"
        if len(b.b_times):
            self._budget(name, command, len(b.a_times) + len(b.b_times), float(b.b_times[-1]))
        if self._block is not None:
            return self._blend_in_block(name, p, b, command, detail, a_rec, b_rec)
        cut = p.first + b.keep  # frames [0, cut) stay
        tl = self.timeline
        events = tl.events
        e_cut = next((i for i, e in enumerate(events) if e.frame >= cut), len(events))
        saved = (tl.sim_times(cut), tl.wall_times(cut), tl.qpos(cut), events[e_cut:])
        end_q, end_t = self.data.qpos.copy(), self.sim_time
        with self._transaction():
            tl.truncate(TimelineMark(cut, e_cut))
            try:
                t_cut, _, q_cut = tl.frame(cut - 1)
                self.sim_time = t_cut
                self.data.qpos[:] = q_cut
                mujoco.mj_kinematics(self.model, self.data)
                self._touching = set()
                if self.check_collisions:
                    mujoco.mj_collision(self.model, self.data)
                    self._touching = {(x, y) for x, y, _ in self.contacts.penetrations(self.data)}
                carried = self._carried(name)
                if len(b.a_times):
                    self._emit_rows(
                        name, b.a_times, lambda lo, hi: b.a_rows[lo:hi], carried, p.command
                    )
                tl.add_event(
                    b.a_end, name, "move", f"{a_detail}: {b.a_end - p.t_start:.6g} s", data=a_rec
                )
                first = len(tl)
                self._emit_rows(name, b.b_times, lambda lo, hi: b.b_rows[lo:hi], carried, command)
                tl.add_event(
                    self.sim_time,
                    name,
                    "move",
                    f"{b_detail}: {len(b.b_times)} frames, {b_dur:.6g} s",
                    data=b_rec,
                )
            except BaseException:
                tl.truncate(TimelineMark(cut, e_cut))
                _restore(tl, cut, saved)
                self.data.qpos[:] = end_q
                self.sim_time = end_t
                raise
        return first, b.a_end

    def _blend_in_block(
        self: Simulator,
        name: str,
        p: Pending,
        b: Blend,
        command: str,
        detail: str,
        a_rec: dict[str, Any],
        b_rec: dict[str, Any],
    ) -> tuple[int, float]:
        from workcell.sim.concurrent import PlannedMove

        block = self._block
        old = block.moves[p.block_move]
        keep = p.first + b.keep
        times = np.concatenate([old.times[:keep], b.a_times])
        rows = np.vstack([old.rows[:keep], b.a_rows])
        a_detail = f"{p.detail}, blended into {command} (zone {b.zone * 1e3:.4g} mm)"
        block.moves[p.block_move] = PlannedMove(name, times, rows, p.command, a_detail, a_rec)
        block.clocks[name] = b.a_end
        self.data.qpos[self._qadr[name]] = rows[-1]
        self._defer(name, b.b_times, b.b_rows, command, f"{detail}, out of a zone", b_rec)
        return 0, b.a_end


def _restore(tl: Any, cut: int, saved: tuple[Array, Array, Array, tuple]) -> None:
    """Put back frames from ``cut`` on and their events (a blend that failed)."""
    times, walls, Q, events = saved
    at = cut
    for e in events:
        upto = e.frame + 1
        if upto > at:
            tl.extend(
                times[at - cut : upto - cut], walls[at - cut : upto - cut], Q[at - cut : upto - cut]
            )
            at = upto
        tl.add_event(e.t, e.robot, e.kind, e.detail, frame=e.frame, data=e.data)
    if at - cut < len(times):
        tl.extend(times[at - cut :], walls[at - cut :], Q[at - cut :])
