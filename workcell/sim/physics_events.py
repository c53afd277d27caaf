"""The events of a physics run (a mixin of the run in :mod:`workcell.sim.physics`).

A physics run makes its own ``grasp``, ``release`` and ``collision`` events and keeps
every other event of the kinematic plan (``move``, ``wait``, ...) at its time. They wait
in a heap ordered by time and are written to the run's timeline between the recorded
frames: an event lands after the last frame at or before its time.

- :meth:`PhysicsEvents._events_at` applies the grasps and releases due at a step: a grasp
  activates the weld of that gripper and part (at the actual or the planned relative
  pose, ``weld_pose``) and switches their contacts off; a release deactivates the weld and
  :meth:`PhysicsEvents._reopen` switches the contacts back on once the fingers have
  opened to their planned opening (within 1e-3).
- :meth:`PhysicsEvents._collisions` makes a collision event for each pair that starts
  touching at a recorded frame (any contact of a robot, or an overlap deeper than
  ``contact_tolerance`` between other things); a pair apart for less than
  :data:`_REARM` seconds is still the same collision.
"""

from __future__ import annotations

import heapq
import math
from typing import TYPE_CHECKING

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.sim.physics_support import quat_angle, relative_pose, set_weld
from workcell.sim.timeline import Event

if TYPE_CHECKING:
    from workcell.sim.physics import _Run

__all__ = ["PhysicsEvents"]

Array = NDArray[np.float64]
_REARM = 0.1  # s: a pair touching again after this long apart is a new collision


class PhysicsEvents:
    """Grasps, releases, collisions and the plan's events of a physics run (module doc)."""

    def _event(
        self: _Run, t: float, robot: str | None, kind: str, detail: str, data: dict | None = None
    ) -> None:
        event = Event(t, robot, kind, detail, data=data)
        heapq.heappush(self.events, (float(t), next(self.order), event))

    def _frames(self: _Run, ts: Array, walls: Array, rows: Array, *, last: bool = False) -> None:
        """Append frames and, in time order, the events up to their times (an event's frame
        is the last frame at or before its time); ``last``: every event left."""
        i, q, eps = 0, self.events, 1e-9
        while q and (last or (len(ts) and q[0][0] <= ts[-1] + eps)):
            t, _, e = heapq.heappop(q)
            k = int(np.searchsorted(ts, t + eps, side="right"))
            if k > i:
                self.out.extend(ts[i:k], walls[i:k], rows[i:k])
                i = k
            self.out.add_event(e.t, e.robot, e.kind, e.detail, data=e.data)
        if i < len(ts):
            self.out.extend(ts[i:], walls[i:], rows[i:])

    def _events_at(self: _Run, n: int) -> None:
        """Apply the grasps and releases due at step ``n`` (before that step)."""
        m, d, cc = self.m, self.d, self.cc
        while self.next < len(self.todo) and self.todo[self.next][0] <= n:
            g = self.todo[self.next][1]
            self.next += 1
            mujoco.mj_kinematics(m, d)
            e, t = self.weld_id[(g.robot, g.part)], n * self.h
            adr = self.free_adr[g.part]
            if g.kind == "grasp":
                if self.weld_pose == "actual":  # where the fingers met the part
                    gb = m.body(cc.gripper_bodies[g.robot]).id
                    pos, quat = relative_pose(d, gb, m.body(cc.part_bodies[g.part]).id)
                else:
                    pos, quat = np.asarray(g.pos, float), np.asarray(g.quat, float)
                set_weld(m, e, pos, quat)
                d.eq_active[e] = True
                self.grip.hold(g.robot, g.part, True)
                self.monitor.excluded |= self.grip.body_pairs(g.robot, g.part)
                self.pending = [p for p in self.pending if (p[0], p[1]) != (g.robot, g.part)]
                dev = float(np.linalg.norm(pos - g.pos)) * 1e3
                ang = math.degrees(quat_angle(quat, g.quat))
                detail = f"grasp '{g.part}': weld pose {dev:.3g} mm, {ang:.3g} deg from the plan's"
            else:
                d.eq_active[e] = False
                opened = self.plan.at(np.array([t]))[0][0]  # the fingers' planned opening
                acts = self.finger_act[g.robot]
                self.pending.append((g.robot, g.part, self.act_adr[acts], opened[acts]))
                centroid = np.empty(3)  # the part frame's centroid offset, turned to the world
                offset = self.sim._centroids[g.part]
                mujoco.mju_rotVecQuat(centroid, offset, d.qpos[adr + 3 : adr + 7])
                where = ", ".join(f"{v:.4g}" for v in d.qpos[adr : adr + 3] + centroid)
                detail = f"release '{g.part}': centroid ({where}) m"
            self._event(t, g.robot, g.kind, detail)

    def _reopen(self: _Run) -> None:
        """Contacts of a released part with its gripper come back once the fingers opened."""
        keep = []
        for robot, part, adr, target in self.pending:
            if np.all(np.abs(self.d.qpos[adr] - target) < 1e-3):
                self.grip.hold(robot, part, False)
                self.monitor.excluded -= self.grip.body_pairs(robot, part)
            else:
                keep.append((robot, part, adr, target))
        self.pending = keep

    def _collisions(self: _Run, t: float) -> list[tuple[str, str]]:
        """Collision events for the pairs that start touching at ``t`` (a pair apart for
        less than :data:`_REARM` seconds is still the same collision); the pairs that
        count as colliding at ``t``."""
        pens = self.monitor.penetrations(self.d)
        if not pens:
            return []
        robot_of, tol, seen = self.monitor.robot_of, self.options["contact_tolerance"], self.seen
        now = []
        for a, b, depth in pens:
            who = robot_of(a) or robot_of(b)
            if not (who or depth > tol):
                continue
            if t - seen.get((a, b), -math.inf) > _REARM:
                self._event(t, who, "collision", f"{a} with {b}: depth {depth * 1e3:.3g} mm")
            seen[(a, b)] = t
            now.append((a, b))
        return now
