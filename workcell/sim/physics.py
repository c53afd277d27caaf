"""Physics mode: a kinematic run's program replayed dynamically with ``mj_step``.

The kinematic :class:`~workcell.sim.simulator.Simulator` run is the *plan*: its timeline
gives every arm joint and finger slide as a function of simulated time (linear between
frames; frames that share a time are a jump at that time) and ``sim.grasps`` gives when
each gripper took or let go of which part. :func:`run_physics` replays that plan on a
copy of the compiled model (``timestep`` s, ``implicitfast`` integrator) from the plan's
first frame. (The plan is taken at its word: in joint-by-joint mode with the thesis's
clock, joints that move while the clock stands still jump, and the servos chase steps;
use path mode, or ``joint_by_joint_clock="sequential"``.)

- every arm joint and finger slide has a position servo (see
  :mod:`workcell.robots.mjcf`: ``kp = I w^2``, ``kv = 2 I w``) whose target is the
  planned value at the step's time plus ``kv / kp`` times the planned velocity (a
  velocity feed-forward: the servo force is ``kp (q_ref - q) + kv (qdot_ref - qdot)``);
  the compiled cell's servos hold the initial pose at ctrl 0, so ``ctrl`` is the target
  minus that pose (:mod:`workcell.cell.compile`);
- the robot bodies have ``gravcomp = 1`` (the arm's own weight is compensated, the
  payload is not: the servos hold it);
- at a grasp the weld of that gripper and part is activated with the relative pose
  captured from the *actual* gripper and part poses at that step (``weld_pose="actual"``,
  the default: no jerk, the part stays where the fingers met it) or the planned one
  (``"planned"``: the weld pulls the part to the pose the plan expects); at a release it
  is deactivated and the part falls onto whatever is under it;
- while a gripper holds a part, contacts between that gripper and that part are off (as
  in the kinematic collision check; ``grip_contacts=True`` keeps them), and they stay off
  after the release until the fingers have opened;
- after the program's last frame the servos hold the final pose for ``settle`` seconds
  while the released parts come to rest.

The result (:class:`~workcell.sim.physics_result.PhysicsResult`) holds the physics frames
sampled at the plan's ``dt`` (the same recording and rendering code plays them), the
tracking error of each robot (joints: actual - planned at every step; tool: distance of
the actual tool point from the planned one), each movable part's settled pose and its
distance from the kinematic result, the deviation of each carried part from its weld,
collision events, wall time and the real-time factor. A collision is the onset (at a
recorded frame) of any contact of a robot (a link or a gripper, not with the part it
holds), or of an overlap deeper than ``contact_tolerance`` between other things (a part
resting on a support touches at a few micrometres): in physics a robot blocked by what it
hits barely overlaps it, and shows up as a tracking error instead. (Grasps, releases,
collisions and the plan's other events of a run: :mod:`workcell.sim.physics_events`;
belts, sources, sinks and sensors: :mod:`workcell.sim.physics_devices`.)

Listeners (``sim.physics_listeners``, the live view's): ``f(t, data, pairs, last)`` at each
recorded frame, on the run's thread: ``data`` is the run's ``MjData`` with the poses and
contacts of time ``t`` (s), ``pairs`` the (thing, thing) labels counted as colliding then,
``last`` True for the settled end state. A listener reads ``data`` and does not keep it.
"""

from __future__ import annotations

import copy
import itertools
import math
import sys
import time
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell import limits
from workcell.cell.compile_devices import PARKED_ABOVE
from workcell.checks import is_finite_number
from workcell.errors import ProgramError
from workcell.sim.contacts import DEFAULT_TOLERANCE, ContactMonitor
from workcell.sim.physics_devices import PhysicsDevices, is_sensor_event
from workcell.sim.physics_events import PhysicsEvents
from workcell.sim.physics_result import PhysicsResult, SettledPart, Tracking
from workcell.sim.physics_support import (
    GripContacts,
    plan_of,
    weld_deviation,
)
from workcell.sim.timeline import Event, Timeline

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["WELD_POSES", "PhysicsResult", "SettledPart", "Tracking", "run_physics"]

