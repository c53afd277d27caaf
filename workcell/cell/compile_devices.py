"""Compiling the cell's devices (:mod:`workcell.cell.devices`) into the MjSpec.

- conveyor ``C``: geoms of the world body: the belt slab (``C.visual0`` and ``C.col0``,
  its top face the belt, its x axis along the belt, so MuJoCo's ``surfacevel`` of
  ``C.col0`` is the belt's motion in physics mode), the frame under it down to the floor
  (``C.visual1``, ``C.col1``; none for a belt lower than the slab) and the end stop plate
  (``C.visual2``, ``C.col2``) just past the belt's end; the collision geoms are boxes
  (group 3), the visual ones non-colliding (group 2). In the compiled model the belt's
  ``surfacevel`` is its speed when it runs from the start (no run signal, or one whose
  initial value is true), else 0; the physics mode sets it while it runs.
- source copies: the compiled model is fixed once compiled, so every copy a source can
  make (``<part>_1`` ... ``<part>_<pool>``) is a body with a free joint from the start,
  sharing its pattern's meshes, *parked*: at :func:`parking_position` (k-th copy of the
  cell), far above the cell (:data:`PARK_HEIGHT`, beyond any coordinate a user may give,
  ``max_coordinate``), one beside the other so they never touch. The simulator parks the
  sources' patterns there too, and sinks park the parts they remove; a body whose
  position is higher than :data:`PARKED_ABOVE` is out of the world (pictures, recordings
  and sensors leave it out: :func:`is_parked`). The model's statistic (its centre and
  extent, which cameras and MuJoCo's viewer use) is the one of the cell without the
  parked copies, written into the spec so an exported file keeps it.

Lengths m, speeds m/s.
"""

from __future__ import annotations

from collections.abc import Mapping

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.cell.devices import BELT_THICKNESS, STOP_HEIGHT, STOP_THICKNESS, Conveyor
from workcell.meshgeoms import (
    COLLISION_GROUP,
    CONTACT_SOLIMP,
    CONTACT_SOLREF,
    VISUAL_GROUP,
)

__all__ = [
    "BELT_RGBA",
    "FRAME_RGBA",
    "PARKED_ABOVE",
    "PARK_HEIGHT",
    "PARK_SPACING",
    "add_conveyor_geoms",
    "belt_geom",
    "is_parked",
    "park_copies",
    "parking_position",
]

PARK_HEIGHT = 1e7  # m: where parked copies wait (max_coordinate is at most 1e6 by default)
PARKED_ABOVE = 5e6  # m: a body higher than this is parked, out of the world
PARK_SPACING = 1000.0  # m between parked bodies (each far smaller)
BELT_RGBA = (0.16, 0.17, 0.19, 1.0)  # the belt: near black rubber
FRAME_RGBA = (0.62, 0.64, 0.67, 1.0)  # frame and end stop: brushed steel
Array = NDArray[np.float64]


def parking_position(k: int) -> Array:
    """World position (m) of parking place ``k`` (0, 1, ...): far above the cell, 1 km apart."""
    return np.array([PARK_SPACING * k, 0.0, PARK_HEIGHT])


def is_parked(z: ArrayLike) -> NDArray[np.bool_]:
    """Whether bodies at heights ``z`` (m, world) are parked (out of the world)."""
    return np.asarray(z, dtype=np.float64) > PARKED_ABOVE


def belt_geom(name: str) -> str:
    """The name of conveyor ``name``'s belt slab collision geom (its ``surfacevel``)."""
    return f"{name}.col0"


def _boxes(c: Conveyor) -> list[tuple[Array, Array, tuple[float, ...]]]:
    """(centre, half sizes, rgba) of the slab, the frame and the end stop, in the belt
    frame's axes (x along the belt, z up)."""
    u = c.direction
    mid = (c.start + c.end) / 2
    top, L, w = c.top, c.length, c.width
    out = [
        (
            mid - np.array([0, 0, BELT_THICKNESS / 2]),
            np.array([L / 2, w / 2, BELT_THICKNESS / 2]),
            BELT_RGBA,
        )
    ]
    low = top - BELT_THICKNESS
    if low > 0.005:  # a frame down to the floor
        out.append(
            (np.array([mid[0], mid[1], low / 2]), np.array([L / 2, 0.4 * w, low / 2]), FRAME_RGBA)
        )
    stop = c.end + u * (STOP_THICKNESS / 2) + np.array([0, 0, (STOP_HEIGHT - BELT_THICKNESS) / 2])
    half = np.array([STOP_THICKNESS / 2, w / 2, (STOP_HEIGHT + BELT_THICKNESS) / 2])
    out.append((stop, half, FRAME_RGBA))
    return out


def add_conveyor_geoms(worldbody: mujoco.MjsBody, c: Conveyor, running: bool) -> None:
    """The belt, frame and end stop of conveyor ``c`` (module doc); ``running``: the belt
    moves from the start (its slab's ``surfacevel`` is the speed)."""
    u = c.direction
    yaw = float(np.arctan2(u[1], u[0]))
    quat = [np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]
    for i, (centre, half, rgba) in enumerate(_boxes(c)):
        common = dict(
            type=mujoco.mjtGeom.mjGEOM_BOX, pos=centre.tolist(), quat=quat, size=half.tolist()
        )
        worldbody.add_geom(
            name=f"{c.name}.visual{i}", contype=0, conaffinity=0, group=VISUAL_GROUP,
            rgba=list(rgba), **common,
        )  # fmt: skip
        extra = {}
        if i == 0 and running:
            extra["surfacevel"] = [c.speed, 0.0, 0.0, 0.0, 0.0, 0.0]
        worldbody.add_geom(
            name=f"{c.name}.col{i}", contype=1, conaffinity=1, group=COLLISION_GROUP,
            rgba=[*rgba[:3], 0.5], solref=list(CONTACT_SOLREF), solimp=list(CONTACT_SOLIMP),
            **common, **extra,
        )  # fmt: skip


def park_copies(
    spec: mujoco.MjSpec,
    model: mujoco.MjModel,
    copies: list[str],
    free_joints: Mapping[str, str],
    parking: Mapping[str, Array],
) -> None:
    """Move the ``copies`` bodies (compiled where their patterns are) to their ``parking``
    places in the spec and in the compiled ``model`` (body pose and ``qpos0``), keeping
    the model's statistic as compiled (module doc)."""
    if not copies:
        return
    spec.stat.center = model.stat.center.copy()
    spec.stat.extent = float(model.stat.extent)
    for name in copies:
        p = parking[name]
        spec.body(name).pos = p.tolist()
        spec.body(name).quat = [1.0, 0.0, 0.0, 0.0]
        b = model.body(name).id
        model.body_pos[b] = p
        model.body_quat[b] = [1.0, 0.0, 0.0, 0.0]
        adr = int(model.jnt_qposadr[model.joint(free_joints[name]).id])
        model.qpos0[adr : adr + 3] = p
        model.qpos0[adr + 3 : adr + 7] = [1.0, 0.0, 0.0, 0.0]
        model.qpos_spring[adr : adr + 7] = model.qpos0[adr : adr + 7]
