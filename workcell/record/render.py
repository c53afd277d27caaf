"""Offscreen pictures of a workcell: cameras, the renderer, PNGs of any frame.

Rendering uses MuJoCo's OpenGL renderer headless; :mod:`workcell.record.gl` picks the
backend (``MUJOCO_GL``, else EGL then OSMesa, a RenderError when none works) when the
first context is made, and this module keeps it for the process (:func:`gl_backend`).

Pictures show visual geometry only (collision pieces, group 3, and sites hidden; with
``collision=True`` the collision pieces instead, each piece of a solid in its own colour), no
shadows and no multisampling (about 15x cheaper on a CPU), a sun-like directional light
plus the head light, and a soft sky where nothing is drawn. The default camera,
:func:`~workcell.record.camera.overview_camera`, frames the visual geometry of the cell
over a whole run, so robots and parts fill the picture without being clipped, from a side
where no part hides behind a robot. Sizes are in pixels, times in
seconds of simulated time.

Contact sheets of key frames and MP4 videos live in :mod:`workcell.record.sheets`; their
names are importable from here too (``from workcell.record.render import contact_sheet``).
"""

from __future__ import annotations

import copy
import io
import itertools
import math
import os
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.errors import ModelError, RenderError
from workcell.files import atomic_write_bytes
from workcell.meshgeoms import COLLISION_GROUP, VISUAL_GROUP
from workcell.record.camera import named_view, overview_camera
from workcell.record.gl import free_context, open_context

if TYPE_CHECKING:
    from workcell.cell.workcell import Workcell
    from workcell.record.sheets import (
        KEY_EVENT_KINDS,
        KeyFrame,
        contact_sheet,
        key_frames,
        save_mp4,
        video_frames,
    )
    from workcell.sim.simulator import Simulator

__all__ = [
    "KEY_EVENT_KINDS",  # from sheets
    "CellRenderer",
    "KeyFrame",  # from sheets
    "contact_sheet",  # from sheets
    "gl_backend",
    "key_frames",  # from sheets
    "overview_camera",
    "render_cell",
    "render_frame",
    "save_mp4",  # from sheets
    "save_png",
    "video_frames",  # from sheets
]

_SHEETS = ("KEY_EVENT_KINDS", "KeyFrame", "contact_sheet", "key_frames", "save_mp4", "video_frames")
_SKY_TOP = np.array([0.45, 0.56, 0.72])  # background gradient (RGB 0-1), top to horizon
_SKY_HORIZON = np.array([0.74, 0.78, 0.84])
_FLOOR_RGBA = np.array([0.46, 0.49, 0.54, 1.0])  # planes: darker than the pale arm links
_GRID_RGBA = np.array([0.56, 0.59, 0.64, 1.0], np.float32)
_PIECE_RGBA = np.array(  # collision pieces, one colour each in turn (collision pictures)
    [
        [0.90, 0.33, 0.25, 1.0],
        [0.25, 0.60, 0.90, 1.0],
        [0.95, 0.75, 0.20, 1.0],
        [0.35, 0.75, 0.40, 1.0],
        [0.70, 0.45, 0.85, 1.0],
        [0.95, 0.55, 0.75, 1.0],
        [0.30, 0.80, 0.80, 1.0],
    ]
)
_backend: str | None = None  # the GL backend that worked, kept for the process


def __getattr__(name: str) -> Any:
    """The names of :mod:`workcell.record.sheets`, imported on first use (it imports this
    module, so importing it here at the top would be circular)."""
    if name in _SHEETS:
        from workcell.record import sheets

        return getattr(sheets, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_SHEETS})


# ---------------------------------------------------------------------- backend
def _open_gl(model: mujoco.MjModel, width: int, height: int) -> tuple[Any, mujoco.MjrContext]:
    """A current GL context and an offscreen MjrContext, choosing the backend on first use."""
    global _backend
    gl, mjr, _backend = open_context(model, width, height, _backend)
    return gl, mjr


def gl_backend() -> str | None:
    """The GL backend in use ("egl", "osmesa", "glfw"), or None before the first render."""
    return _backend