WELD_POSES = ("actual", "planned")
DEFAULT_SETTLE = 1.0  # s
DEFAULT_CONTACT_TOLERANCE = DEFAULT_TOLERANCE  # m, as the kinematic collision check
_BLOCK = 2048  # physics steps per block of vectorised bookkeeping
_BAD = (mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQPOS)
Array = NDArray[np.float64]


def _check(sim: object, timestep: object, settle: object, weld_pose: object, tol: object) -> None:
    if not hasattr(sim, "grasps") or not hasattr(sim, "timeline"):
        raise ProgramError(f"run_physics needs a Simulator that has run a program, got {sim!r}")
    if len(sim.timeline) == 0:  # type: ignore[attr-defined]
        raise ProgramError("run_physics: the simulator's timeline has no frames")
    if timestep is not None and not (is_finite_number(timestep) and 0 < timestep <= 0.01):
        raise ProgramError(f"timestep must be a number of seconds in (0, 0.01], got {timestep!r}")
    if not (is_finite_number(settle) and settle >= 0):
        raise ProgramError(f"settle must be a number of seconds >= 0, got {settle!r}")
    if weld_pose not in WELD_POSES:
        raise ProgramError(f"unknown weld_pose {weld_pose!r}; valid: {', '.join(WELD_POSES)}")
    if not (is_finite_number(tol) and tol > 0):
        raise ProgramError(f"contact_tolerance must be a number of metres > 0, got {tol!r}")


def run_physics(
    sim: Simulator,
    *,
    timestep: float | None = None,
    settle: float = DEFAULT_SETTLE,
    weld_pose: str = "actual",
    feedforward: bool = True,
    gravcomp: bool = True,
    grip_contacts: bool = False,
    contact_tolerance: float = DEFAULT_CONTACT_TOLERANCE,
    progress: bool | None = None,
) -> PhysicsResult:
    """Replay ``sim``'s program with dynamics (module doc) and report how it went.

    ``sim``: a simulator that has run its program (any mode; the plan is its timeline).
    ``timestep`` (s; default the model's, 0.002): the physics step; the grasp weld's
    stiffness needs <= 0.002. ``settle`` (s): time after the program for parts to come to
    rest. ``weld_pose``: "actual" or "planned" (module doc). ``feedforward``: the planned
    velocity feeds the servos; ``gravcomp``: the arms' gravity compensation (off only to
    measure what it does); ``grip_contacts``: keep contacts between a gripper and the part
    it holds. ``contact_tolerance`` (m): overlaps deeper than this between things other
    than robots are collision events (module doc).
    ``progress``: a tqdm bar on stderr (None: on a terminal, for runs over 100,000 steps).
    Raises ProgramError for bad arguments or when the simulation becomes unstable.
    """
    _check(sim, timestep, settle, weld_pose, contact_tolerance)
    options = dict(
        weld_pose=weld_pose,
        feedforward=bool(feedforward),
        gravcomp=bool(gravcomp),
        grip_contacts=bool(grip_contacts),
        contact_tolerance=float(contact_tolerance),
    )
    return _Run(sim, timestep, float(settle), options).execute(progress)


