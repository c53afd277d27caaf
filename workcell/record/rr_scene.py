"""The static part of a rerun recording: entity paths, time columns, layout, meshes.

Used by :mod:`workcell.record.rerun_log` (see its module doc for the entity layout):
the entity-path helpers; ``index_columns`` (frame, simulated and wall time as integer
nanoseconds); :class:`Layout` (moving bodies, bodies welded to the world, joint series,
tool sites, grippers, from the compiled model); :func:`log_static` logs every visual geom
once in its body's frame (meshes with flat face normals, primitives, the ground as a
quad; collision-only geoms, group 3, skipped), the cameras as pinhole frusta and the
series styles.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np
import rerun as rr
from numpy.typing import ArrayLike, NDArray

from workcell.meshgeoms import COLLISION_GROUP
from workcell.spatial import wxyz_to_xyzw

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = [
    "BODIES",
    "EVENTS",
    "GRIPPERS",
    "JOINTS",
    "TOOL_PATHS",
    "WORLD",
    "Layout",
    "body_entity",
    "entity_part",
    "gripper_entity",
    "index_columns",
    "joint_entity",
    "log_static",
    "tool_path_entity",
]

Array = NDArray[np.float64]

WORLD = "/world"

BODIES = "/world/bodies"

TOOL_PATHS = "/world/tool_paths"

JOINTS = "/joints"

GRIPPERS = "/gripper"

EVENTS = "/events"

_PALETTE = [(230, 80, 40), (40, 120, 230), (40, 170, 80), (200, 60, 200), (220, 180, 30)]

_GEOM = mujoco.mjtGeom


def entity_part(name: str) -> str:
    """One escaped entity-path part of a name (rerun escapes /, spaces, ...)."""
    return rr.escape_entity_path_part(name)


def body_entity(body: str) -> str:
    """Entity path of a MuJoCo body (its world pose)."""
    return f"{BODIES}/{entity_part(body)}"


def joint_entity(robot: str) -> str:
    """Entity path of a robot's joint value series (one series per joint)."""
    return f"{JOINTS}/{entity_part(robot)}"


def gripper_entity(robot: str) -> str:
    """Entity path of a robot's gripper state series (1 closed on a part, 0 open)."""
    return f"{GRIPPERS}/{entity_part(robot)}"


def tool_path_entity(robot: str) -> str:
    """Entity path of a robot's tool path segments."""
    return f"{TOOL_PATHS}/{entity_part(robot)}"


def _ns(seconds: Array) -> NDArray[np.timedelta64]:
    """Seconds -> integer nanoseconds as ``timedelta64[ns]`` (rounded, never truncated)."""
    return np.rint(np.asarray(seconds) * 1e9).astype(np.int64).astype("timedelta64[ns]")


def index_columns(frames: ArrayLike, sim_t: ArrayLike, wall_t: ArrayLike) -> list[rr.TimeColumn]:
    """The three timelines of rows: frame indices, simulated and wall clocks (s)."""
    return [
        rr.TimeColumn("frame", sequence=np.asarray(frames, dtype=np.int64)),
        rr.TimeColumn("sim_time", duration=_ns(sim_t)),
        rr.TimeColumn("wall_time", duration=_ns(wall_t)),
    ]


def _rgba(model: mujoco.MjModel, g: int) -> NDArray[np.uint8]:
    rgba = model.geom_rgba[g]
    mat = model.geom_matid[g]
    if mat >= 0 and np.allclose(rgba, (0.5, 0.5, 0.5, 1.0)):  # MuJoCo: material unless set
        rgba = model.mat_rgba[mat]
    return np.round(np.clip(rgba, 0, 1) * 255).astype(np.uint8)


@dataclass
class Layout:
    """Names and indices of what is logged, from the compiled model."""

    moving: list[tuple[int, str]]  # (body id, entity) with a pose per frame
    static: list[tuple[int, str]]  # bodies welded to the world (not the world body)
    joints: list[tuple[str, NDArray[np.intp], NDArray[np.bool_], list[str]]]
    # (entity, qpos addresses, revolute, series names) per robot
    tools: list[tuple[str, int, str]]  # (robot, site id, entity)
    grippers: list[str]  # robots with a gripper

    @classmethod
    def of(cls, sim: Simulator) -> Layout:
        m, c = sim.model, sim.compiled
        names = [m.body(b).name or f"body{b}" for b in range(m.nbody)]
        moving = [(b, body_entity(names[b])) for b in range(1, m.nbody) if m.body_weldid[b]]
        static = [(b, body_entity(names[b])) for b in range(1, m.nbody) if not m.body_weldid[b]]
        joints = []
        for robot in sim.robots:
            prefix = c.robot_prefixes.get(robot, "")
            ids = [m.joint(j).id for j in c.joint_names[robot]]
            revolute = np.array([m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE for j in ids])
            labels = [
                f"{n.removeprefix(prefix)} ({'deg' if r else 'm'})"
                for n, r in zip(c.joint_names[robot], revolute, strict=True)
            ]
            adr = np.array([m.jnt_qposadr[j] for j in ids], dtype=np.intp)
            joints.append((joint_entity(robot), adr, revolute, labels))
        tools = [(r, m.site(c.tool_sites[r]).id, tool_path_entity(r)) for r in sim.robots]
        return cls(moving, static, joints, tools, [r for r in sim.robots if r in c.gripper_bodies])