# ---------------------------------------------------------------------- renderer
class CellRenderer:
    """An offscreen renderer of one model at ``width`` x ``height`` pixels.

    Draws from a private copy of the model (the caller's is not changed) in the module's
    style: visual groups only, no shadows or MSAA, a sun and the head light, a blue-grey
    floor with a grid and a sky with matching fog, unless the model brings its own floor
    material or skybox. Use it as a context manager or call :meth:`close`: a GL context
    left to the garbage collector at interpreter exit prints EGL errors.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        width: int = 640,
        height: int = 480,
        *,
        collision: bool = False,
    ) -> None:
        for what, v in (("width", width), ("height", height)):
            if not (isinstance(v, (int, np.integer)) and 8 <= v <= 8192):
                raise RenderError(f"{what} must be an integer in [8, 8192] pixels, got {v!r}")
        self.width, self.height = int(width), int(height)
        m = copy.copy(model)
        m.vis.global_.offwidth = max(self.width, m.vis.global_.offwidth)
        m.vis.global_.offheight = max(self.height, m.vis.global_.offheight)
        m.vis.quality.offsamples = 0
        m.vis.headlight.ambient[:] = 0.32
        m.vis.headlight.diffuse[:] = 0.38
        m.vis.headlight.specular[:] = 0.08
        self._sky = not np.any(m.tex_type == mujoco.mjtTexture.mjTEXTURE_SKYBOX)
        m.vis.rgba.fog[:3] = _SKY_HORIZON
        planes = (m.geom_type == mujoco.mjtGeom.mjGEOM_PLANE) & (m.geom_matid < 0)
        m.geom_rgba[planes] = _FLOOR_RGBA
        self.model = m
        self.option = mujoco.MjvOption()
        self.option.geomgroup[COLLISION_GROUP:] = 0
        if collision:  # the collision pieces instead of the visual meshes
            self.option.geomgroup[VISUAL_GROUP] = 0
            self.option.geomgroup[COLLISION_GROUP] = 1
            cols = np.flatnonzero(m.geom_group == COLLISION_GROUP)
            m.geom_rgba[cols] = _PIECE_RGBA[np.arange(len(cols)) % len(_PIECE_RGBA)]
        self.option.sitegroup[:] = 0
        self.scene = mujoco.MjvScene(m, maxgeom=max(1000, 2 * m.ngeom))
        self._rect = mujoco.MjrRect(0, 0, self.width, self.height)
        self._gl, self._mjr = _open_gl(m, self.width, self.height)
        self._depth = np.empty((self.height, self.width), np.float32)
        t = np.linspace(0.0, 1.0, self.height)[:, None] ** 0.7
        self._sky_rows = ((1 - t) * _SKY_TOP + t * _SKY_HORIZON) * 255  # (H, 3)
        self._grid = _floor_grid(m)

    def camera(self, name: str) -> mujoco.MjvCamera:
        """The model's fixed camera ``name``; ModelError listing the cameras if unknown."""
        cid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_CAMERA, name)
        if cid < 0:
            known = [self.model.camera(i).name for i in range(self.model.ncam)]
            raise ModelError(
                f"no camera {name!r} in the cell; cameras: {', '.join(known) or 'none'}"
            )
        cam = mujoco.MjvCamera()
        cam.type, cam.fixedcamid = mujoco.mjtCamera.mjCAMERA_FIXED, cid
        return cam

    def render(
        self,
        data: mujoco.MjData,
        camera: str | mujoco.MjvCamera,
        paths: Sequence[tuple[NDArray[np.float64], Sequence[float]]] = (),
    ) -> NDArray[np.uint8]:
        """An (H, W, 3) uint8 picture of ``data`` (poses as computed by mj_forward);
        ``paths``: polylines drawn over the cell, each (points (k, 3) m, RGBA)."""
        if self._mjr is None:
            raise RenderError("the renderer is closed")
        cam = self.camera(camera) if isinstance(camera, str) else camera
        mujoco.mjv_updateScene(
            self.model, data, self.option, None, cam, mujoco.mjtCatBit.mjCAT_ALL, self.scene
        )
        self.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
        self.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = False
        self.scene.flags[mujoco.mjtRndFlag.mjRND_FOG] = True
        self._add_grid()
        for points, rgba in paths:
            self._add_path(np.asarray(points, dtype=np.float64), rgba)
        self._set_lights()
        # fog (m): from just past the cell to a few extents behind it, whatever the camera
        ext = max(float(self.model.stat.extent), 0.1)
        dist = float(np.linalg.norm(np.array(self.scene.camera[0].pos) - self.model.stat.center))
        self._mjr.fogStart, self._mjr.fogEnd = dist + 0.8 * ext, dist + 2.5 * ext
        self._gl.make_current()
        mujoco.mjr_render(self._rect, self.scene, self._mjr)
        img = np.empty((self.height, self.width, 3), np.uint8)
        mujoco.mjr_readPixels(img, self._depth if self._sky else None, self._rect, self._mjr)
        img = np.flipud(img)
        if self._sky:  # nothing drawn (depth at the far plane): a sky gradient
            empty = np.flipud(self._depth) >= 1.0
            rows = np.broadcast_to(self._sky_rows[:, None, :], img.shape)
            img[empty] = rows[empty].astype(np.uint8)
        return np.ascontiguousarray(img)

    def _set_lights(self) -> None:
        """The cell's lights become one sun, from above and behind the camera's left."""
        scn = self.scene
        f = np.array(scn.camera[0].forward, dtype=np.float64)
        side = np.cross(f, [0.0, 0.0, 1.0])
        d = f + 0.6 * side / max(np.linalg.norm(side), 1e-9) + np.array([0.0, 0.0, -1.3])
        for k in range(scn.nlight):
            light = scn.lights[k]
            if light.headlight:
                continue
            light.type = mujoco.mjtLightType.mjLIGHT_DIRECTIONAL
            light.dir = d / np.linalg.norm(d)
            light.diffuse, light.specular, light.ambient = [0.55] * 3, [0.15] * 3, [0.0] * 3

    def _add_grid(self) -> None:
        """Grid lines on the floor plane (scene-only geoms, no effect on the model)."""
        scn = self.scene
        n = min(len(self._grid), scn.maxgeom - scn.ngeom)
        for k in range(n):
            a, b = self._grid[k]
            g = scn.geoms[scn.ngeom + k]
            mujoco.mjv_initGeom(
                g,
                mujoco.mjtGeom.mjGEOM_LINE,
                np.zeros(3),
                np.zeros(3),
                np.eye(3).ravel(),
                _GRID_RGBA,
            )
            mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_LINE, 1.0, a, b)
        scn.ngeom += n

    def _add_path(self, points: NDArray[np.float64], rgba: Sequence[float]) -> None:
        """A polyline as thin capsules (scene-only geoms), at most 400 segments."""
        scn = self.scene
        if len(points) > 401:
            points = points[np.linspace(0, len(points) - 1, 401).round().astype(int)]
        radius = 0.004 * max(float(self.model.stat.extent), 0.1)
        colour = np.asarray(rgba, dtype=np.float32)
        for a, b in itertools.pairwise(points):
            if scn.ngeom >= scn.maxgeom or np.allclose(a, b):
                continue
            g = scn.geoms[scn.ngeom]
            mujoco.mjv_initGeom(
                g,
                mujoco.mjtGeom.mjGEOM_CAPSULE,
                np.zeros(3),
                np.zeros(3),
                np.eye(3).ravel(),
                colour,
            )
            mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_CAPSULE, radius, a, b)
            scn.ngeom += 1

    def close(self) -> None:
        """Free the GL resources (idempotent)."""
        if self._mjr is not None:
            self._mjr.free()
            self._mjr = None
        if self._gl is not None:
            free_context(self._gl)
            self._gl = None

    def __enter__(self) -> CellRenderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        if getattr(self, "_mjr", None) is not None:
            self.close()


