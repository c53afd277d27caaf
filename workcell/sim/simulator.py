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

Clocks (§4.4.3; the thesis's words in docs/thesis.md): the *simulated clock* is the time
the commands would take on a real robot: dT per step in path and playback mode (stored in
the frames), and in joint-by-joint mode the time of the joint that moves most, so a
command takes ``max_i |Delta theta_i| / theta_dot`` in every mode.
``joint_by_joint_clock="sequential"`` instead charges each joint its own
``|Delta theta_i| / theta_dot`` (their sum: what a robot moving one joint at a time would
take). The *wall clock* is a stopwatch that runs while the simulator works (computing,
showing or replaying frames); both clocks are kept on every frame of the timeline.

Cartesian commands (thesis §4.5; see :mod:`workcell.sim.cartesian`):
``move_end_effector(robot, T, config)`` solves IK for the world tool pose T and moves
linearly in joints like ``move_joints_absolute``; ``move_straight_line(robot, T, step)``
samples the Cartesian line, solves IK at each sample warm-started at the previous one and
moves linearly in joints between samples (path-mode timing in every mode), checking the
joint jumps and the tool's deviation from the line (``line_tolerance``).

Grasping (§4.5; :mod:`workcell.sim.gripping`): ``close_gripper`` grasps the first
movable part that passes the thesis's three tests and carries it exactly (a weld) until
``open_gripper``; a part may be held by two robots at once (a handoff).

Collisions (``check_collisions``, default on; :mod:`workcell.sim.frames`): every pair of
things that starts overlapping by more than ``contact_tolerance`` (m) in a frame becomes a
``collision`` event; ``stop_on_collision`` raises :class:`CollisionError` at the first
one. :meth:`Simulator.clearance` gives the minimum distance between two named things.

Several robots at once (beyond the thesis; :mod:`workcell.sim.concurrent`): inside
``with sim.concurrently():`` each robot's motion commands start together and the frames
are merged, so the clock advances by the longest robot's time.

Planning and task level (beyond the thesis; :mod:`workcell.sim.planned`,
:mod:`workcell.sim.task_commands`, calling the planners of :mod:`workcell.plan`):
``plan=True`` on ``move_joints_absolute`` and ``move_end_effector`` moves along a
collision-free path (OMPL), ``pick``, ``place`` and ``handover`` choose poses,
configurations and paths themselves; a part released in mid-air gets a ``warning`` event, or drops onto what is
below it with ``open_gripper(..., settle=True)``.

Profiles (``profile``; :mod:`workcell.sim.profiles`): the thesis's constant speed
("linear"), or, beyond the thesis, "trapezoid" (``acceleration`` rad/s^2) or "quintic",
for joint moves and ``move_end_effector``; the simulated clock then runs by the
profile's duration. Like an industrial controller (:mod:`workcell.sim.motion`): profile
"jerk" (each joint's own speed, acceleration and jerk limits), ``move_linear`` and
``move_circular`` at a tool speed, zones that blend a move into the next, the speed
override, and the cycle-time report (``summary()["commands"]``).

Errors: every command validates first (unknown robot: ProgramError listing the robots;
target outside the limits: JointLimitError naming the joint and its range; bad speed or
vector: ProgramError) and changes nothing when it fails; an exception while frames are
applied undoes the command (:mod:`workcell.sim.frames`).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell import limits
from workcell.cell.compile import CompiledCell, compile_cell, subtree_bodies
from workcell.cell.workcell import Workcell
from workcell.checks import is_finite_number, quote_angle
from workcell.errors import (
    ProgramError,
)
from workcell.sim import profiles
from workcell.sim.blending import Pending
from workcell.sim.cartesian import CartesianCommands
from workcell.sim.concurrent import ConcurrentCommands
from workcell.sim.contacts import (
    DEFAULT_TOLERANCE,
    ContactMonitor,
    contact_model,
)
from workcell.sim.cycle import command_record
from workcell.sim.devices import CellLogic
from workcell.sim.frames import FrameRunner
from workcell.sim.gripping import GraspRecord, GripperCommands, Hold
from workcell.sim.jogging import JogCommands
from workcell.sim.motion import MotionCommands
from workcell.sim.planned import PlanningCommands
from workcell.sim.profiles import step_times
from workcell.sim.readback import ReadBack
from workcell.sim.resting import RestingCommands
from workcell.sim.signals import SignalCommands
from workcell.sim.task_commands import TaskCommands
from workcell.sim.timeline import DEFAULT_MEMORY_LIMIT, Timeline

__all__ = ["JOINT_BY_JOINT_CLOCKS", "MODES", "Hold", "Simulator", "step_times"]

MODES = ("path", "joint-by-joint", "playback")
JOINT_BY_JOINT_CLOCKS = ("thesis", "sequential")

Array = NDArray[np.float64]


class Simulator(
    MotionCommands,
    CartesianCommands,
    GripperCommands,
    ConcurrentCommands,
    PlanningCommands,
    RestingCommands,
    TaskCommands,
    JogCommands,
    FrameRunner,
    ReadBack,
    SignalCommands,
):
    """Kinematic simulator of a workcell (see the module doc).

    ``mode``: "path", "joint-by-joint" or "playback"; ``dt`` the sampling interval dT
    (s); ``realtime``: playback waits dT per frame (default: as fast as possible);
    ``joint_by_joint_clock``: "thesis" or "sequential"; ``compiled``: an already compiled
    cell (default: compile ``cell``); ``memory_limit`` (bytes, None: none) and
    ``spill_dir``: frames beyond the limit spill to a temporary file (see
    :class:`~workcell.sim.timeline.Timeline`). ``check_collisions``,
    ``stop_on_collision`` and ``contact_tolerance`` (m): collision events (module doc);
    ``profile`` ("linear", "trapezoid", "quintic") and ``acceleration`` (rad/s^2, for
    "trapezoid"): joint-move time profiles; ``line_tolerance`` (m): the largest
    deviation of a straight line's frames from the line; ``progress``: a progress bar on
    stderr for commands of more than 100,000 frames (None: only when stderr is a terminal).
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
        check_collisions: bool = True,
        stop_on_collision: bool = False,
        contact_tolerance: float = DEFAULT_TOLERANCE,
        profile: str = "linear",
        acceleration: float = 2.0,
        line_tolerance: float = 1e-3,
        progress: bool | None = None,
    ) -> None:
        if mode not in MODES:
            raise ProgramError(f"unknown simulation mode {mode!r}; valid: {', '.join(MODES)}")
        if not (is_finite_number(dt) and dt > 0):
            raise ProgramError(f"dt must be a finite number of seconds > 0, got {dt!r}")
        if joint_by_joint_clock not in JOINT_BY_JOINT_CLOCKS:
            raise ProgramError(
                f"unknown joint_by_joint_clock {joint_by_joint_clock!r}; "
                f"valid: {', '.join(JOINT_BY_JOINT_CLOCKS)}"
            )
        if profile not in profiles.PROFILES:
            raise ProgramError(
                f"unknown profile {profile!r}; valid: {', '.join(profiles.PROFILES)}"
            )
        for what, v in (
            ("acceleration", acceleration),
            ("contact_tolerance", contact_tolerance),
            ("line_tolerance", line_tolerance),
        ):
            if not (is_finite_number(v) and v > 0):
                raise ProgramError(f"{what} must be a finite number > 0, got {v!r}")
        self.cell = cell
        self.mode = mode
        self.profile = profile
        self.acceleration = float(acceleration)
        self.line_tolerance = float(line_tolerance)
        self.progress = progress
        self.check_collisions = bool(check_collisions)
        self.stop_on_collision = bool(stop_on_collision)
        self.dt = float(dt)
        self.realtime = bool(realtime)
        self.joint_by_joint_clock = joint_by_joint_clock
        self.compiled = compile_cell(cell) if compiled is None else compiled
        # the simulator's own copy (grasps write its eq_data; contacts use its margins)
        self.model: mujoco.MjModel = contact_model(self.compiled.model)
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
        self._override = dict.fromkeys(self._qadr, 1.0)  # speed override per robot
        self._pending: dict[str, Pending] = {}  # zone moves the next move may blend out of
        m, cc = self.model, self.compiled
        self._part_body = {p: m.body(b).id for p, b in cc.part_bodies.items()}
        self._free_adr = {p: int(m.jnt_qposadr[m.joint(j).id]) for p, j in cc.free_joints.items()}
        self._fingers: dict[str, NDArray[np.intp]] = {
            r: np.array([m.jnt_qposadr[m.joint(j).id] for j in js], dtype=np.intp)
            for r, js in cc.finger_joints.items()
        }
        self._gripper: dict[str, int] = {r: m.body(b).id for r, b in cc.gripper_bodies.items()}
        self._gripper_tree = {r: set(subtree_bodies(m, g)) for r, g in self._gripper.items()}
        self._weld = {k: m.equality(e).id for k, e in cc.welds.items()}
        pattern = {p: cc.patterns.get(p, p) for p in cc.part_bodies}  # a copy's part
        self._boxes = {p: cell.bounding_box(pattern[p]) for p in cc.part_bodies}
        self._centroids = {p: cell.centroid_frame(pattern[p])[:3, 3] for p in cc.part_bodies}
        self._holds: dict[str, Hold] = {}
        self.grasps: list[GraspRecord] = []  # every grasp and release, in order
        self._holders: dict[str, list[str]] = {p: [] for p in cc.part_bodies}
        self.contacts = ContactMonitor(cc, contact_tolerance, self.model)
        self.contacts.mount(self.data)  # a robot's link 1 may touch what its base stands on
        self._touching: set[tuple[str, str]] = set()
        self.sim_time = 0.0
        self._wall = 0.0
        # f(frame, t) each time data shows a frame (observers: workcell.sim.frames)
        self.frame_listeners: list[Callable[[int, float], None]] = []
        # f(t, data, pairs, last) at each recorded frame of a physics replay of this
        # simulator's program (workcell.sim.physics)
        self.physics_listeners: list[
            Callable[[float, mujoco.MjData, list[tuple[str, str]], bool], None]
        ] = []
        self.timeline = Timeline(self.model.nq, memory_limit=memory_limit, spill_dir=spill_dir)
        self._logic = CellLogic.of(self)  # the devices (None: the cell has none)
        if self._logic is not None:
            self._logic.start()
        self.event_listeners = self.timeline.listeners  # f(event) as each event is recorded
        self.timeline.append(0.0, 0.0, self.data.qpos)
        if self.check_collisions:
            mujoco.mj_collision(m, self.data)
            self._contact_events(0.0, self.contacts.penetrations(self.data), stop=False)

    # ------------------------------------------------------------------ commands
    def set_speed(self, robot: str, speed: float) -> None:
        """Set the robot's speed (rad/s): the speed of the joint that moves most (thesis
        ``robot_speed``). Must be finite, > 0 and at most the fastest joint's limit."""
        name = self._robot(robot)
        top = float(np.max(self.cell.robots[name].robot.max_speeds))
        if not (is_finite_number(speed) and 0 < float(speed) <= top):
            raise ProgramError(
                f"set_speed '{name}': speed must be > 0 and at most {quote_angle(top, '/s')} "
                f"(the fastest joint's limit), got {quote_angle(speed, '/s')}"
            )
        with self._transaction():
            self._speed[name] = float(speed)
            self.timeline.add_event(self.sim_time, name, "speed", f"speed {float(speed):.6g} rad/s")

    def move_joints_absolute(
        self, robot: str, q: ArrayLike | str, *, zone: float = 0.0, plan: bool = False
    ) -> None:
        """Move the robot's joints to ``q`` (rad/m), or to one of its named poses
        (``"home"``), in the simulator's mode; ``zone`` (m): blend into the next move
        (:mod:`workcell.sim.blending`); with ``plan``, along a collision-free path
        (:mod:`workcell.sim.planned`; PlanningError when none; a planned path stops at
        its end: no zone)."""
        name = self._robot(robot)
        if isinstance(q, str):
            poses = self.cell.robots[name].robot.poses
            if q not in poses:
                raise ProgramError(
                    f"move_joints_absolute '{name}': no pose {q!r}; "
                    f"named poses: {', '.join(poses) or 'none'}"
                )
            q = poses[q]
        target = self._vector(name, q, "move_joints_absolute", "q")
        if plan:
            self._check_target(name, target, "move_joints_absolute")
            self._move_planned(name, [target], "move_joints_absolute")
        else:
            self._move(name, target, "move_joints_absolute", zone)

    def move_joints_relative(self, robot: str, dq: ArrayLike, *, zone: float = 0.0) -> None:
        """Move the robot's joints by ``dq`` (rad/m) in the simulator's mode; ``zone`` (m)
        as for :meth:`move_joints_absolute`."""
        name = self._robot(robot)
        d = self._vector(name, dq, "move_joints_relative", "dq")
        self._move(name, self.joints(name) + d, "move_joints_relative", zone)

    def set_mode(self, mode: str) -> None:
        """Switch the simulation mode for the commands that follow."""
        if mode not in MODES:
            raise ProgramError(f"unknown simulation mode {mode!r}; valid: {', '.join(MODES)}")
        self._not_in_block("set_mode")
        self.mode = mode
        self.timeline.add_event(self.sim_time, None, "mode", f"mode {mode}")

    def wait(self, seconds: float) -> None:
        """Let ``seconds`` of simulated time pass, no robot moving: one frame at the end;
        with devices, the cell alive (a frame every dt while belts or sources can change
        something, :mod:`workcell.sim.signals`); in ``run_programs``, the other programs
        go on (:mod:`workcell.logic`)."""
        if not (is_finite_number(seconds) and seconds >= 0):
            raise ProgramError(f"wait: seconds must be a finite number >= 0, got {seconds!r}")
        self._not_in_block("wait")
        s = float(seconds)
        limits.check("max_sim_time", self.sim_time + s, f"wait {s:.6g} s: the clock")
        if self._block is not None:  # run_programs: the scheduler lets time pass
            self._block.wait(self, s)
            return
        with self._transaction():
            if s > 0 and self._logic is not None:
                self._pass_time(s, "wait")
            elif s > 0:
                c0 = time.perf_counter()
                self.timeline.append(self.sim_time + s, self._wall, self.data.qpos)
                self.sim_time += s
                self._wall += time.perf_counter() - c0
            asked = {"kind": "wait", "seconds": s}
            rec = command_record(None, "wait", self.sim_time - s, s, "wait", program=asked)
            self.timeline.add_event(self.sim_time, None, "wait", f"wait {s:.6g} s", data=rec)

    def _log_error(self, exc: BaseException, robot: str | None = None) -> None:
        """Note on the timeline that the program stopped on ``exc``: an ``error`` event
        (its type and message) at the current time. The failed command itself changed
        nothing; this is for runners that record or report the run up to the error."""
        self.timeline.add_event(self.sim_time, robot, "error", f"{type(exc).__name__}: {exc}")

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
        if a.shape != (n,):
            got = f"{a.size} value(s)" if a.ndim == 1 else f"an array of shape {a.shape}"
            raise ProgramError(
                f"{command} '{name}': {what} must be {n} joint values (one per joint), got {got}"
            )
        if not np.all(np.isfinite(a)):
            raise ProgramError(f"{command} '{name}': {what} must be finite, got {a.tolist()}")
        return a

    def __repr__(self) -> str:
        return (
            f"Simulator(cell '{self.cell.name}', mode={self.mode!r}, dt={self.dt}, "
            f"{self.frames} frames, t_sim={self.sim_time:.6g} s)"
        )
