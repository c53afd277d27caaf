"""What a study measures on a finished run: clearance, reach margin, joint-limit margin.

**Clearance** (``min_clearance_m``, ``clearance_bound_m``, ``clearance_pair``): the
smallest distance between a robot (its links and gripper) and an obstacle (the static
parts, the ground and the other robots) over the run. Movable parts are the work, not
obstacles: fingers touch them and a placed part touches its support by design.

- Measured: MuJoCo's own narrow phase on the convex collision pieces, ``mj_collision`` on
  a copy of the model whose geom margins add up to ``cutoff`` and whose contact bits
  admit only robot-obstacle pairs, so every contact it lists is a pair closer than the
  cutoff with its signed distance (distances of the cutoff or more count as the cutoff).
  First every 32nd frame and the last frame of each command (where a robot comes to
  rest, often closest to something).
- Bound: between two measured instants a and b every point of a robot moves at most
  ``delta = sum_j rho_j * TV_j(a, b)``: TV_j the total variation of joint j in between
  (frames are joined linearly in joint space) and rho_j an upper bound of the distance
  from joint j's axis to any point of the links it moves (the next anchor's distance from
  the axis, the chain of anchors after it and each geom's bounding sphere: each term is
  fixed in one body, so it holds in every configuration; 1 for a slide). So the clearance
  between them is at least ``(c_a + c_b - delta) / 2``.
- Refined: an interval whose bound is below the best clearance found less ``tolerance``
  is split at its middle (a frame, then points between frames on the joint-space line)
  and measured, lowest bound first, until none is (only below half the cutoff: farther
  clearances are reported, not refined). Then ``min_clearance_m`` (the smallest measured)
  and ``clearance_bound_m`` (the smallest bound left) enclose the true minimum over the
  continuous motion within ``tolerance``. Example 2: 7.5 mm and 7.0 mm from ~300 of its
  3,460 frames, ~7 ms of CPU.

**Reach margin** (``reach_margin_m``): for every Cartesian target the program gave
(``move_end_effector`` and ``move_straight_line`` goals), how far the target can move
along the ray from the robot's shoulder (the point of joint 1's axis nearest joint 2's
axis) before the robot cannot reach it any more, with the same orientation and arm/elbow
configuration, outwards and inwards; the smallest over targets and both directions. Found
by doubling steps from 1 cm, then bisection to 1 mm (a gap in the workspace narrower
than the step can be stepped over; each search stops at the smallest margin found so
far); IK as ``move_end_effector`` solves it (closed form for OPW and UR robots).

**Joint-limit margin** (``joint_limit_margin_deg``): the smallest distance of a revolute
joint from its nearest limit over every frame of the run, in degrees.
"""

from __future__ import annotations

import copy
import heapq
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.cell.compile import CompiledCell, subtree_bodies
from workcell.cell.workcell import RobotPlacement
from workcell.errors import KinematicsError
from workcell.robots.ik_closed import config_of
from workcell.sim.cartesian import solve_pose
from workcell.sim.contacts import ContactMonitor

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = [
    "Clearance",
    "ClearanceModel",
    "base_overlaps",
    "clearance",
    "joint_limit_margin",
    "reach_margin",
    "target_config",
]

Array = NDArray[np.float64]
_FIRST_STEP = 0.01  # m: reach search, first step
_RESOLUTION = 0.001  # m: reach search, bisection stops here
_FAR = 5.0  # m: reach search, farthest look
_EVERY = 32  # clearance: frames between first samples
_BUDGET = 5000  # clearance: most refinements of one run


@dataclass(frozen=True)
class Clearance:
    """Sampled minimum (m, at most the cutoff), guaranteed lower bound (m), and where."""

    minimum: float
    bound: float
    pair: str


def _joint_path(m: mujoco.MjModel, j: int, body: int) -> list[int]:
    """Joints on the chain from joint ``j`` (included) down to ``body``, in order."""
    chain = []
    b = body
    top = int(m.jnt_bodyid[j])
    while b != top:
        chain.append(b)
        b = int(m.body_parentid[b])
    joints = [
        k for k in range(m.body_jntadr[top], m.body_jntadr[top] + m.body_jntnum[top]) if k >= j
    ]
    for b in reversed(chain):
        joints.extend(range(m.body_jntadr[b], m.body_jntadr[b] + m.body_jntnum[b]))
    return joints


