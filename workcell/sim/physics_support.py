"""Helpers of the physics mode: the plan, gripper-part contact switching, quaternions.

:class:`Plan` is the kinematic run's joint values as functions of simulated time: linear
between the timeline's frames; where several frames share one time the value jumps there
(before it: the first of them, from it on: the last), and the velocity is the slope of
the segment (zero before the first frame and after the last).

:class:`GripContacts` switches contacts between a gripper and the part it holds off and
on at run time through collision bit masks of a model copy (MuJoCo cannot add or remove
``<exclude>`` pairs after compiling). Bit 0 is everything else (links, static parts,
ground; unchanged); gripper k's collision geoms get ``contype`` bit k+1 and
``conaffinity`` bit 0 | all gripper bits (they touch everything but parts); movable parts
get ``contype`` bit 30 and ``conaffinity`` bit 0 | bit 30 | the bits of the grippers
that do *not* hold them. MuJoCo makes a contact when ``contype1 & conaffinity2`` or
``contype2 & conaffinity1`` is non-zero, so a part touches the world, the arms, other
parts and every gripper except those holding it.

Mounted robots (:meth:`workcell.sim.contacts.ContactMonitor.mount`, ``mounts``): the
static things they stand on get ``contype`` bit 29 and their link 1 bit 28 (instead of
bit 0), and every other colliding geom has both bits in its ``conaffinity``, so link 1
and its mount exert no force on each other while each touches everything else as
before. (With several mounted robots, one's link 1 does not touch another's mount
either.)
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.cell.compile import CompiledCell, subtree_bodies
from workcell.errors import ProgramError

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = [
    "GripContacts",
    "Plan",
    "plan_of",
    "quat_angle",
    "quat_conj",
    "quat_mul",
    "quat_rotate",
    "relative_pose",
    "set_weld",
    "weld_deviation",
]

Array = NDArray[np.float64]
_PART_BIT = 1 << 30
_MOUNT_BIT, _LINK1_BIT = 1 << 29, 1 << 28  # what mounted robots stand on, their link 1
_MAX_GRIPPERS = 27


class Plan:
    """Planned actuator targets: piecewise linear in time through the timeline's frames."""

    def __init__(self, times: Array, targets: Array) -> None:
        self.t, self.P = times, targets

    def at(self, ts: Array) -> tuple[Array, Array]:
        """Targets (n, nu) and their velocities (n, nu) at times ``ts`` (s)."""
        t, P = self.t, self.P
        if len(t) == 1:
            return np.repeat(P[:1], len(ts), axis=0), np.zeros((len(ts), P.shape[1]))
        i = np.searchsorted(t, ts, side="right") - 1  # last frame at or before ts
        inside = (i >= 0) & (i < len(t) - 1)
        i0 = np.clip(i, 0, len(t) - 2)
        span = t[i0 + 1] - t[i0]
        span = np.where(inside, span, 1.0)  # inside: > 0 (i is the last frame at <= ts)
        frac = np.where(inside, (ts - t[i0]) / span, np.where(i < 0, 0.0, 1.0))
        step = P[i0 + 1] - P[i0]
        return P[i0] + frac[:, None] * step, np.where(inside[:, None], step / span[:, None], 0.0)


def _corners(t: Array, P: Array) -> NDArray[np.bool_]:
    """For the interior frames 1..n-2: True where the plan bends (the slopes before and
    after differ by more than 1e-9 relative) or jumps (a zero-length segment)."""
    dt0, dt1 = t[1:-1] - t[:-2], t[2:] - t[1:-1]
    flat = (dt0 > 0) & (dt1 > 0)
    s0 = (P[1:-1] - P[:-2]) / np.where(flat, dt0, 1.0)[:, None]
    s1 = (P[2:] - P[1:-1]) / np.where(flat, dt1, 1.0)[:, None]
    bend = np.abs(s1 - s0) > 1e-9 * (1.0 + np.abs(s0) + np.abs(s1))
    return ~flat | np.any(bend, axis=1)