def _nice(x: float) -> float:
    """The 1-2-5 step nearest below x."""
    e = 10 ** math.floor(math.log10(x))
    return e * max(v for v in (1, 2, 5) if v * e <= x)


def _floor_grid(m: mujoco.MjModel) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
    """Segments of a square grid on the first horizontal plane geom (none: no segments).

    It covers the model's extent around its centre, spacing a 1-2-5 step near extent/5.
    """
    planes = np.flatnonzero(m.geom_type == mujoco.mjtGeom.mjGEOM_PLANE)
    data = mujoco.MjData(m)
    mujoco.mj_kinematics(m, data)
    for g in planes:
        if m.geom_matid[g] >= 0:  # the floor has its own material (a grid texture, say)
            return []
        if m.geom_group[g] < COLLISION_GROUP and data.geom_xmat[g][8] > 1 - 1e-9:
            z = float(data.geom_xpos[g][2]) + 1e-3
            break
    else:
        return []
    ext = max(float(m.stat.extent), 0.1)
    step = _nice(ext / 5)
    cx, cy = (round(float(v) / step) * step for v in m.stat.center[:2])
    k = math.ceil(2.5 * ext / step)
    ticks = np.arange(-k, k + 1) * step
    out = []
    for t in ticks:
        out.append((np.array([cx + t, cy - k * step, z]), np.array([cx + t, cy + k * step, z])))
        out.append((np.array([cx - k * step, cy + t, z]), np.array([cx + k * step, cy + t, z])))
    return out


