"""Camera presets of the live view: the overview, top, front, one per robot, and the
cell's own cameras, each as (eye, look-at, up, vertical field of view).

The overview is :func:`workcell.record.camera.overview_camera` (the camera of the
project's pictures: it frames every visual geom and turns until no part hides behind a
robot), converted from MuJoCo's free camera (look-at, distance, azimuth, elevation) to
an eye point; top and front look at the same centre from above and from -y; a robot's
preset looks at its base from a three-quarter view at three times its reach; a cell
camera is MuJoCo's camera (it looks along its -z axis, its y axis up).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.record.camera import camera_eye, overview_camera

if TYPE_CHECKING:
    import viser

    from workcell.robots.robot import Robot

__all__ = ["View", "apply_view", "free_camera_view", "presets", "reach"]

Array = NDArray[np.float64]


class View(NamedTuple):
    """A camera: ``eye`` and ``look_at`` (m, world), ``up`` (unit), ``fov`` (rad, vertical)."""

    eye: Array
    look_at: Array
    up: Array
    fov: float


def free_camera_view(cam: mujoco.MjvCamera, fovy_deg: float) -> View:
    """MuJoCo's free camera as a View (:func:`~workcell.record.camera.camera_eye`)."""
    eye, look = camera_eye(cam)
    return View(eye, look, np.array([0.0, 0.0, 1.0]), math.radians(fovy_deg))


def presets(model: mujoco.MjModel, data: mujoco.MjData, bases: dict[str, Array],
            reaches: dict[str, float], cameras: dict[str, str]) -> dict[str, View]:  # fmt: skip
    """Every preset by name: "overview", "top", "front", "robot <name>", "camera <name>"."""
    fovy = float(model.vis.global_.fovy)
    over = free_camera_view(overview_camera(model, [data.qpos.copy()]), fovy)
    out = {"overview": over}
    dist = float(np.linalg.norm(over.eye - over.look_at))
    c = over.look_at
    z = np.array([0.0, 0.0, 1.0])
    out["top"] = View(c + np.array([0.0, -1e-3 * dist, dist]), c.copy(), z, over.fov)
    out["front"] = View(c + np.array([0.0, -dist, 0.0]), c.copy(), z, over.fov)
    for robot, T in bases.items():
        look = T[:3, 3] + np.array([0.0, 0.0, 0.5 * reaches[robot]])
        d = 3.0 * reaches[robot]
        eye = look + d * np.array([0.6, -0.6, 0.5]) / np.linalg.norm([0.6, -0.6, 0.5])
        out[f"robot {robot}"] = View(eye, look, z, over.fov)
    for name, cam in cameras.items():
        c_id = model.camera(cam).id
        R = data.cam_xmat[c_id].reshape(3, 3)
        eye = data.cam_xpos[c_id].copy()
        out[f"camera {name}"] = View(eye, eye - R[:, 2], R[:, 1].copy(),
                                     math.radians(float(model.cam_fovy[c_id])))  # fmt: skip
    return out


def reach(robot: Robot) -> float:
    """A robot's reach (m): the farthest tool point from its base over sampled poses."""
    lo, hi = np.asarray(robot.lower), np.asarray(robot.upper)
    lo, hi = np.where(np.isfinite(lo), lo, -math.pi), np.where(np.isfinite(hi), hi, math.pi)
    Q = lo + np.random.default_rng(0).random((64, len(lo))) * (hi - lo)
    T = robot.fk_batch(Q)
    return float(max(0.3, np.max(np.linalg.norm(T[:, :3, 3], axis=1))))


def apply_view(server: viser.ViserServer, v: View, client: viser.ClientHandle | None) -> None:
    """Point one page's camera (``client``), else every page's and the initial one, at
    ``v``."""
    cams = [client.camera] if client is not None else [
        c.camera for c in server.get_clients().values()]  # fmt: skip
    ic = server.initial_camera
    ic.position, ic.look_at, ic.up, ic.fov = tuple(v.eye), tuple(v.look_at), tuple(v.up), v.fov
    for cam in cams:
        with server.atomic():
            cam.up_direction = tuple(v.up)
            cam.position = tuple(v.eye)
            cam.look_at = tuple(v.look_at)
            cam.fov = v.fov