def plan_of(sim: Simulator, cols: NDArray[np.intp]) -> Plan:
    """The plan of ``sim``'s timeline for the ``qpos`` columns ``cols`` (one per actuator).

    Read block by block; frames on a straight segment between their neighbours are
    dropped (a constant-speed move keeps its two ends), so a long program's plan is small.
    """
    times, rows = [], []
    t_tail, P_tail = np.empty(0), np.empty((0, len(cols)))  # frames not yet decided
    for i, block in sim.timeline.iter_blocks():
        t = np.concatenate([t_tail, block[:, 0]])
        P = np.concatenate([P_tail, block[:, 2 + cols]])
        if i == 0:  # the first frame is always kept
            times.append(t[:1])
            rows.append(P[:1])
        if len(t) >= 3:
            keep = np.flatnonzero(_corners(t, P)) + 1
            times.append(t[keep])
            rows.append(P[keep])
            t_tail, P_tail = t[-2:], P[-2:]  # the last frame, with its left neighbour
        else:
            t_tail, P_tail = t, P
    if len(t_tail) > 1 or not times:  # the last frame is always kept
        times.append(t_tail[-1:])
        rows.append(P_tail[-1:])
    return Plan(np.concatenate(times), np.concatenate(rows))


class GripContacts:
    """Contacts between grippers and movable parts of ``m`` (a model copy; module doc).

    With ``switching`` False every contact stays as compiled and :meth:`hold` does nothing.
    """

    def __init__(
        self,
        m: mujoco.MjModel,
        compiled: CompiledCell,
        *,
        switching: bool = True,
        mounts: tuple[NDArray[np.intp], NDArray[np.intp]] | None = None,
    ):
        self.m, self.enabled = m, switching
        # bits every geom but the mounts and their robots' link 1 has in its conaffinity
        self.extra = _MOUNT_BIT | _LINK1_BIT if mounts is not None and len(mounts[1]) else 0
        robots = list(compiled.gripper_bodies)
        if len(robots) > _MAX_GRIPPERS:
            raise ProgramError(
                f"the physics mode handles up to {_MAX_GRIPPERS} grippers, the cell has "
                f"{len(robots)}"
            )
        collide = (m.geom_contype != 0) | (m.geom_conaffinity != 0)
        self.bit = {r: 1 << (k + 1) for k, r in enumerate(robots)}
        self.all = sum(self.bit.values())
        self.gripper_bodies = {
            r: subtree_bodies(m, m.body(compiled.gripper_bodies[r]).id) for r in robots
        }
        self.part_body = {p: m.body(b).id for p, b in compiled.part_bodies.items()}
        self.part_geoms = {
            p: np.flatnonzero((m.geom_bodyid == b) & collide) for p, b in self.part_body.items()
        }
        self.held: dict[str, int] = {p: 0 for p in self.part_body}  # bits of holding grippers
        if self.extra:
            link1, mount = mounts  # type: ignore[misc]
            others = np.flatnonzero(collide)
            others = others[~np.isin(others, mount)]
            m.geom_conaffinity[others] |= self.extra
            m.geom_conaffinity[link1] &= ~_MOUNT_BIT
            m.geom_contype[mount] = _MOUNT_BIT
            m.geom_contype[link1] = _LINK1_BIT
            self._body_masks(range(m.nbody))
        if not switching:
            return
        for r, bodies in self.gripper_bodies.items():
            g = np.flatnonzero(np.isin(m.geom_bodyid, bodies) & collide)
            m.geom_contype[g] = self.bit[r]
            m.geom_conaffinity[g] = 1 | self.all | self.extra
            self._body_masks(bodies)
        for p in self.part_body:
            self._set_part(p)

    def _set_part(self, part: str) -> None:
        g = self.part_geoms[part]
        self.m.geom_contype[g] = _PART_BIT
        self.m.geom_conaffinity[g] = 1 | _PART_BIT | self.extra | (self.all & ~self.held[part])
        self._body_masks([self.part_body[part]])

    def _body_masks(self, bodies: Iterable[int]) -> None:
        """A body's masks are the OR of its geoms' (MuJoCo's broad phase reads them)."""
        m = self.m
        for b in bodies:
            g = m.geom_bodyid == b
            m.body_contype[b] = int(np.bitwise_or.reduce(m.geom_contype[g], initial=0))
            m.body_conaffinity[b] = int(np.bitwise_or.reduce(m.geom_conaffinity[g], initial=0))

    def hold(self, robot: str, part: str, held: bool) -> None:
        """Switch contacts between ``robot``'s gripper and ``part`` off (held) or on."""
        if not self.enabled:
            return
        bit = self.bit[robot]
        self.held[part] = (self.held[part] | bit) if held else (self.held[part] & ~bit)
        self._set_part(part)

    def body_pairs(self, robot: str, part: str) -> set[tuple[int, int]]:
        """(low, high) body id pairs of ``robot``'s gripper bodies and ``part``."""
        p = self.part_body[part]
        return {(min(b, p), max(b, p)) for b in self.gripper_bodies[robot]}