# ---------------------------------------------------------------------- frames
def _frames_qpos(sim: Simulator, frames: Sequence[int]) -> Iterator[NDArray[np.float64]]:
    """qpos of ``frames`` (ascending, non-negative), one pass over the timeline's blocks."""
    want = list(frames)
    k = 0
    for start, rows in sim.timeline.iter_blocks(want[0] if want else 0):
        while k < len(want) and want[k] < start + len(rows):
            yield rows[want[k] - start, 2:].copy()
            k += 1
        if k == len(want):
            return


def _sample_frames(sim: Simulator, n: int = 64) -> list[int]:
    """n frames evenly over the run plus every key frame (the poses a camera must cover)."""
    from workcell.record.sheets import key_frames

    total = sim.frames
    even = np.linspace(0, total - 1, min(n, total)).round().astype(int).tolist()
    return sorted({*even, *(k.frame for k in key_frames(sim)), total - 1})


def _camera_for(
    sim: Simulator, camera: str | None, width: int, height: int
) -> str | mujoco.MjvCamera:
    """A cell camera or preset view (:func:`~workcell.record.camera.named_view`) fitted
    over the whole run; None: the overview."""
    frames = lambda: _frames_qpos(sim, _sample_frames(sim))  # noqa: E731
    return named_view(sim.model, camera, frames, width=width, height=height)


def _check_frame(sim: Simulator, frame: int) -> int:
    n = sim.frames
    if not (isinstance(frame, (int, np.integer)) and -n <= frame < n):
        raise ModelError(f"frame {frame!r} out of range: the timeline has {n} frames")
    return int(frame) % n


def render_frame(
    sim: Simulator,
    frame: int = -1,
    *,
    camera: str | None = None,
    width: int = 640,
    height: int = 480,
) -> NDArray[np.uint8]:
    """The cell at timeline ``frame`` (negative counts from the end) as (H, W, 3) uint8.

    ``camera``: a camera of the cell by name, a preset view (``"top"``, ``"front"`` ...:
    :data:`~workcell.record.camera.VIEWS`), or None for :func:`overview_camera`; views
    are fitted over the whole run (the same view for every frame of a run).
    """
    i = _check_frame(sim, frame)
    cam = _camera_for(sim, camera, width, height)
    data = mujoco.MjData(sim.model)
    data.qpos[:] = sim.timeline.frame(i)[2]
    mujoco.mj_forward(sim.model, data)
    with CellRenderer(sim.model, width, height) as r:
        return r.render(data, cam)


def render_cell(
    cell: Workcell,
    *,
    camera: str | None = None,
    width: int = 640,
    height: int = 480,
    collision: bool = False,
    concavity: float | None = None,
) -> NDArray[np.uint8]:
    """The cell in its initial state (no simulation) as (H, W, 3) uint8; see :func:`render_frame`.

    ``collision``: draw the collision pieces (non-convex parts decomposed within
    ``concavity``, default :data:`workcell.decompose.DEFAULT_CONCAVITY`), each in its own
    colour, instead of the visual meshes.
    """
    from workcell.cell.compile import compile_cell
    from workcell.decompose import DEFAULT_CONCAVITY

    bound = DEFAULT_CONCAVITY if concavity is None else concavity
    model = compile_cell(cell, concavity=bound).model
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    cam = named_view(model, camera, width=width, height=height)
    with CellRenderer(model, width, height, collision=collision) as r:
        return r.render(data, cam)


def _png_bytes(image: NDArray[np.uint8]) -> bytes:
    from PIL import Image as PILImage

    buf = io.BytesIO()
    PILImage.fromarray(np.asarray(image, dtype=np.uint8)).save(buf, format="PNG")
    return buf.getvalue()


def save_png(image: NDArray[np.uint8], path: str | os.PathLike) -> Path:
    """Write an (H, W, 3) or (H, W) uint8 image as PNG, atomically; return the path."""
    a = np.asarray(image)
    if a.dtype != np.uint8 or a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] not in (3, 4)):
        raise RenderError(f"image must be (H, W[, 3|4]) uint8, got {a.shape} {a.dtype}")
    p = Path(path)
    atomic_write_bytes(p, _png_bytes(a), error=RenderError)
    return p
