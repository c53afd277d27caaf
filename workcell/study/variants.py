"""Cell variants without recompiling: move robots and parts in a copy of the compiled model.

Compiling a cell (meshes, convex pieces, MjSpec) costs about as much as running a short
program on it, so a study compiles each robot choice once per worker (a
:class:`Template`) and makes every candidate of that choice by editing a copy of the
compiled ``MjModel``:

- a robot's base: the world pose of its link-0 body (``body_pos``/``body_quat``), which is
  ``base @ robot.base`` (see :mod:`workcell.cell.compile`);
- a static part: its geoms on the world body (``geom_pos``/``geom_quat``), each moved by
  ``new pose @ inverse(old pose)`` (MuJoCo re-centres mesh geoms on compiling, so the
  geoms' own poses are kept and composed, not overwritten);
- a movable part: its body pose and its free joint's ``qpos0`` (the initial state).

MuJoCo's midphase keeps a tree of bounding boxes per body, made when compiling, in the
body's inertial frame; the world body's holds the static parts' geoms where they were.
A variant that moves a static part refits that tree: each node's box is made again as
MuJoCo makes it (the union of its geoms' boxes, each geom's local box turned and moved by
the geom's pose), on the same tree. Stale boxes would let the midphase skip pairs that
touch; turning the midphase off instead is no cure either: the narrow phase then meets
pairs the midphase keeps from it, such as a part resting on its support, and with the
simulator's negative contact margins it reports those as overlaps of one tolerance.

The same edits give the model a fresh compile of the moved cell gives (the tests compare
body and geom poses, contacts and whole runs). The cell object the simulator reads (for
IK, grasp data and targets) is rebuilt through the public ``Workcell.add_*`` calls with
the new poses, reusing the template's robots (no rebuild). A robot *choice* changes the
robot itself: :func:`rebuild` adds it with ``Workcell.add_robot(name, robot_name)``, so
every name ``add_robot`` knows can be chosen, and the result is compiled again.

Meshes reach MuJoCo from memory (``spec.assets``), never from files, so MuJoCo's cache of
mesh files by path cannot hand one variant another's meshes.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Mapping

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.cell.compile import CompiledCell, compile_cell
from workcell.cell.workcell import Workcell
from workcell.robots.mjcf import body_name
from workcell.spatial import invert, pose_from_pos_quat, quat_from_matrix, rot_z

__all__ = ["Template", "moved", "rebuild"]

Array = NDArray[np.float64]


def moved(
    T: Array,
    x: float | None = None,
    y: float | None = None,
    z: float | None = None,
    yaw: float | None = None,
) -> Array:
    """``T`` (4x4) with its position's x, y, z (m) replaced where given, and turned about
    the world's vertical so its yaw (rad, the heading of its x axis) is ``yaw``."""
    out = np.array(T, dtype=np.float64)
    for i, v in enumerate((x, y, z)):
        if v is not None:
            out[i, 3] = float(v)
    if yaw is not None:
        yaw0 = math.atan2(out[1, 0], out[0, 0])
        out[:3, :3] = rot_z(float(yaw) - yaw0)[:3, :3] @ out[:3, :3]
    return out


def rebuild(
    cell: Workcell,
    *,
    robots: Mapping[str, str] | None = None,
    bases: Mapping[str, Array] | None = None,
    poses: Mapping[str, Array] | None = None,
) -> Workcell:
    """A copy of ``cell`` (sharing its model) with robots replaced by the named ones
    (``robots``: robot -> a name ``add_robot`` takes; the gripper is kept, the initial q
    is the new robot's default), robots' ``bases`` and parts' ``poses`` (4x4) changed."""
    robots, bases, poses = robots or {}, bases or {}, poses or {}
    out = Workcell(cell.name, model=cell.model)
    for p in cell.static_parts.values():
        out.add_static(p.name, p.entity, poses.get(p.name, p.pose), colour=p.colour)
    for p in cell.movable_parts.values():
        out.add_movable(
            p.name, p.entity, poses.get(p.name, p.pose), density=p.density, colour=p.colour
        )
    for r in cell.robots.values():
        base = bases.get(r.name, r.base)
        choice = robots.get(r.name)
        if choice is None or choice == r.builtin:  # the same robot, saved as it was
            out.add_robot(r.name, r, base=base)
            continue
        gripper: Mapping[str, object] | bool | None = None
        if r.gripper_parameters is not None:
            gripper = dict(r.gripper_parameters)
        elif r.robot.gripper is not None:
            gripper = True
        out.add_robot(r.name, choice, gripper=gripper, base=base)
    for c in cell.cameras.values():
        out.add_camera(c.name, c.position, c.target, c.fovy)
    return out


