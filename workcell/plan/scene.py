"""Collision checks for motion planning: robots' configurations in a frozen copy of the cell.

A :class:`PlanningScene` copies the simulator's model and state when it is made. Its
*moving* things are the links of the planned robots (from the first arm joint on,
gripper included) and the parts they carry (posed at gripper x relative pose, as the
simulator carries them); everything else stands where it is. A configuration is valid
when no moving thing comes closer than ``clearance`` (m) to anything else (other robots,
parts, the ground, the robot's own links: MuJoCo's ``mj_collision`` on the convex
collision pieces, with geom margins of ``clearance / 2`` so pairs closer than the
clearance are listed), except:

- pairs the simulator never checks (a held part and the gripper holding it, links up to
  two apart, parent and child bodies) and (gripper, part) pairs the caller names
  (``grips``: a gripper about to grasp a part may straddle it closely);
- pairs already closer than the clearance in the scene's start state (*touching*: a part
  resting on its support, a gripper around the part it has just released): these may stay
  close but must not overlap by more than ``tolerance`` (the simulator's contact
  tolerance). A pair overlapping by more than that at the start is a *start collision*
  (:attr:`PlanningScene.start_collision`).

Only the pairs to check are computed (contact bits: one per group of fixed things, moving
links, and each gripper and part never checked together; two groups collide unless both
are fixed or they are such a pair), so a check in free space costs one or two
``mj_kinematics`` and one ``mj_collision`` with no contact to look at (~10-20 us here).

:meth:`PlanningScene.radii` bounds how far things move with the joints: a point of the
links after joint i moves at most ``sum_i |dq_i| R_i`` along a straight joint-space
segment, with ``R_i`` the largest distance from joint i's axis to any moving geometry
beyond it (the chain of joint-anchor distances plus each geom's bounding sphere; 1 for a
prismatic joint), so checks ``sum_i |dq_i| R_i / clearance`` times along a segment keep
every displacement between two checks within the clearance
(:func:`workcell.plan.rrt.checks_needed`).
Units: metres, radians.
"""

from __future__ import annotations

import copy
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Protocol

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.cell.compile import CompiledCell
from workcell.spatial import quat_from_matrix

__all__ = ["PlanningScene", "SceneSource", "Violation"]

Array = NDArray[np.float64]
Violation = tuple[str, str, float]  # (thing, thing, signed distance m)


class _Contacts(Protocol):
    tolerance: float  # m: the overlap allowed to things touching
    colliding: Sequence[int]  # the collision geoms
    labels: Sequence[str]  # each geom's thing label, by geom id


class SceneSource(Protocol):
    """What a :class:`PlanningScene` copies: a simulator's model, state and bookkeeping
    (:class:`workcell.sim.Simulator` is one; the planners never import it). Joint and
    free-joint addresses index ``data.qpos``; bodies are MuJoCo body ids."""

    model: mujoco.MjModel
    data: mujoco.MjData
    compiled: CompiledCell
    contacts: _Contacts
    _qadr: Mapping[str, NDArray[np.intp]]  # robot -> its arm joints' qpos addresses
    _holds: Mapping[str, Any]  # robot -> what it holds (``.part``)
    _gripper_tree: Mapping[str, set[int]]  # robot -> its gripper's bodies
    _part_body: Mapping[str, int]  # movable part -> its body
    _fingers: Mapping[str, NDArray[np.intp]]  # robot -> its fingers' qpos addresses
    _free_adr: Mapping[str, int]  # movable part -> its free joint's qpos address

    def _carried(self, name: str) -> list[tuple[int, int, Array, Array]]:
        """(gripper body, free-joint qpos address, relative pos, quat) of what ``name``
        carries."""
        ...


