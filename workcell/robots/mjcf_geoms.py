"""A robot's solids as MuJoCo geoms of a body, for :mod:`workcell.robots.mjcf`.

:func:`add_solid` places a modeller solid (a block of ``robot.model``): one visual mesh geom
that carries the mass and its convex collision geoms; :func:`add_mesh` places a mesh
entry (of ``robot.geometry`` or of a gripper read from a file) with its own collision
pieces. A placement that is not rigid is baked into the vertices.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.meshgeoms import (
    MeshAssets,
    add_mesh_geoms,
    collision_meshes,
    convex_pieces,
    mass_inertia,
)
from workcell.robots.gripper import GripperPart
from workcell.robots.robot import LinkGeometry, Robot
from workcell.spatial import is_rigid, pos_quat_from_pose

__all__ = ["add_mesh", "add_solid"]

Array = NDArray[np.float64]
_SHELL = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL


def _placed_meshes(
    robot: Robot, block: str, T: Array, reg: MeshAssets, cache: dict[str, tuple[str, list[str]]]
) -> tuple[str, list[str], Array]:
    """(visual mesh, collision meshes, geom pose) of ``block`` placed by T in a body."""
    model = robot.model
    if is_rigid(T):
        if block not in cache:
            pieces, convex = convex_pieces(model, block)
            vis = reg.add(f"{reg.prefix}{block}", model.world_mesh(("block", block)))
            cache[block] = (vis, collision_meshes(reg, f"{reg.prefix}{block}", pieces, convex, vis))
        vis, col = cache[block]
        return vis, col, T
    # a scaled, sheared or mirrored placement is baked into new vertices (geom poses are
    # rigid); trimesh re-winds the faces of a mirrored mesh itself
    m = model.world_mesh(("block", block)).copy().apply_transform(T)
    vis = reg.add(f"{reg.prefix}{block}.placed", m)
    pieces, convex = convex_pieces(model, block)
    placed = [p.copy().apply_transform(T).convex_hull for p in pieces]
    return vis, collision_meshes(reg, f"{reg.prefix}{block}.placed", placed, convex, vis), np.eye(4)


def add_solid(
    body: mujoco.MjsBody,
    robot: Robot,
    block: str,
    T: Array,
    colour: tuple[float, ...] | None,
    density: float,
    reg: MeshAssets,
    cache: dict[str, tuple[str, list[str]]],
) -> None:
    """One visual geom (mass carrier) and the collision geoms of a solid, placed by T."""
    rgba = list(colour) if colour is not None else [0.7, 0.7, 0.72, 1.0]
    vis, col, P = _placed_meshes(robot, block, T, reg, cache)
    pos, quat = pos_quat_from_pose(P)
    gname = reg.unique(f"{reg.prefix}{block}")
    add_mesh_geoms(
        body,
        [(gname, vis)],
        col,
        collision_prefix=gname,
        pos=pos,
        quat=quat,
        density=density,
        rgba=rgba,
    )


def add_mesh(
    body: mujoco.MjsBody,
    name: str,
    g: LinkGeometry | GripperPart,
    density: float,
    reg: MeshAssets,
) -> bool:
    """A mesh entry (of ``robot.geometry`` or of a gripper read from a file): its visual
    mesh and its convex collision pieces (or its hull; none when ``g.collides`` is
    False), placed by ``g.transform`` (baked in when not rigid). The visual mesh carries
    the mass at ``density``: exactly when it is closed, from its hull when it is open (a
    DAE surface; :func:`~workcell.meshgeoms.mass_inertia`), not at all when flat. Returns
    whether it carries mass."""
    rgba = list(g.colour) if g.colour is not None else [0.7, 0.7, 0.72, 1.0]
    pieces = (list(g.collision) or [g.mesh.convex_hull]) if g.collides else []
    T, mesh = g.transform, g.mesh
    if not is_rigid(T):
        mesh, T = g.mesh.copy().apply_transform(T), np.eye(4)
        pieces = [p.copy().apply_transform(g.transform).convex_hull for p in pieces]
    inertia = mass_inertia(mesh)
    vis = reg.add(name, mesh, _SHELL if inertia is None else inertia)
    col = collision_meshes(reg, name, pieces, False, vis) if pieces else []
    pos, quat = pos_quat_from_pose(T)
    gname = reg.unique(name)
    add_mesh_geoms(
        body, [(gname, vis)], col, collision_prefix=gname, pos=pos, quat=quat,
        density=density if inertia is not None else 0.0, rgba=rgba,
    )  # fmt: skip
    return inertia is not None