class ClearanceModel:
    """How to measure clearance on the variants of one compiled cell (module doc):
    robot-obstacle contact bits and each robot's joint radii ``rho``."""

    def __init__(self, compiled: CompiledCell, cutoff: float) -> None:
        m = compiled.model
        self.cutoff = float(cutoff)
        monitor = ContactMonitor(compiled)
        self.labels = monitor.labels
        robots = list(compiled.robot_prefixes)
        bits = {r: 1 << (i + 1) for i, r in enumerate(robots)}
        every = sum(bits.values())
        self.contype = np.zeros(m.ngeom, dtype=np.int32)
        self.conaffinity = np.zeros(m.ngeom, dtype=np.int32)
        for g in monitor.colliding:
            robot = monitor.robot_of(self.labels[g])
            if robot is not None:
                self.contype[g] = bits[robot]
                self.conaffinity[g] = 1 | (every & ~bits[robot])
            elif m.geom_bodyid[g] == 0:  # static parts and the ground
                self.contype[g], self.conaffinity[g] = 1, every
        self.body_contype = np.zeros(m.nbody, dtype=np.int32)
        self.body_conaffinity = np.zeros(m.nbody, dtype=np.int32)
        np.bitwise_or.at(self.body_contype, m.geom_bodyid, self.contype)
        np.bitwise_or.at(self.body_conaffinity, m.geom_bodyid, self.conaffinity)
        d = mujoco.MjData(m)
        mujoco.mj_kinematics(m, d)
        self.joints: list[tuple[NDArray[np.intp], Array]] = []  # (qpos addresses, rho)
        for r in robots:
            root = m.body(f"{compiled.robot_prefixes[r]}link0").id
            bodies = set(subtree_bodies(m, root))
            joints = [j for j in range(m.njnt) if int(m.jnt_bodyid[j]) in bodies]
            geoms = [g for g in range(m.ngeom) if self.contype[g] and m.geom_bodyid[g] in bodies]
            rho = np.array([self._rho(m, d, j, geoms) for j in joints])
            adr = np.array([m.jnt_qposadr[j] for j in joints], dtype=np.intp)
            self.joints.append((adr, rho))

    @staticmethod
    def _rho(m: mujoco.MjModel, d: mujoco.MjData, j: int, geoms: list[int]) -> float:
        """Upper bound (m) of the distance from joint j's axis to any point it moves:
        the perpendicular distance of the next anchor (or the geom's centre) from the axis,
        then the chain of anchors, each geom's bounding sphere and slide travels; each term
        is fixed in one body, so the bound holds in every configuration."""
        slide = mujoco.mjtJoint.mjJNT_SLIDE
        if m.jnt_type[j] == slide:
            return 1.0  # a slide moves every point by exactly its own travel
        below = set(subtree_bodies(m, int(m.jnt_bodyid[j])))
        axis, anchor = d.xaxis[j], d.xanchor[j]

        def off_axis(v: Array) -> float:
            return float(np.linalg.norm(v - (v @ axis) * axis))

        best = 0.0
        for g in geoms:
            if int(m.geom_bodyid[g]) not in below:
                continue
            path = _joint_path(m, j, int(m.geom_bodyid[g]))
            centre = d.geom_xpos[g]
            if len(path) == 1:
                reach = off_axis(centre - anchor)
            else:
                reach = off_axis(d.xanchor[path[1]] - anchor)
                for k, k2 in itertools.pairwise(path[1:]):
                    reach += float(np.linalg.norm(d.xanchor[k2] - d.xanchor[k]))
                reach += float(np.linalg.norm(centre - d.xanchor[path[-1]]))
            reach += float(m.geom_rbound[g])
            for k in path[1:]:
                if m.jnt_type[k] == slide:
                    reach += float(m.jnt_range[k, 1] - m.jnt_range[k, 0])
            best = max(best, reach)
        return best

    def measuring_model(self, model: mujoco.MjModel) -> mujoco.MjModel:
        """A copy of a variant's ``model`` that lists robot-obstacle pairs within the cutoff."""
        m = copy.copy(model)
        m.geom_contype[:] = self.contype
        m.geom_conaffinity[:] = self.conaffinity
        m.body_contype[:] = self.body_contype
        m.body_conaffinity[:] = self.body_conaffinity
        m.geom_margin[:] = self.cutoff / 2.0
        m.geom_gap[:] = 0.0
        m.body_margin[:] = self.cutoff / 2.0
        return m