def _set_pose(pos: Array, quat: Array, T: Array) -> None:
    """Write T (4x4) into a MuJoCo position and unit quaternion (wxyz) in place."""
    q = quat_from_matrix(T[:3, :3])
    pos[:] = T[:3, 3]
    quat[:] = q / math.sqrt(float(q @ q))


class Template:
    """``cell`` compiled once (``compiled``), and :meth:`place` for its moved variants."""

    def __init__(self, cell: Workcell) -> None:
        self.cell = cell
        self.compiled = cc = compile_cell(cell)
        m = cc.model
        self._link0 = {r: m.body(body_name(p, 0)).id for r, p in cc.robot_prefixes.items()}
        world = [g for g in range(m.ngeom) if m.geom_bodyid[g] == 0]
        self._static_geoms = {
            p: np.array([g for g in world if m.geom(g).name.startswith(f"{p}.")], dtype=np.intp)
            for p in cell.static_parts
        }
        self._free = {
            p: (m.body(b).id, int(m.jnt_qposadr[m.joint(cc.free_joints[p]).id]))
            for p, b in cc.part_bodies.items()
        }

    def place(
        self, bases: Mapping[str, Array] | None = None, poses: Mapping[str, Array] | None = None
    ) -> tuple[Workcell, CompiledCell]:
        """The cell with robots' ``bases`` and parts' ``poses`` (4x4, world) changed, and
        its compiled form (a copy of the template's model, edited; module doc)."""
        bases, poses = bases or {}, poses or {}
        cell = rebuild(self.cell, bases=bases, poses=poses)
        m = copy.copy(self.compiled.model)
        for r in bases:
            b = self._link0[r]
            _set_pose(m.body_pos[b], m.body_quat[b], cell.robots[r].world_base)
        for p, T in poses.items():
            if p in self._free:
                b, adr = self._free[p]
                _set_pose(m.body_pos[b], m.body_quat[b], T)
                m.qpos0[adr : adr + 3] = m.body_pos[b]
                m.qpos0[adr + 3 : adr + 7] = m.body_quat[b]
                m.qpos_spring[adr : adr + 7] = m.qpos0[adr : adr + 7]
                if m.nkey:
                    m.key_qpos[:, adr : adr + 7] = m.qpos0[adr : adr + 7]
                continue
            D = T @ invert(self.cell.static_parts[p].pose)
            for g in self._static_geoms[p]:
                G = D @ pose_from_pos_quat(m.geom_pos[g], m.geom_quat[g])
                _set_pose(m.geom_pos[g], m.geom_quat[g], G)
        if any(p in self._static_geoms for p in poses):
            _refit_world_tree(m)
        return cell, dataclasses.replace(self.compiled, model=m)


_EPS = 1e-14  # MuJoCo's mjEPS: flat boxes are inflated by it


def _refit_world_tree(m: mujoco.MjModel) -> None:
    """Remake the world body's bounding boxes (bvh_aabb) from its geoms' current poses."""
    adr = int(m.body_bvhadr[0])
    if adr < 0:
        return
    R_body = np.empty(9)
    mujoco.mju_quat2Mat(R_body, m.body_iquat[0])
    R_body = R_body.reshape(3, 3)
    signs = np.array(
        [[(v & 1) * 2 - 1, (v >> 1 & 1) * 2 - 1, (v >> 2 & 1) * 2 - 1] for v in range(8)]
    )

    def leaf(g: int) -> tuple[Array, Array]:
        R = np.empty(9)
        mujoco.mju_quat2Mat(R, m.geom_quat[g])
        corners = m.geom_aabb[g, :3] + signs * m.geom_aabb[g, 3:]
        world = corners @ R.reshape(3, 3).T + m.geom_pos[g]
        local = (world - m.body_ipos[0]) @ R_body
        return local.min(axis=0), local.max(axis=0)

    def refit(node: int) -> tuple[Array, Array]:
        kids = [int(k) for k in m.bvh_child[adr + node] if k >= 0]
        if kids:
            boxes = [refit(k) for k in kids]
            lo = np.min([b[0] for b in boxes], axis=0)
            hi = np.max([b[1] for b in boxes], axis=0)
        else:
            lo, hi = leaf(int(m.bvh_nodeid[adr + node]))
        flat = np.abs(hi - lo) < _EPS
        lo, hi = np.where(flat, lo - _EPS, lo), np.where(flat, hi + _EPS, hi)
        m.bvh_aabb[adr + node, :3] = (hi + lo) / 2
        m.bvh_aabb[adr + node, 3:] = (hi - lo) / 2
        return lo, hi

    refit(0)