def _geom_archetype(model: mujoco.MjModel, g: int) -> rr.AsComponents | None:
    """The geom's geometry in its own frame, or None for what is not drawn."""
    kind, size, rgba = model.geom_type[g], model.geom_size[g], _rgba(model, g)
    if kind == _GEOM.mjGEOM_MESH:
        mid = model.geom_dataid[g]
        v0, nv = model.mesh_vertadr[mid], model.mesh_vertnum[mid]
        f0, nf = model.mesh_faceadr[mid], model.mesh_facenum[mid]
        corners = model.mesh_vert[v0 : v0 + nv][model.mesh_face[f0 : f0 + nf]]  # (nf, 3, 3)
        # one vertex per face corner with its face's normal: flat shading, sharp edges
        # (the compiled model's mesh_normal is not usable for this: checked on 3.17)
        normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
        pos, normals = corners.reshape(-1, 3), np.repeat(normal, 3, axis=0)
        return rr.Mesh3D(
            vertex_positions=pos.astype(np.float32),
            triangle_indices=np.arange(len(pos), dtype=np.uint32).reshape(-1, 3),
            vertex_normals=normals.astype(np.float32),
            albedo_factor=rgba,
        )
    if kind == _GEOM.mjGEOM_PLANE:  # infinite planes (size 0) drawn over the model's extent
        hx, hy = (s if s > 0 else 2.0 * model.stat.extent for s in size[:2])
        quad = np.array([[-hx, -hy, 0], [hx, -hy, 0], [hx, hy, 0], [-hx, hy, 0]], np.float32)
        return rr.Mesh3D(
            vertex_positions=quad,
            triangle_indices=np.array([[0, 1, 2], [0, 2, 3]], np.uint32),
            vertex_normals=np.tile(np.float32([0, 0, 1]), (4, 1)),
            albedo_factor=rgba,
        )
    r, h, fill = size[0], size[1], rr.components.FillMode.Solid
    if kind == _GEOM.mjGEOM_BOX:
        return rr.Boxes3D(half_sizes=[size], colors=[rgba], fill_mode=fill)
    if kind in (_GEOM.mjGEOM_SPHERE, _GEOM.mjGEOM_ELLIPSOID):
        half = size if kind == _GEOM.mjGEOM_ELLIPSOID else [r, r, r]
        return rr.Ellipsoids3D(half_sizes=[half], colors=[rgba], fill_mode=fill)
    if kind == _GEOM.mjGEOM_CAPSULE:  # rerun's capsule starts at the origin along +z
        return rr.Capsules3D(lengths=[2 * h], radii=[r], translations=[[0, 0, -h]], colors=[rgba])
    if kind == _GEOM.mjGEOM_CYLINDER:
        return rr.Cylinders3D(lengths=[2 * h], radii=[r], colors=[rgba], fill_mode=fill)
    return None  # height fields, SDFs: not drawn


def log_static(rec: rr.RecordingStream, sim: Simulator, layout: Layout, d: mujoco.MjData) -> None:
    """Coordinates, static body poses, geometry, cameras and series styles (once)."""
    m = sim.model
    rec.log(WORLD, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    names = [m.body(b).name or f"body{b}" for b in range(m.nbody)]
    for b, ent in layout.static:  # poses of bodies welded to the world never change
        q = wxyz_to_xyzw(d.xquat[b])
        rec.log(ent, rr.Transform3D(translation=d.xpos[b], quaternion=q), static=True)
    for g in range(m.ngeom):
        if m.geom_group[g] == COLLISION_GROUP or m.geom_rgba[g][3] == 0:
            continue
        arch = _geom_archetype(m, g)
        if arch is None:
            continue
        ent = f"{body_entity(names[m.geom_bodyid[g]])}/{entity_part(m.geom(g).name or f'geom{g}')}"
        pose = rr.Transform3D(translation=m.geom_pos[g], quaternion=wxyz_to_xyzw(m.geom_quat[g]))
        rec.log(ent, pose, arch, static=True)
    for c in range(m.ncam):
        ent = (
            f"{body_entity(names[m.cam_bodyid[c]])}/{entity_part(m.camera(c).name or f'camera{c}')}"
        )
        pose = rr.Transform3D(translation=m.cam_pos[c], quaternion=wxyz_to_xyzw(m.cam_quat[c]))
        pinhole = rr.Pinhole(
            fov_y=float(np.radians(m.cam_fovy[c])),
            aspect_ratio=4 / 3,
            camera_xyz=rr.ViewCoordinates.RUB,  # MuJoCo/OpenGL: x right, y up, looks along -z
            image_plane_distance=0.1,
        )
        rec.log(ent, pose, pinhole, static=True)
    for i, (_, _, ent) in enumerate(layout.tools):
        colour = _PALETTE[i % len(_PALETTE)]
        rec.log(ent, rr.LineStrips3D.from_fields(colors=[colour], radii=[0.002]), static=True)
    for ent, _, _, labels in layout.joints:
        rec.log(ent, rr.SeriesLines(names=labels), static=True)
    for robot in layout.grippers:
        # no averaging of the points that share a pixel: a 0/1 step stays a step when zoomed out
        step = rr.SeriesLines(names=f"{robot} closed", aggregation_policy="minmax")
        rec.log(gripper_entity(robot), step, static=True)