def _sample_frames(times: Array, move_ends: list[float], every: int) -> NDArray[np.intp]:
    n = len(times)
    ends = np.searchsorted(times, np.asarray(move_ends, dtype=np.float64), side="right") - 1
    idx = np.concatenate([np.arange(0, n, every), [n - 1], ends[(ends >= 0) & (ends < n)]])
    return np.unique(idx.astype(np.intp))


def clearance(sim: Simulator, cm: ClearanceModel, tolerance: float) -> Clearance:
    """Clearance of the finished run of ``sim``, to ``tolerance`` (m; module doc)."""
    m = cm.measuring_model(sim.model)
    d = mujoco.MjData(m)
    timeline = sim.timeline
    Q = timeline.qpos()
    n = len(Q)
    step = np.zeros(max(n - 1, 0))
    for adr, rho in cm.joints:
        step += np.abs(np.diff(Q[:, adr], axis=0)) @ rho
    D = np.concatenate([[0.0], np.cumsum(step)])  # displacement bound from frame 0 (m)
    seen: dict[float, tuple[float, float]] = {}  # s -> (clearance, displacement bound)
    where = ["", math.inf]

    def measure(s: float) -> float:
        """Clearance at s (frames; between frames: on the joint-space line)."""
        f = min(int(s), n - 1)
        t = s - f
        if t == 0.0:
            d.qpos[:] = Q[f]
            disp = float(D[f])
        else:
            d.qpos[:] = Q[f] + t * (Q[f + 1] - Q[f])
            disp = float(D[f] + t * step[f])
        mujoco.mj_kinematics(m, d)
        mujoco.mj_collision(m, d)
        c = cm.cutoff
        if d.ncon:
            dist = d.contact.dist[: d.ncon]
            i = int(np.argmin(dist))
            c = min(c, float(dist[i]))
            if c < where[1]:
                con = d.contact[i]
                a, b = sorted((cm.labels[con.geom1], cm.labels[con.geom2]))
                where[:] = [f"{a} / {b}", c]
        seen[s] = (c, disp)
        return c

    def bound(a: float, b: float) -> float:
        (ca, da), (cb, db) = seen[a], seen[b]
        return (ca + cb - (db - da)) / 2.0

    moves = [e.t for e in timeline.events if e.kind == "move"]
    idx = [float(f) for f in _sample_frames(timeline.sim_times(), moves, _EVERY)]
    best = min(measure(s) for s in idx)
    heap = [(bound(a, b), a, b) for a, b in itertools.pairwise(idx)]
    heapq.heapify(heap)
    budget = _BUDGET
    # refine where the clearance could be below the best found (only below half the
    # cutoff: farther clearances are reported, not certified to the tolerance)
    while heap and heap[0][0] < min(best, cm.cutoff / 2.0) - tolerance and budget > 0:
        _, a, b = heapq.heappop(heap)
        mid = float((int(a) + int(b)) // 2) if b - a > 1 and a == int(a) else (a + b) / 2.0
        best = min(best, measure(mid))
        budget -= 1
        heapq.heappush(heap, (bound(a, mid), a, mid))
        heapq.heappush(heap, (bound(mid, b), mid, b))
    low = min(best, heap[0][0]) if heap else best
    return Clearance(best, low, str(where[0]))


def base_overlaps(sim: Simulator, tolerance: float) -> list[tuple[str, str, float]]:
    """Robot bases (link 0, fixed to the world, so never in MuJoCo's contacts with static
    geometry) overlapping a static part or another base by more than ``tolerance`` (m):
    (base label, other label, depth m)."""
    m, d, monitor = sim.model, sim.data, sim.contacts
    prefixes = sim.compiled.robot_prefixes
    bases = {f"{p}link0" for p in prefixes.values()}
    statics = [g for g in monitor.colliding if m.geom_bodyid[g] == 0]
    mine = [g for g in monitor.colliding if monitor.labels[g] in bases]
    out = []
    for i, g in enumerate(mine):
        others = statics + [h for h in mine[i + 1 :] if monitor.labels[h] != monitor.labels[g]]
        for h in others:
            dist = mujoco.mj_geomDistance(m, d, int(g), int(h), 1.0, None)
            if dist < -tolerance:
                out.append((monitor.labels[g], monitor.labels[h], -float(dist)))
    return out


def target_config(placement: RobotPlacement, q: Array) -> str | None:
    """The arm and elbow letters of a closed-form (OPW or UR) robot at q (None for others)."""
    if placement.robot.ik_family is None:
        return None
    return config_of(placement.robot, q)[:2]


def _shoulder(sim: Simulator, robot: str) -> Array:
    """World point of joint 1's axis nearest joint 2's axis (joint 1's anchor if parallel)."""
    m, d = sim.model, sim.data
    names = sim.compiled.joint_names[robot]
    j1 = m.joint(names[0]).id
    a1, u1 = d.xanchor[j1].copy(), d.xaxis[j1].copy()
    if len(names) < 2:
        return a1
    j2 = m.joint(names[1]).id
    a2, u2 = d.xanchor[j2], d.xaxis[j2]
    w = a1 - a2
    b = float(u1 @ u2)
    den = 1.0 - b * b
    if den < 1e-12:
        return a1
    s = (b * float(u2 @ w) - float(u1 @ w)) / den
    return a1 + s * u1


def _distance_to_boundary(reachable: Callable[[float], bool], start: float, limit: float) -> float:
    """How far (m, <= limit) one can go from 0 before ``reachable(t)`` fails (module doc)."""
    ok, t = 0.0, start
    while t < limit and reachable(t):
        ok, t = t, 2.0 * t
    if t >= limit:
        if reachable(limit):
            return limit
        t = limit
    bad = t
    while bad - ok > _RESOLUTION:
        mid = (ok + bad) / 2.0
        if reachable(mid):
            ok = mid
        else:
            bad = mid
    return ok


def _reachable(
    placement: RobotPlacement, T: Array, u: Array, config: str | None, sign: float, t: float
) -> bool:
    """Whether the tool reaches T moved by ``sign * t`` (m) along ``u``."""
    G = T.copy()
    G[:3, 3] = T[:3, 3] + sign * t * u
    try:
        solve_pose(placement, G, placement.q, config)
    except KinematicsError:
        return False
    return True


def reach_margin(sim: Simulator, targets: list[tuple[str, Array, str | None]]) -> float | None:
    """The reach margin (m) of the run's Cartesian ``targets`` (robot, world pose, config;
    module doc); None when the program gave none."""
    seen: set[tuple[str, bytes, str | None]] = set()
    best = math.inf
    for robot, T, config in targets:
        key = (robot, T.tobytes(), config)
        if key in seen:
            continue
        seen.add(key)
        placement = sim.cell.robots[robot]
        c = _shoulder(sim, robot)
        r = float(np.linalg.norm(T[:3, 3] - c))
        u = (T[:3, 3] - c) / r if r > 1e-9 else np.array([0.0, 0.0, 1.0])
        out = _distance_to_boundary(
            partial(_reachable, placement, T, u, config, 1.0), _FIRST_STEP, _FAR
        )
        inward = _distance_to_boundary(
            partial(_reachable, placement, T, u, config, -1.0), _FIRST_STEP, r
        )
        best = min(best, out, inward)
    return None if best == math.inf else float(best)


def joint_limit_margin(sim: Simulator) -> float:
    """The smallest distance (deg) of a revolute joint from a limit over the run."""
    best = math.inf
    for name, placement in sim.cell.robots.items():
        robot = placement.robot
        rev = np.asarray(robot.revolute, dtype=bool)
        if not rev.any():
            continue
        q = sim.trajectory(name)[1][:, rev]
        lo, hi = robot.lower[rev], robot.upper[rev]
        best = min(best, float(np.minimum(q - lo, hi - q).min()))
    return math.degrees(best)
