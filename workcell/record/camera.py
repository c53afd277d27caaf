"""The overview camera: a free camera that frames the whole cell and sees every part.

:func:`overview_camera` looks down ``elevation`` degrees and fits its distance and look-at
point so the visual geometry of every given configuration fills the picture without being
clipped. Its azimuth is chosen among twelve, 30 degrees apart, starting from a
three-quarter view across the cell's longer side: the first from which no part is hidden
behind a robot in the first configuration, else the one that hides least of them
(:func:`occlusion`). Each visual geom of a part is tested at its centre and at the
corners of its bounding box drawn 20 % in towards the centre: a point is hidden when the
ray from the camera's eye to it first meets a robot's geom (``mj_ray``); a geom counts when a third of its points or
more are hidden. A movable part
counts ten times as much as a static one, and large static parts (tables, floors: a
bounding radius over a quarter of the cell's extent) not at all: they are always partly
behind something. Angles in degrees, sizes in pixels.

:func:`named_view` turns a name into a view: a camera of the cell by its name, else one
of the preset :data:`VIEWS`, each a free camera fitted like the overview (every given
configuration in the picture) from a fixed direction: ``overview`` (the automatic
azimuth), ``front`` (from -y), ``back`` (from +y), ``left`` (from -x), ``right`` (from +x),
all looking down 20 degrees, and ``top`` (straight down, +y up in the picture). A cell
camera of the same name wins.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.cell.compile_devices import is_parked
from workcell.errors import ModelError
from workcell.meshgeoms import COLLISION_GROUP

__all__ = [
    "AZIMUTH_STEP",
    "VIEWS",
    "camera_eye",
    "named_view",
    "occlusion",
    "overview_camera",
    "visual_points",
]

AZIMUTH_STEP = 30.0  # deg between the azimuths tried
_MOVABLE_WEIGHT = 10.0  # a hidden movable part costs as much as ten static ones
_LARGE = 0.25  # a static geom whose bounding radius is over this x the cell's extent
Array = NDArray[np.float64]
_SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
_SIDE = -20.0  # deg: the preset side views look down this much
# preset views: name -> overview_camera's azimuth and elevation (deg; none: its own)
VIEWS: dict[str, dict[str, float]] = {
    "overview": {},
    "front": {"azimuth": 90.0, "elevation": _SIDE},
    "back": {"azimuth": 270.0, "elevation": _SIDE},
    "left": {"azimuth": 0.0, "elevation": _SIDE},
    "right": {"azimuth": 180.0, "elevation": _SIDE},
    "top": {"azimuth": 90.0, "elevation": -89.9},
}


def _visible_geoms(model: mujoco.MjModel) -> NDArray[np.intp]:
    keep = (
        (model.geom_group < COLLISION_GROUP)
        & (model.geom_type != mujoco.mjtGeom.mjGEOM_PLANE)
        & (model.geom_rgba[:, 3] > 0)
    )
    return np.flatnonzero(keep)


def visual_points(model: mujoco.MjModel, data: mujoco.MjData) -> Array:
    """World corners (8 per geom) of the bounding boxes of the visible non-plane geoms
    (not of parts parked out of the world, :mod:`workcell.cell.compile_devices`)."""
    idx = _visible_geoms(model)
    idx = idx[~is_parked(data.geom_xpos[idx, 2])]
    if len(idx) == 0:
        return np.empty((0, 3))
    return _box_points(model, data, idx, 1.0)[:, 1:].reshape(-1, 3)


def _box_points(
    model: mujoco.MjModel, data: mujoco.MjData, idx: NDArray[np.intp], shrink: float
) -> Array:
    """(k, 9, 3): each geom's box centre, then its 8 corners drawn in by ``shrink``."""
    aabb = model.geom_aabb[idx]  # centre (3), half sizes (3) in the geom frame
    local = aabb[:, None, :3] + shrink * _SIGNS[None] * aabb[:, None, 3:]
    local = np.concatenate([aabb[:, None, :3], local], axis=1)
    R = data.geom_xmat[idx].reshape(-1, 3, 3)
    return np.einsum("kij,kpj->kpi", R, local) + data.geom_xpos[idx][:, None, :]


def _robot_bodies(model: mujoco.MjModel) -> NDArray[np.bool_]:
    """Bodies of robots: not the world, in a tree whose root has no free joint (a movable
    part's body has one; static parts are geoms of the world body)."""
    free = np.zeros(model.nbody, dtype=bool)
    for j in range(model.njnt):
        if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            free[model.jnt_bodyid[j]] = True
    root = model.body_rootid
    return (np.arange(model.nbody) > 0) & ~free[root]


def occlusion(model: mujoco.MjModel, data: mujoco.MjData, eye: Array) -> float:
    """How much of the parts the robots hide from ``eye`` (world, m) in ``data``'s
    configuration (poses as computed by mj_kinematics): the sum over the parts' visual
    geoms of the fraction of their points a robot hides (when a third of them or more),
    weighted 10 for a movable part, 1 for a static one and 0 for a large static one
    (module doc); 0: nothing hidden."""
    robot = _robot_bodies(model)
    idx = _visible_geoms(model)
    idx = idx[~is_parked(data.geom_xpos[idx, 2])]
    parts = idx[~robot[model.geom_bodyid[idx]]]
    if len(parts) == 0 or not robot.any():
        return 0.0
    groups = np.zeros(6, np.uint8)
    groups[:COLLISION_GROUP] = 1
    hit = np.zeros(1, np.int32)
    large = _LARGE * max(float(model.stat.extent), 1e-9)
    score = 0.0
    for g, points in zip(parts, _box_points(model, data, parts, 0.8), strict=True):
        if model.geom_bodyid[g] > 0:
            weight = _MOVABLE_WEIGHT
        else:
            weight = 1.0 if model.geom_rbound[g] < large else 0.0
        if weight == 0:
            continue
        hidden = 0
        for p in points:
            x = mujoco.mj_ray(model, data, eye, p - eye, groups, 1, -1, hit)
            hidden += 0 <= x < 1 - 1e-6 and bool(robot[model.geom_bodyid[hit[0]]])
        if 3 * hidden >= len(points):  # a corner or two behind a robot is no harm
            score += weight * hidden / len(points)
    return score


