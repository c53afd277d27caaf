"""The workcell simulator, kinematic mode: joint-space commands in the thesis's three modes.

A :class:`Simulator` compiles a :class:`~workcell.Workcell` with
:func:`~workcell.cell.compile_cell` and moves its robots by writing MuJoCo's ``qpos`` and
calling ``mj_kinematics`` (no dynamics). Commands run one after another, one robot at a
time; each appends frames and an event to the :class:`~workcell.sim.timeline.Timeline`
(frame 0 is the initial state at t = 0).

Modes (thesis §4.4; every command runs in any of them):

- ``"path"`` (§4.4.1.2): all joints move together, linearly in joint space. With the
  robot's speed theta_dot (the speed of the joint that moves most) and the sampling
  interval dT = ``dt``, eq. 4.27 gives the motion's duration
  ``T = max_i |Delta theta_i| / theta_dot``; each joint steps by
  ``delta theta_i = Delta theta_i / T * dT`` (eq. 4.28). With ``T = m dT + Delta T`` the
  motion is m full steps plus one remainder step: m + 1 frames (m when the remainder is
  zero to 1e-9 dT). Every frame is shown (``mj_kinematics``) as it is computed.
- ``"joint-by-joint"`` (§4.4.1.1): the joints move one after another (joint 1 first),
  each linearly in steps of ``delta theta = theta_dot * dT``; joint i takes
  ``m_i + 1`` frames with ``m_i = floor(|Delta theta_i| / delta theta)`` (eq. 4.26), the
  last one the remainder. Joints that do not move give no frames.
- ``"playback"`` (§4.4.2): the frames are computed exactly as in path mode and stored
  (not shown); :meth:`Simulator.play` then replays them, in real time (a wait of dT per
  frame, scheduled on the wall clock) or as fast as possible.

Clocks (§4.4.3): the *simulated clock* shows "the time that the action would have taken
if the execution was on a real robot"; in path mode, "the time needed for each display
update or step motion is known from equation 4.27. Thus the time display [...] is just
incremented by dT for each step motion"; in joint-by-joint mode "the time is incremented
during the motion of one joint which we chose to be the joint that has to move the
fastest for the whole motion" (so a command takes the same simulated time,
``max_i |Delta theta_i| / theta_dot``, in every mode); in play-back "the time is updated
in the same manner as in the path simulation approach, but is stored in the frames".
``joint_by_joint_clock="sequential"`` instead charges each joint its own
``|Delta theta_i| / theta_dot`` (their sum: what a robot moving one joint at a time would
take). The *wall clock* is a stopwatch that runs while the simulator works (computing,
showing or replaying frames); both clocks are kept on every frame of the timeline.

Errors: every command validates first (unknown robot: ProgramError listing the robots;
target outside the limits: JointLimitError naming the joint and its range; bad speed or
vector: ProgramError) and changes nothing when it fails; an exception while frames are
applied restores joints, clocks, speeds and timeline as they were before the command.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.cell.compile import CompiledCell, compile_cell
from workcell.cell.workcell import Workcell
from workcell.errors import JointLimitError, ProgramError
from workcell.sim.timeline import DEFAULT_MEMORY_LIMIT, Event, Timeline

__all__ = ["JOINT_BY_JOINT_CLOCKS", "MODES", "Simulator", "step_times"]

MODES = ("path", "joint-by-joint", "playback")
JOINT_BY_JOINT_CLOCKS = ("thesis", "sequential")
_REMAINDER_TOL = 1e-9  # a remainder below this fraction of dT is no step

Array = NDArray[np.float64]


def step_times(T: float, dt: float) -> Array:
    """Sample times in (0, T] of a motion of duration T sampled every dt (thesis eq. 4.27).

    ``T = m dt + Delta T``: the m full steps ``dt, 2 dt, ..., m dt`` then the remainder
    step ending at T exactly; when ``Delta T`` is zero (below 1e-9 dt) the last full step
    is the end and its time is set to T exactly. T = 0 gives no samples.
    """
    if not T > 0:
        return np.empty(0)
    m = math.floor(T / dt)
    rem = T - m * dt
    t = dt * np.arange(1, m + 1, dtype=np.float64)
    if rem > _REMAINDER_TOL * dt:
        return np.append(t, T)
    if len(t) == 0:  # T is below the tolerance itself: one step
        return np.array([T])
    t[-1] = T
    return t


def _finite_number(x: object) -> bool:
    return (
        isinstance(x, (int, float, np.integer, np.floating))
        and not isinstance(x, bool)
        and math.isfinite(float(x))
    )


class Simulator:
    """Kinematic simulator of a workcell (see the module doc).

    ``mode``: "path", "joint-by-joint" or "playback"; ``dt`` the sampling interval dT
    (s); ``realtime``: playback waits dT per frame (default: as fast as possible);
    ``joint_by_joint_clock``: "thesis" or "sequential"; ``compiled``: an already compiled
    cell (default: compile ``cell``); ``memory_limit`` (bytes, None: none) and
    ``spill_dir``: frames beyond the limit spill to a temporary file (see
    :class:`~workcell.sim.timeline.Timeline`).
    """

    def __init__(
        self,
        cell: Workcell,
        mode: str = "path",
        dt: float = 0.01,
        *,
        realtime: bool = False,
        joint_by_joint_clock: str = "thesis",
        compiled: CompiledCell | None = None,
        memory_limit: int | None = DEFAULT_MEMORY_LIMIT,
        spill_dir: str | None = None,
    ) -> None:
        if mode not in MODES:
            raise ProgramError(f"unknown simulation mode {mode!r}; valid: {', '.join(MODES)}")
        if not (_finite_number(dt) and dt > 0):
            raise ProgramError(f"dt must be a finite number of seconds > 0, got {dt!r}")
        if joint_by_joint_clock not in JOINT_BY_JOINT_CLOCKS:
            raise ProgramError(
                f"unknown joint_by_joint_clock {joint_by_joint_clock!r}; "
                f"valid: {', '.join(JOINT_BY_JOINT_CLOCKS)}"
            )
        self.cell = cell
        self.mode = mode
        self.dt = float(dt)
        self.realtime = bool(realtime)
        self.joint_by_joint_clock = joint_by_joint_clock
        self.compiled = compile_cell(cell) if compiled is None else compiled
        self.model: mujoco.MjModel = self.compiled.model
        self.data = mujoco.MjData(self.model)
        mujoco.mj_kinematics(self.model, self.data)
        self._qadr: dict[str, NDArray[np.intp]] = {}
        self._site: dict[str, int] = {}
        self._speed: dict[str, float] = {}
        for name, placement in cell.robots.items():
            joints = self.compiled.joint_names[name]
            self._qadr[name] = np.array(
                [self.model.jnt_qposadr[self.model.joint(j).id] for j in joints], dtype=np.intp
            )
            self._site[name] = self.model.site(self.compiled.tool_sites[name]).id
            self._speed[name] = float(placement.robot.nominal_speed)
        self._part_body = {p: self.model.body(b).id for p, b in self.compiled.part_bodies.items()}
        self.sim_time = 0.0
        self._wall = 0.0
        self.timeline = Timeline(self.model.nq, memory_limit=memory_limit, spill_dir=spill_dir)
        self.timeline.append(0.0, 0.0, self.data.qpos)

    # ------------------------------------------------------------------ read-back
    @property
    def robots(self) -> tuple[str, ...]:
        """The cell's robot names."""
        return tuple(self._qadr)

    @property
    def wall_time(self) -> float:
        """The wall clock (s): time the simulator has spent on commands and replays."""
        return self._wall

    @property
    def frames(self) -> int:
        """Number of frames on the timeline (frame 0 is the initial state)."""
        return len(self.timeline)

    @property
    def events(self) -> tuple[Event, ...]:
        """The timeline's events."""
        return self.timeline.events

    def joints(self, robot: str) -> Array:
        """The robot's current joint values (rad/m), a copy."""
        return self.data.qpos[self._qadr[self._robot(robot)]].copy()

    def tool_pose(self, robot: str) -> Array:
        """The robot's current tool pose in the world (4x4), from MuJoCo's tool site."""
        i = self._site[self._robot(robot)]
        T = np.eye(4)
        T[:3, :3] = self.data.site_xmat[i].reshape(3, 3)
        T[:3, 3] = self.data.site_xpos[i]
        return T

    def speed(self, robot: str) -> float:
        """The robot's speed (rad/s): the speed of the joint that moves most."""
        return self._speed[self._robot(robot)]

    def trajectory(self, robot: str) -> tuple[Array, Array]:
        """(simulated times (N,), joint values (N, dof)) of every frame for one robot."""
        adr = self._qadr[self._robot(robot)]
        return self.timeline.sim_times(), self.timeline.qpos()[:, adr]

    def part_positions(self) -> dict[str, list[float]]:
        """World position (m) of each movable part's body frame, by name."""
        return {p: self.data.xpos[b].tolist() for p, b in self._part_body.items()}

    def summary(self) -> dict[str, Any]:
        """The DESIGN.md ``workcell demo --json`` fields this slice knows (``mjcf`` None)."""
        return {
            "sim_time_s": self.sim_time,
            "wall_time_s": self._wall,
            "frames": self.frames,
            "events": [e.to_dict() for e in self.events],
            "collisions": sum(1 for e in self.events if e.kind == "collision"),
            "objects": self.part_positions(),
            "mjcf": None,
        }

    # ------------------------------------------------------------------ commands
    def set_speed(self, robot: str, speed: float) -> None:
        """Set the robot's speed (rad/s): the speed of the joint that moves most (thesis
        ``robot_speed``). Must be finite, > 0 and at most the fastest joint's limit."""
        name = self._robot(robot)
        top = float(np.max(self.cell.robots[name].robot.max_speeds))
        if not (_finite_number(speed) and 0 < float(speed) <= top):
            raise ProgramError(
                f"set_speed '{name}': speed must be a number in (0, {top:.4g}] rad/s "
                f"(the fastest joint's limit), got {speed!r}"
            )
        with self._transaction():
            self._speed[name] = float(speed)
            self.timeline.add_event(self.sim_time, name, "speed", f"speed {float(speed):.6g} rad/s")

    def move_joints_absolute(self, robot: str, q: ArrayLike) -> None:
        """Move the robot's joints to ``q`` (rad/m) in the simulator's mode."""
        name = self._robot(robot)
        target = self._vector(name, q, "move_joints_absolute", "q")
        self._move(name, target, "move_joints_absolute")

    def move_joints_relative(self, robot: str, dq: ArrayLike) -> None:
        """Move the robot's joints by ``dq`` (rad/m) in the simulator's mode."""
        name = self._robot(robot)
        d = self._vector(name, dq, "move_joints_relative", "dq")
        self._move(name, self.joints(name) + d, "move_joints_relative")

    def wait(self, seconds: float) -> None:
        """Let ``seconds`` of simulated time pass with nothing moving (one frame at the end)."""
        if not (_finite_number(seconds) and seconds >= 0):
            raise ProgramError(f"wait: seconds must be a finite number >= 0, got {seconds!r}")
        s = float(seconds)
        with self._transaction():
            if s > 0:
                c0 = time.perf_counter()
                self.timeline.append(self.sim_time + s, self._wall, self.data.qpos)
                self.sim_time += s
                self._wall += time.perf_counter() - c0
            self.timeline.add_event(self.sim_time, None, "wait", f"wait {s:.6g} s")

    def play(self, realtime: bool | None = None, start: int = 0) -> int:
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
                    walls[k] = clock()
                self.timeline.set_wall_times(i, w0 + (walls - c0))
        finally:
            qpos[:] = final
            kin(m, d)
            self._wall = w0 + (clock() - c0)
        return n - start

    # ------------------------------------------------------------------ internals
    def _robot(self, robot: object) -> str:
        if not isinstance(robot, str) or robot not in self._qadr:
            known = ", ".join(self._qadr) or "none"
            raise ProgramError(f"no robot {robot!r} in cell '{self.cell.name}'; known: {known}")
        return robot

    def _vector(self, name: str, v: ArrayLike, command: str, what: str) -> Array:
        n = len(self._qadr[name])
        try:
            a = np.array(v, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise ProgramError(
                f"{command} '{name}': {what} must be {n} numbers, got {v!r}"
            ) from exc
        if a.shape != (n,) or not np.all(np.isfinite(a)):
            raise ProgramError(
                f"{command} '{name}': {what} must be {n} finite numbers (rad/m), got {v!r}"
            )
        return a

    def _plan(self, name: str, q0: Array, target: Array) -> tuple[Array, Array]:
        """Simulated times (k,) and joint values (k, dof) of a move, last row = target."""
        speed, dt = self._speed[name], self.dt
        delta = target - q0
        big = float(np.max(np.abs(delta))) if len(delta) else 0.0
        if big == 0.0:
            return np.empty(0), np.empty((0, len(q0)))
        if self.mode != "joint-by-joint":  # path and playback: eq. 4.27, 4.28
            T = big / speed
            t = step_times(T, dt)
            Q = q0 + np.outer(t / T, delta)
            Q[-1] = target
            return self.sim_time + t, Q
        times, rows = [], []
        q = q0.copy()
        clock = self.sim_time
        fastest = int(np.argmax(np.abs(delta)))
        for i in np.flatnonzero(delta):
            Ti = abs(delta[i]) / speed
            t = step_times(Ti, dt)
            Q = np.repeat(q[None, :], len(t), axis=0)
            Q[:, i] = q0[i] + delta[i] * (t / Ti)
            Q[-1, i] = target[i]
            q[i] = target[i]
            if self.joint_by_joint_clock == "sequential" or i == fastest:
                times.append(clock + t)
                clock += Ti
            else:  # thesis: the clock runs only while the joint that moves most moves
                times.append(np.full(len(t), clock))
            rows.append(Q)
        return np.concatenate(times), np.concatenate(rows)

    def _move(self, name: str, target: Array, command: str) -> None:
        placement = self.cell.robots[name]
        try:
            placement.robot.check_limits(target)
        except JointLimitError as exc:
            raise JointLimitError(f"{command} '{name}': target refused: {exc}") from exc
        q0 = self.joints(name)
        times, Qr = self._plan(name, q0, target)
        Q = np.repeat(self.data.qpos[None, :], len(times), axis=0)
        Q[:, self._qadr[name]] = Qr
        t_before = self.sim_time
        with self._transaction():
            self._emit(times, Q)
            deg = ", ".join(f"{v:.6g}" for v in np.degrees(target))
            self.timeline.add_event(
                self.sim_time,
                name,
                "move",
                f"{command} to ({deg}) deg: {len(times)} frames, {self.sim_time - t_before:.6g} s",
            )

    def _emit(self, times: Array, Q: Array) -> None:
        """Apply (path, joint-by-joint) or store (playback) frames; advance both clocks."""
        k = len(times)
        if k == 0:
            return
        m, d = self.model, self.data
        clock = time.perf_counter
        w0 = self._wall
        c0 = clock()
        if self.mode == "playback":
            walls = np.full(k, clock())
            d.qpos[:] = Q[-1]
            mujoco.mj_kinematics(m, d)
        else:
            walls = np.empty(k)
            qpos, kin = d.qpos, mujoco.mj_kinematics
            for j in range(k):
                qpos[:] = Q[j]
                kin(m, d)
                walls[j] = clock()
        self.timeline.extend(times, w0 + (walls - c0), Q)
        self.sim_time = float(times[-1])
        self._wall = w0 + (clock() - c0)

    @contextmanager
    def _transaction(self) -> Iterator[None]:
        """Undo everything (joints, clocks, speeds, timeline) if the body raises."""
        qpos = self.data.qpos.copy()
        saved = (self.sim_time, self._wall, dict(self._speed), self.timeline.mark())
        try:
            yield
        except BaseException:
            self.sim_time, self._wall, self._speed, mark = saved
            self.timeline.truncate(mark)
            self.data.qpos[:] = qpos
            mujoco.mj_kinematics(self.model, self.data)
            raise

    def __repr__(self) -> str:
        return (
            f"Simulator(cell '{self.cell.name}', mode={self.mode!r}, dt={self.dt}, "
            f"{self.frames} frames, t_sim={self.sim_time:.6g} s)"
        )