class _Run(PhysicsEvents):
    """State of one physics run (see :func:`run_physics`)."""

    def __init__(
        self, sim: Simulator, timestep: float | None, settle: float, options: dict[str, Any]
    ) -> None:
        self.c0 = time.perf_counter()
        self.sim, self.settle, self.options = sim, settle, options
        self.weld_pose = options["weld_pose"]
        cc = self.cc = sim.compiled
        m = self.m = copy.deepcopy(cc.model)  # as compiled (the simulator's copy has margins)
        if timestep is not None:
            m.opt.timestep = float(timestep)
        self.h = h = float(m.opt.timestep)
        if m.nu == 0 or np.any(m.actuator_trntype != mujoco.mjtTrn.mjTRN_JOINT):
            raise ProgramError(
                "run_physics needs a model with a position actuator on every robot joint "
                "(compile the cell with workcell.cell.compile_cell)"
            )
        if not options["gravcomp"]:
            m.body_gravcomp[:] = 0.0
        mounts = sim.contacts.allowed_geoms()  # mounted robots' link 1 and what they stand on
        self.grip = GripContacts(m, cc, switching=not options["grip_contacts"], mounts=mounts)
        self.compiled = replace(cc, model=m)
        self.monitor = ContactMonitor(self.compiled, 0.0)  # every contact; _collisions sorts
        self.monitor.allowed = set(sim.contacts.allowed)
        d = self.d = mujoco.MjData(m)
        d.qpos[:] = sim.timeline.frame(0)[2]
        mujoco.mj_forward(m, d)
        # actuators, robots, parts
        act_jnt = m.actuator_trnid[:, 0]
        self.act_adr = m.jnt_qposadr[act_jnt].astype(np.intp)
        kp, kv = m.actuator_gainprm[:, 0], -m.actuator_biasprm[:, 2]
        self.lead = kv / kp if options["feedforward"] else np.zeros(m.nu)
        self.hold = m.actuator_biasprm[:, 0] / kp  # the joint value each servo holds at ctrl 0
        self.plan = plan_of(sim, self.act_adr)
        act_of = {int(j): a for a, j in enumerate(act_jnt)}
        self.robots = list(cc.joint_names)
        self.arm_act = {
            r: np.array([act_of[m.joint(j).id] for j in js], dtype=np.intp)
            for r, js in cc.joint_names.items()
        }
        self.finger_act = {
            r: np.array([act_of[m.joint(j).id] for j in js], dtype=np.intp)
            for r, js in cc.finger_joints.items()
        }
        self.tool_ids = np.array([m.site(cc.tool_sites[r]).id for r in self.robots], np.intp)
        self.gripped = list(cc.gripper_bodies)
        self.grip_ids = np.array([m.body(cc.gripper_bodies[r]).id for r in self.gripped], np.intp)
        self.parts = list(cc.part_bodies)
        self.free_adr = {p: int(m.jnt_qposadr[m.joint(cc.free_joints[p]).id]) for p in self.parts}
        self.weld_id = {k: m.equality(e).id for k, e in cc.welds.items()}
        self.weld_key = {e: k for k, e in self.weld_id.items()}
        # steps, recorded frames, grasp events
        self.program_time = float(self.plan.t[-1])
        limits.check(
            "max_frames_per_command", (self.program_time + settle) / h, "run_physics: steps"
        )
        self.n_prog = math.floor(self.program_time / h + 1e-9)  # steps 0..n_prog: program
        self.n_end = max(math.ceil((self.program_time + settle) / h - 1e-9), 1)
        self.dt = float(getattr(sim, "dt", h))
        grid = np.arange(math.floor(self.n_end * h / self.dt + 1e-9) + 1) * self.dt
        self.record = np.zeros(self.n_end + 1, dtype=bool)
        self.record[np.minimum(np.ceil(grid / h - 1e-9).astype(np.int64), self.n_end)] = True
        self.record[self.n_end] = True
        self.todo = [
            (min(max(math.ceil(g.t / h - 1e-9), 0), self.n_end), g) for g in sim.grasps
        ]  # in program order; step times never decrease
        self.next = 0
        self.pending: list[tuple[str, str, NDArray[np.intp], Array]] = []
        self.seen: dict[tuple[str, str], float] = {}  # pair -> last time it touched (s)
        own = ("grasp", "release", "collision")  # the physics run makes its own of these
        self.events: list[tuple[float, int, Event]] = []  # a heap: (t, order, event)
        self.order = itertools.count()
        self.devices = None if sim._logic is None else PhysicsDevices(self)
        for e in sim.timeline.events:
            if e.kind in own or (self.devices is not None and is_sensor_event(e)):
                continue
            keep = e.data if e.kind in ("signal", "source", "sink") else None
            self._event(e.t, e.robot, e.kind, e.detail, keep)
        tl = sim.timeline
        self.out = Timeline(m.nq, memory_limit=tl.memory_limit, spill_dir=tl.spill_dir)
        nr = len(self.robots)
        self.sq, self.cnt = np.zeros(nr), np.zeros(nr, dtype=np.int64)
        self.jmax = [np.zeros(len(self.arm_act[r])) for r in self.robots]
        self.tmax, self.tsq = np.zeros(nr), np.zeros(nr)
        self.peak = np.zeros(m.nu)
        self.carry = {p: [0.0, 0.0, False] for p in self.parts}  # max m, max rad, held

    # ------------------------------------------------------------------ the loop
    def execute(self, progress: bool | None) -> PhysicsResult:
        """Step from the first frame to the end of settling; return the result."""
        m, d, h, n_end = self.m, self.d, self.h, self.n_end
        bounds = sorted({*range(0, n_end, _BLOCK), n_end, *(s for s, _ in self.todo)})
        devices = self.devices
        if devices is not None:
            bounds = sorted({*bounds, *(s for s in devices.steps if s < n_end)})
        lo, hi = m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1]
        show = progress if progress is not None else (sys.stderr.isatty() and n_end > 100_000)
        bar = None
        if show:
            from tqdm import tqdm

            bar = tqdm(total=n_end, unit="step", desc="physics", file=sys.stderr, leave=False)
        step, qpos, ctrl_in = mujoco.mj_step, d.qpos, d.ctrl
        xpos, xquat, sxpos, force = d.xpos, d.xquat, d.site_xpos, d.actuator_force
        tools, grips, record, clock = self.tool_ids, self.grip_ids, self.record, time.perf_counter
        listeners = list(getattr(self.sim, "physics_listeners", ()))  # a live view, say
        try:
            for a, b in itertools.pairwise(bounds):
                self._events_at(a)
                if devices is not None:
                    devices.at(a)
                k = b - a
                ts = np.arange(a, b) * h
                ref, vel = self.plan.at(ts)
                ctrl = np.clip(ref - self.hold + self.lead * vel, lo, hi)
                qb, sb, fb = np.empty((k, m.nq)), np.empty((k, len(tools), 3)), np.empty((k, m.nu))
                gp, gq = np.empty((k, len(grips), 3)), np.empty((k, len(grips), 4))
                walls = np.zeros(k)
                for j in range(k):
                    if self.pending:
                        self._reopen()
                    qb[j] = qpos
                    ctrl_in[:] = ctrl[j]
                    step(m, d)  # its forward pass is the state at ts[j]: qb[j], xpos, contacts
                    sb[j], gp[j], gq[j], fb[j] = sxpos[tools], xpos[grips], xquat[grips], force
                    if record[a + j]:
                        walls[j] = clock() - self.c0
                        hits = self._collisions(float(ts[j]))
                        if devices is not None:
                            devices.sense(float(ts[j]))
                        for listener in listeners:  # d's poses and contacts are at ts[j]
                            listener(float(ts[j]), d, hits, False)
                if any(d.warning[w].number for w in _BAD) or not np.all(np.isfinite(qpos)):
                    raise ProgramError(
                        f"the physics became unstable before t = {b * h:.4g} s (timestep "
                        f"{h} s); try a smaller timestep"
                    )
                sel = record[a:b]
                self._frames(ts[sel], walls[sel], qb[sel])
                self._tracking(a, b, qb, ref, sb, fb)
                self._carry(qb, gp, gq)
                if bar is not None:
                    bar.update(k)
            self._events_at(n_end)
            mujoco.mj_forward(m, d)
            self._frames(np.array([n_end * h]), np.array([clock() - self.c0]), qpos[None, :])
            for listener in listeners:
                listener(n_end * h, d, [], True)
        finally:
            if bar is not None:
                bar.close()
        return self._result()

    def _tracking(self, a: int, b: int, qb: Array, ref: Array, sb: Array, fb: Array) -> None:
        """Accumulate joint and tool errors and peak forces over the block's program steps."""
        p = min(b, self.n_prog + 1) - a
        if p <= 0:
            return
        cell = self.sim.cell
        for i, r in enumerate(self.robots):
            acts = self.arm_act[r]
            planned = ref[:p, acts]
            err = qb[:p, self.act_adr[acts]] - planned
            self.sq[i] += float(np.sum(err * err))
            self.cnt[i] += p
            self.jmax[i] = np.maximum(self.jmax[i], np.max(np.abs(err), axis=0))
            pl = cell.robots[r]
            tool = (pl.base @ pl.robot.fk_batch(planned))[:, :3, 3]
            dist = np.linalg.norm(sb[:p, i] - tool, axis=1)
            self.tmax[i] = max(self.tmax[i], float(dist.max()))
            self.tsq[i] += float(np.sum(dist * dist))
        self.peak = np.maximum(self.peak, np.max(np.abs(fb[:p]), axis=0))

    def _carry(self, qb: Array, gp: Array, gq: Array) -> None:
        """Largest deviation of each held part from gripper pose x weld pose in the block."""
        m, d = self.m, self.d
        for e in np.flatnonzero(d.eq_active):  # constant in a block: events start blocks
            robot, part = self.weld_key[int(e)]
            i = self.gripped.index(robot)
            adr = self.free_adr[part]
            dp, da = weld_deviation(gp[:, i], gq[:, i], m.eq_data[e, 3:10], qb[:, adr : adr + 7])
            c = self.carry[part]
            c[0], c[1], c[2] = max(c[0], dp), max(c[1], da), True

    def _result(self) -> PhysicsResult:
        m, d, h = self.m, self.d, self.h
        final = self.sim.timeline.frame(-1)[2]
        parts = {}
        for p in self.parts:
            adr = self.free_adr[p]
            if final[adr + 2] > PARKED_ABOVE:  # out of the world in the plan's end
                continue
            dof = int(m.jnt_dofadr[m.joint(self.cc.free_joints[p]).id])
            e_max, a_max, held = self.carry[p]
            s = parts[p] = SettledPart.of(
                p, d.qpos[adr : adr + 7], d.qvel[dof : dof + 6], final[adr : adr + 7],
                carry=(e_max, a_max) if held else None,
            )  # fmt: skip
            state = "resting" if s.resting else f"moving at {s.speed * 1e3:.3g} mm/s"
            where = ", ".join(f"{v:.4g}" for v in s.position)
            detail = (
                f"'{p}' settled at ({where}) m, {s.distance * 1e3:.3g} mm and "
                f"{math.degrees(s.angle):.3g} deg from the kinematic result, {state}"
            )
            self._event(self.n_end * h, None, "settle", detail)
        self._frames(np.empty(0), np.empty(0), np.empty((0, m.nq)), last=True)
        tracking = {}
        for i, r in enumerate(self.robots):
            n = max(int(self.cnt[i]), 1)
            tracking[r] = Tracking(
                joint_max=float(self.jmax[i].max()),
                joint_rms=math.sqrt(self.sq[i] / (n * len(self.arm_act[r]))),
                joint_max_each=self.jmax[i],
                tool_max=float(self.tmax[i]),
                tool_rms=math.sqrt(self.tsq[i] / n),
                peak_force=self.peak[self.arm_act[r]],
            )
        return PhysicsResult(
            cell=self.sim.cell,
            compiled=self.compiled,
            model=m,
            data=d,
            timeline=self.out,
            dt=self.dt,
            timestep=h,
            settle=self.settle,
            program_time=self.program_time,
            sim_time=self.n_end * h,
            wall_time=time.perf_counter() - self.c0,
            tracking=tracking,
            parts=parts,
            options=self.options,
            commands=self.sim.cycle_time()["commands"],  # the plan's: the program replayed
        )