# ---------------------------------------------------------------------- welds
def relative_pose(d: mujoco.MjData, body1: int, body2: int) -> tuple[Array, Array]:
    """Pose of ``body2`` in ``body1``'s frame from ``d``'s kinematics: position (m), wxyz."""
    ip, iq, pos, quat = np.zeros(3), np.zeros(4), np.zeros(3), np.zeros(4)
    mujoco.mju_negPose(ip, iq, d.xpos[body1], d.xquat[body1])
    mujoco.mju_mulPose(pos, quat, ip, iq, d.xpos[body2], d.xquat[body2])
    return pos, quat


def set_weld(m: mujoco.MjModel, e: int, pos: Array, quat: Array) -> None:
    """Give weld equality ``e`` the relative pose (body2 in body1: m, wxyz), anchor 0,
    torquescale 1 and a zero flag (so nothing recomputes the pose from qpos0)."""
    m.eq_data[e, 0:3] = 0.0
    m.eq_data[e, 3:6] = pos
    m.eq_data[e, 6:10] = quat
    m.eq_data[e, 10] = 1.0
    m.eq_data[e, 11] = 0.0


def weld_deviation(
    grip_pos: Array, grip_quat: Array, weld: Array, part: Array
) -> tuple[float, float]:
    """Largest position (m) and rotation (rad) deviation of a welded part from where the
    weld puts it: gripper poses (N, 3) and (N, 4), the weld's relative pose ``weld``
    (7: position, wxyz) and the part's free-joint poses ``part`` (N, 7)."""
    want_p = grip_pos + quat_rotate(grip_quat, np.broadcast_to(weld[:3], grip_pos.shape))
    want_q = quat_mul(grip_quat, np.broadcast_to(weld[3:7], grip_quat.shape))
    dp = np.linalg.norm(part[:, :3] - want_p, axis=1)
    return float(dp.max()), float(np.max(quat_angle(part[:, 3:7], want_q)))


# ---------------------------------------------------------------------- quaternions (wxyz)
def quat_conj(q: Array) -> Array:
    """Conjugate of quaternions (..., 4), wxyz."""
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def quat_mul(a: Array, b: Array) -> Array:
    """Hamilton products a b of quaternions (..., 4), wxyz."""
    aw, ax, ay, az = np.moveaxis(np.asarray(a, dtype=np.float64), -1, 0)
    bw, bx, by, bz = np.moveaxis(np.asarray(b, dtype=np.float64), -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def quat_rotate(q: Array, v: Array) -> Array:
    """Vectors (..., 3) rotated by unit quaternions (..., 4), wxyz."""
    q = np.asarray(q, dtype=np.float64)
    w, u = q[..., :1], q[..., 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def quat_angle(a: Array, b: Array) -> float | Array:
    """Rotation angle (rad, in [0, pi]) between unit quaternions a and b (..., 4)."""
    dot = np.abs(np.sum(np.asarray(a) * np.asarray(b), axis=-1))
    ang = 2.0 * np.arccos(np.clip(dot, 0.0, 1.0))
    return float(ang) if np.ndim(ang) == 0 else ang