class PlanningScene:
    """Validity of configurations of ``robots`` in a copy of ``sim``'s current state
    (``sim``: a :class:`SceneSource`, such as the simulator).

    ``clearance`` (m): the distance moving things keep from everything else;
    ``tolerance`` (m): the overlap allowed for pairs touching at the start (default: the
    simulator's contact tolerance); ``grips``: (robot, part) pairs whose gripper and
    part are never checked, besides what the grippers hold (a gripper and the part it is
    about to grasp); ``touching``: pairs of thing
    labels that may touch as if they touched at the start (a part and the support it is
    put down on). A hypothetical state to check from: ``carry`` False (moving robots do not
    carry what they hold), ``fingers`` (robot -> each finger's opening, m from closed),
    ``state`` (robot -> joint values, any robot) and ``parts`` (part -> body pose, 4x4),
    applied after the start state's touching pairs are recorded.
    """

    def __init__(
        self,
        sim: SceneSource,
        robots: Iterable[str],
        *,
        clearance: float,
        tolerance: float | None = None,
        grips: Iterable[tuple[str, str]] = (),
        touching: Iterable[tuple[str, str]] = (),
        carry: bool = True,
        fingers: Mapping[str, float] | None = None,
        state: Mapping[str, Array] | None = None,
        parts: Mapping[str, Array] | None = None,
    ) -> None:
        self.robots = tuple(robots)
        self.clearance = float(clearance)
        self.tolerance = float(sim.contacts.tolerance if tolerance is None else tolerance)
        m = copy.copy(sim.model)
        self.model, self.data = m, mujoco.MjData(m)
        self.data.qpos[:] = sim.data.qpos
        self._adr = dict(sim._qadr)
        self._carried = [c for r in self.robots for c in sim._carried(r)] if carry else []
        self._joints = {
            r: [m.joint(j).id for j in sim.compiled.joint_names[r]] for r in self.robots
        }
        moving = self._moving_bodies()
        colliding = np.asarray(sim.contacts.colliding, dtype=np.intp)
        self._labels = list(sim.contacts.labels)
        names = sorted(set(self._labels))
        self._label_id = np.array([names.index(x) for x in self._labels], dtype=np.int64)
        self._nlabel = len(names)
        pairs = {(r, h.part) for r, h in sim._holds.items()} | set(grips)
        self._set_contact_bits(sim, colliding, moving, pairs)
        m.geom_margin[colliding] = self.clearance / 2.0
        m.geom_gap[:] = 0.0
        m.body_margin[:] = self.clearance / 2.0
        self._moving = moving
        self._touching = np.zeros(self._nlabel * self._nlabel, dtype=bool)  # by label key
        self.start_collision: Violation | None = None
        self._start()
        for a, b in touching:
            self._touching[self._label_key(a, b)] = True
        for r, opening in (fingers or {}).items():
            self.data.qpos[sim._fingers[r]] = opening
        self._free = dict(sim._free_adr)
        for part, P in (parts or {}).items():
            self.put(part, P)
        self.set(state or {})

    def _set_contact_bits(
        self,
        sim: SceneSource,
        colliding: NDArray[np.intp],
        moving: set[int],
        pairs: set[tuple[str, str]],
    ) -> None:
        """Contact bits so MuJoCo computes exactly the pairs to check: one bit per group
        (fixed things, moving links, each gripper and each part of a (robot, part) pair
        never checked); two groups collide unless both are fixed or they form such a pair."""
        m = self.model
        group = {b: (0 if b not in moving else 1) for b in range(m.nbody)}  # 0 fixed, 1 moving
        fixed = [True, False]
        skip: set[tuple[int, int]] = set()
        for robot, part in sorted(pairs):
            gi = len(fixed)
            tree = sim._gripper_tree[robot]
            fixed.append(not (tree & moving))
            for b in tree:
                group[b] = gi
            pb = sim._part_body[part]
            if group[pb] < 2:
                fixed.append(pb not in moving)
                group[pb] = len(fixed) - 1
            skip |= {(gi, group[pb]), (group[pb], gi)}
        n = len(fixed)
        if n > 30:
            raise ValueError("too many grasp pairs for MuJoCo's contact bits")
        collide = [
            [not (fixed[i] and fixed[j]) and (i, j) not in skip for j in range(n)] for i in range(n)
        ]
        affinity = [sum(1 << j for j in range(n) if collide[i][j]) for i in range(n)]
        g_group = np.array([group[int(b)] for b in m.geom_bodyid[colliding]], dtype=np.int64)
        m.geom_contype[colliding] = 1 << g_group
        m.geom_conaffinity[colliding] = np.array([affinity[k] for k in g_group])
        m.body_contype[:] = 0
        m.body_conaffinity[:] = 0
        for g, k in zip(colliding.tolist(), g_group.tolist(), strict=True):
            b = int(m.geom_bodyid[g])
            m.body_contype[b] |= 1 << k
            m.body_conaffinity[b] |= affinity[k]

    def _label_key(self, a: str, b: str) -> int:
        names = sorted(set(self._labels))
        ia, ib = names.index(a), names.index(b)
        return min(ia, ib) * self._nlabel + max(ia, ib)

    # ------------------------------------------------------------------ set-up
    def _moving_bodies(self) -> set[int]:
        m = self.model
        roots = {int(m.jnt_bodyid[js[0]]) for js in self._joints.values()}
        out = set()
        for b in range(1, m.nbody):
            a = b
            while a > 0 and a not in roots:
                a = int(m.body_parentid[a])
            if a in roots:
                out.add(b)
        return out | {int(m.jnt_bodyid[self._free_joint(adr)]) for _, adr, _, _ in self._carried}

    def _free_joint(self, qadr: int) -> int:
        return int(np.flatnonzero(self.model.jnt_qposadr == qadr)[0])

    def _start(self) -> None:
        """Record the pairs touching in the start state and any start collision."""
        self._pose()
        mujoco.mj_collision(self.model, self.data)
        pairs = self._pairs(self.data.ncon)
        worst = None
        for key, dist, g1, g2 in pairs:
            self._touching[key] = True
            if dist < -self.tolerance and (worst is None or dist < worst[2]):
                worst = (self._labels[g1], self._labels[g2], dist)
        self.start_collision = worst

    # ------------------------------------------------------------------ checks
    def _pose(self) -> None:
        m, d = self.model, self.data
        mujoco.mj_kinematics(m, d)
        if self._carried:
            p, q = np.empty(3), np.empty(4)
            for g, adr, rp, rq in self._carried:
                mujoco.mju_mulPose(p, q, d.xpos[g], d.xquat[g], rp, rq)
                d.qpos[adr : adr + 3] = p
                d.qpos[adr + 3 : adr + 7] = q
            mujoco.mj_kinematics(m, d)

    def put(self, part: str, pose: Array) -> None:
        """Put a part that is not carried at ``pose`` (4x4, its body frame)."""
        adr = self._free[part]
        self.data.qpos[adr : adr + 3] = pose[:3, 3]
        self.data.qpos[adr + 3 : adr + 7] = quat_from_matrix(pose[:3, :3])
        self._pose()

    def set(self, configs: Mapping[str, Array]) -> None:
        """Put robots at joint values (rad/m) and carried parts with them."""
        for r, q in configs.items():
            self.data.qpos[self._adr[r]] = q
        self._pose()

    def _pairs(self, n: int) -> list[tuple[int, float, int, int]]:
        if n == 0:
            return []
        con = self.data.contact
        g1, g2, dist = con.geom1[:n], con.geom2[:n], con.dist[:n]
        cols = (self._keys(g1, g2).tolist(), dist.tolist(), g1.tolist(), g2.tolist())
        return list(zip(*cols, strict=True))

    def _keys(self, g1: NDArray[np.intp], g2: NDArray[np.intp]) -> NDArray[np.int64]:
        la, lb = self._label_id[g1], self._label_id[g2]
        return np.minimum(la, lb) * self._nlabel + np.maximum(la, lb)

    def _ok(self) -> bool:
        mujoco.mj_collision(self.model, self.data)
        n = self.data.ncon
        if n == 0:
            return True
        con = self.data.contact
        g1, g2 = con.geom1[:n], con.geom2[:n]
        key = self._keys(g1, g2)
        return bool((self._touching[key] & (con.dist[:n] >= -self.tolerance)).all())

    def valid(self, q: Array, robot: str | None = None) -> bool:
        """Whether ``robot`` (default: the first planned robot) at ``q`` keeps the clearance."""
        self.data.qpos[self._adr[robot or self.robots[0]]] = q
        self._pose()
        return self._ok()

    def valid_configs(self, configs: Mapping[str, Array]) -> bool:
        """Whether the robots at these joint values keep the clearance."""
        self.set(configs)
        return self._ok()

    def violation(self, configs: Mapping[str, Array]) -> Violation | None:
        """The closest offending pair at these joint values (None when valid)."""
        self.set(configs)
        mujoco.mj_collision(self.model, self.data)
        worst = None
        for key, dist, g1, g2 in self._pairs(self.data.ncon):
            if self._touching[key] and dist >= -self.tolerance:
                continue
            if worst is None or dist < worst[2]:
                worst = (self._labels[g1], self._labels[g2], dist)
        return worst

    # ------------------------------------------------------------------ resolution
    def radii(self, robot: str | None = None) -> Array:
        """R_i (m per rad, or 1 for a prismatic joint): a bound of how far any moving point
        beyond joint i moves per unit of joint i, whatever the other joints (module doc).

        A point p moved by joint i (and maybe later joints) is at most
        ``d_i(A_{i+1}) + |A_{i+2} - A_{i+1}| + ... + |p - A_k|`` from joint i's axis:
        ``d_i(A_{i+1})``, the distance of the next joint's anchor from the axis, and each
        anchor-to-anchor distance are fixed by the links; p's distance from the anchor of
        the last joint k that moves it is fixed too (plus its geom's bounding sphere).
        Geometry moved by joint i alone is at a fixed distance from its axis.
        """
        robot = robot or self.robots[0]
        m, d = self.model, self.data
        self._pose()
        joints = self._joints[robot]
        n = len(joints)
        anchors = d.xanchor[joints]
        axes = d.xaxis[joints]
        prismatic = m.jnt_type[joints] == mujoco.mjtJoint.mjJNT_SLIDE
        span = np.where(prismatic, m.jnt_range[joints, 1] - m.jnt_range[joints, 0], 0.0)
        # a prismatic joint moves the anchors after it by up to its span
        links = np.linalg.norm(np.diff(anchors, axis=0), axis=1) + span[1:]

        def off_axis(i: int, p: Array) -> float:
            v = p - anchors[i]
            return float(np.linalg.norm(v - (v @ axes[i]) * axes[i]))

        reach = np.zeros(n)  # farthest geometry carried by joint k from anchor k
        own = np.zeros(n)  # farthest geometry carried by joint k from axis k
        for g, k in self._carrier(joints).items():
            rb = float(m.geom_rbound[g])
            reach[k] = max(reach[k], float(np.linalg.norm(d.geom_xpos[g] - anchors[k])) + rb)
            own[k] = max(own[k], off_axis(k, d.geom_xpos[g]) + rb)
        R = np.zeros(n)
        for i in range(n):
            R[i] = own[i]
            chain = off_axis(i, anchors[i + 1]) if i + 1 < n else 0.0
            for k in range(i + 1, n):
                R[i] = max(R[i], chain + reach[k])
                if k + 1 < n:
                    chain += links[k]
        return np.where(prismatic, 1.0, R)

    def _carrier(self, joints: list[int]) -> dict[int, int]:
        """Moving collision geoms -> the index of the last arm joint that moves them."""
        m = self.model
        jbody = {int(m.jnt_bodyid[j]): k for k, j in enumerate(joints)}
        part_bodies = {int(m.jnt_bodyid[self._free_joint(a)]) for _, a, _, _ in self._carried}
        out = {}
        for g in np.flatnonzero(m.geom_contype != 0):
            b = int(m.geom_bodyid[g])
            if b not in self._moving:
                continue
            if b in part_bodies:
                out[int(g)] = len(joints) - 1
                continue
            a = b
            while a > 0 and a not in jbody:
                a = int(m.body_parentid[a])
            if a in jbody:
                out[int(g)] = jbody[a]
        return out