def _fit(
    P: Array, azimuth: float, elevation: float, tv: float, th: float
) -> tuple[Array, float, Array]:
    """Look-at point, distance and forward direction that put points P within the
    half-angles' tangents ``tv`` (vertical) and ``th`` (horizontal)."""
    az, el = math.radians(azimuth), math.radians(elevation)
    f = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    u = np.array([-math.sin(el) * math.cos(az), -math.sin(el) * math.sin(az), math.cos(el)])
    r = np.cross(f, u)
    c = (P.min(axis=0) + P.max(axis=0)) / 2
    for i in range(6):  # fit the distance, then centre the projection; the last fit stays
        x, y, z = (P - c) @ r, (P - c) @ u, (P - c) @ f
        d = float(max(np.max(np.abs(x) / th - z), np.max(np.abs(y) / tv - z)))
        if i == 5:
            break
        px, py = x / np.maximum(z + d, 1e-9), y / np.maximum(z + d, 1e-9)
        c = c + (r * (px.max() + px.min()) + u * (py.max() + py.min())) / 2 * d
    return c, d, f


def overview_camera(
    model: mujoco.MjModel,
    qpos: Iterable[Array] | None = None,
    *,
    width: int = 640,
    height: int = 480,
    azimuth: float | None = None,
    elevation: float = -24.0,
    margin: float = 0.06,
) -> mujoco.MjvCamera:
    """A free camera that frames the cell's visual geometry in every pose of ``qpos``.

    ``qpos``: the configurations to cover (default: ``qpos0``); the first is the one in
    which no part may hide behind a robot (module doc). The camera looks down
    ``elevation`` degrees from ``azimuth`` (default: chosen as the module doc says); its
    distance and look-at point put the projected geometry within ``margin`` (fraction of
    the half size) of the picture's edges for a ``width`` x ``height`` picture with the
    model's vertical field of view.
    """
    data = mujoco.MjData(model)
    configs = [model.qpos0] if qpos is None else list(qpos)
    pts = []
    for q in reversed(configs):  # ends in the first configuration: the one checked
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        pts.append(visual_points(model, data))
    P = np.concatenate(pts) if pts else np.empty((0, 3))
    cam = mujoco.MjvCamera()
    mujoco.mjv_defaultFreeCamera(model, cam)
    if len(P) == 0:
        return cam
    tv = math.tan(math.radians(model.vis.global_.fovy) / 2) * (1 - margin)
    th = tv * width / height
    if azimuth is None:
        span = P.max(axis=0) - P.min(axis=0)
        start = 60.0 if span[0] >= span[1] else 150.0
        best = None
        for k in range(round(360 / AZIMUTH_STEP)):
            az = start + AZIMUTH_STEP * ((k + 1) // 2) * (1 if k % 2 else -1)  # 0, +30, -30 ...
            c, d, f = _fit(P, az, elevation, tv, th)
            score = occlusion(model, data, c - d * f)
            if best is None or score < best[0]:
                best = (score, az, c, d)
            if score == 0:
                break
        _, azimuth, c, d = best  # type: ignore[misc]
    else:
        c, d, _ = _fit(P, azimuth, elevation, tv, th)
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = c
    cam.distance = d
    cam.azimuth, cam.elevation = azimuth % 360.0, elevation
    return cam


def named_view(
    model: mujoco.MjModel,
    name: str | None,
    qpos: Callable[[], Iterable[Array]] | None = None,
    *,
    width: int = 640,
    height: int = 480,
) -> str | mujoco.MjvCamera:
    """The view ``name`` names (module doc): the cell camera's name itself, else the
    preset view fitted over the configurations ``qpos()`` gives (default: ``qpos0``;
    called only for a preset) for a ``width`` x ``height`` picture; None: ``overview``.
    An unknown name: ModelError listing the cell's cameras and the preset views."""
    if name is not None and mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, name) >= 0:
        return name
    view = VIEWS.get("overview" if name is None else name)
    if view is None:
        cams = [model.camera(i).name for i in range(model.ncam)]
        raise ModelError(
            f"no camera {name!r} in the cell and no such view; cameras: "
            f"{', '.join(cams) or 'none'}; views: {', '.join(VIEWS)}"
        )
    configs = None if qpos is None else qpos()
    return overview_camera(model, configs, width=width, height=height, **view)


def camera_eye(cam: mujoco.MjvCamera) -> tuple[Array, Array]:
    """A free camera's eye point and look-at point (m, world): the eye sits ``distance``
    behind the look-at point along the viewing direction given by azimuth and elevation."""
    az, el = math.radians(cam.azimuth), math.radians(cam.elevation)
    forward = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    look = np.array(cam.lookat, dtype=np.float64)
    return look - cam.distance * forward, look
