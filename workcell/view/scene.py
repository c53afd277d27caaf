"""The cell in the live view's 3-D scene: a node per body, the visual geoms as meshes.

:class:`Scene` builds, from a simulator's compiled model, one viser frame per body that
has visual geoms (``/cell/<body>``, placed at the body's world pose) with its geoms as
meshes in the body's frame, in the geom's colour (collision-only geoms, group 3, are
left out; primitives become meshes; the ground plane becomes a grid on the floor's colour).
It adds axes at each robot's base and tool, a marker for contacts, and one line set
per robot for its tool path. :meth:`Scene.show` poses every moving body from an
``MjData`` and paints the bodies in contact red, with a marker and the depth at each
contact point; bodies welded to the world are placed once.

Colours are MuJoCo's (geom rgba, else its material's), so the page and MuJoCo's own
renderer agree on what is where (tests compare the two pictures).
"""

from __future__ import annotations

from collections.abc import Iterable

import mujoco
import numpy as np
import trimesh
import viser
from numpy.typing import NDArray

from workcell.meshgeoms import COLLISION_GROUP
from workcell.view.contacts import Contact

__all__ = ["COLLISION_RGB", "Scene", "geom_mesh", "geom_rgba"]

COLLISION_RGB = (235, 20, 20)  # bodies in contact
_MARKERS = 8  # contact markers kept (the deepest contacts shown)
_G = mujoco.mjtGeom
Array = NDArray[np.float64]


def stage(server: viser.ViserServer) -> None:
    """An empty scene, z up, with plain lights (no environment map to load and fade in:
    steady colours at once; no shadows: ten times the work in a software browser)."""
    server.scene.reset()
    server.scene.set_up_direction("+z")
    server.scene.configure_environment_map(None)
    server.scene.configure_default_lights(cast_shadow=False)
    server.scene.add_light_hemisphere("/lights/sky", sky_color=(255, 255, 255),
                                      ground_color=(120, 120, 130), intensity=2.0)  # fmt: skip


def geom_rgba(model: mujoco.MjModel, g: int) -> NDArray[np.float64]:
    """A geom's colour (0..1): its rgba, else its material's (MuJoCo's rule)."""
    rgba = model.geom_rgba[g]
    mat = model.geom_matid[g]
    if mat >= 0 and np.allclose(rgba, (0.5, 0.5, 0.5, 1.0)):
        rgba = model.mat_rgba[mat]
    return np.clip(rgba, 0.0, 1.0)


def geom_mesh(model: mujoco.MjModel, g: int) -> trimesh.Trimesh | None:
    """A visual geom's surface in its own frame (m), or None for what is not drawn."""
    kind, size = model.geom_type[g], model.geom_size[g]
    if kind == _G.mjGEOM_MESH:
        mid = model.geom_dataid[g]
        v0, nv = model.mesh_vertadr[mid], model.mesh_vertnum[mid]
        f0, nf = model.mesh_faceadr[mid], model.mesh_facenum[mid]
        return trimesh.Trimesh(
            model.mesh_vert[v0 : v0 + nv].astype(np.float64),
            model.mesh_face[f0 : f0 + nf],
            process=False,
        )
    if kind == _G.mjGEOM_BOX:
        return trimesh.creation.box(extents=2.0 * size)
    if kind == _G.mjGEOM_SPHERE:
        return trimesh.creation.icosphere(subdivisions=3, radius=float(size[0]))
    if kind == _G.mjGEOM_ELLIPSOID:
        s = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
        s.apply_scale(size)
        return s
    if kind == _G.mjGEOM_CYLINDER:
        return trimesh.creation.cylinder(radius=float(size[0]), height=2.0 * size[1], sections=32)
    if kind == _G.mjGEOM_CAPSULE:
        return trimesh.creation.capsule(height=2.0 * size[1], radius=float(size[0]))
    return None  # planes (the floor is drawn apart), height fields, SDFs


def _u8(rgb: Iterable[float]) -> tuple[int, int, int]:
    r, g, b = (round(255 * float(c)) for c in list(rgb)[:3])
    return (r, g, b)


class Scene:
    """The cell's nodes on a viser server (module doc)."""

    def __init__(self, server: viser.ViserServer, model: mujoco.MjModel, data: mujoco.MjData,
                 *, labels: list[str], tool_sites: dict[str, int],
                 bases: dict[str, Array]) -> None:  # fmt: skip
        self.server = server
        self.model = model
        sc = server.scene
        names = [model.body(b).name or f"body{b}" for b in range(model.nbody)]
        self.frames: dict[int, viser.FrameHandle] = {}
        # meshes by thing label (a body's name, a static part's name): what turns red
        self.meshes: dict[str, list[tuple[viser.MeshHandle, tuple[int, int, int]]]] = {}
        self.moving = [b for b in range(1, model.nbody) if model.body_weldid[b]]
        extent = float(model.stat.extent)
        for g in range(model.ngeom):
            if model.geom_group[g] == COLLISION_GROUP or model.geom_rgba[g][3] == 0:
                continue
            b = int(model.geom_bodyid[g])
            if model.geom_type[g] == _G.mjGEOM_PLANE:
                self._floor(model, g, extent)
                continue
            mesh = geom_mesh(model, g)
            if mesh is None:
                continue
            if b not in self.frames:
                self.frames[b] = sc.add_frame(
                    f"/cell/{names[b]}", show_axes=False,
                    position=data.xpos[b].copy(), wxyz=data.xquat[b].copy(),
                )  # fmt: skip
            rgba = geom_rgba(model, g)
            colour = _u8(rgba)
            h = sc.add_mesh_simple(
                f"/cell/{names[b]}/{model.geom(g).name or f'geom{g}'}",
                vertices=np.asarray(mesh.vertices, np.float32),
                faces=np.asarray(mesh.faces, np.uint32),
                color=colour,
                opacity=None if rgba[3] >= 1 else float(rgba[3]),
                flat_shading=True,
                cast_shadow=False,
                receive_shadow=False,
                position=model.geom_pos[g].copy(),
                wxyz=model.geom_quat[g].copy(),
            )
            self.meshes.setdefault(labels[g], []).append((h, colour))
        self.moving = [b for b in self.moving if b in self.frames]
        self.tool_sites = tool_sites
        axes = max(0.05, 0.06 * extent)
        for robot, T in bases.items():
            sc.add_frame(f"/axes/{robot}/base", axes_length=axes, axes_radius=axes / 25,
                         position=T[:3, 3], wxyz=_wxyz(T[:3, :3]))  # fmt: skip
        self.tools = {
            r: sc.add_frame(f"/axes/{r}/tool", axes_length=axes * 0.7, axes_radius=axes / 35)
            for r in tool_sites
        }
        self.markers = [
            (
                sc.add_icosphere(f"/contacts/m{i}", radius=0.008, color=(255, 230, 0),
                                 visible=False),
                sc.add_label(f"/contacts/m{i}/depth", "", visible=False),
            )
            for i in range(_MARKERS)
        ]  # fmt: skip
        self.paths: dict[str, viser.LineSegmentsHandle] = {}
        self._red: set[str] = set()
        self._marked = False
        self._ids = np.array(self.moving, dtype=np.intp)
        self._shown = np.full((len(self._ids), 7), np.nan)  # poses sent: xpos, xquat

    def _floor(self, model: mujoco.MjModel, g: int, extent: float) -> None:
        # One node: the grid's own plane carries the floor's colour. A separate floor
        # quad under the grid doubled the full-screen fragment work, which is most of a
        # frame in a software-rendered browser (6 -> 10 frames a second, 1280 x 800).
        size = model.geom_size[g]
        half = [float(s) if s > 0 else 2.0 * extent for s in size[:2]]
        cells = max(0.1, round(extent / 5.0, 1))
        rgba = geom_rgba(model, g)
        self.server.scene.add_grid(
            "/floor/grid", width=2 * half[0], height=2 * half[1], cell_size=cells,
            section_size=5 * cells, plane_color=_u8(rgba), plane_opacity=float(rgba[3]),
            shadow_opacity=0.0, position=model.geom_pos[g].copy(), wxyz=model.geom_quat[g].copy(),
        )  # fmt: skip

    def show(self, data: mujoco.MjData, contacts: list[Contact] | None = None) -> None:
        """Pose the moving bodies and tool axes from ``data``; paint the things in
        ``contacts`` red and mark the contact points (deepest first) with their depth."""
        ids = self._ids
        pose = np.concatenate([data.xpos[ids], data.xquat[ids]], axis=1)
        moved = np.flatnonzero(np.any(pose != self._shown, axis=1))
        self._shown[moved] = pose[moved]
        with self.server.atomic():
            for k in moved:  # only what moved since the last picture (a message each)
                f = self.frames[int(ids[k])]
                f.position = pose[k, :3]
                f.wxyz = pose[k, 3:]
            for r, h in self.tools.items():
                s = self.tool_sites[r]
                if np.any(h.position != data.site_xpos[s]):
                    h.position = data.site_xpos[s]
                    h.wxyz = _wxyz(data.site_xmat[s].reshape(3, 3))
            contacts = contacts or []
            red = {x for c in contacts for x in (c.a, c.b)} & set(self.meshes)
            for label in self._red ^ red:
                for h, colour in self.meshes[label]:
                    h.color = COLLISION_RGB if label in red else colour
            self._red = red
            if contacts or self._marked:
                for i, (ball, text) in enumerate(self.markers):
                    if i < len(contacts):
                        ball.position = contacts[i].point
                        text.text = f"{contacts[i].depth * 1e3:.3g} mm"
                    ball.visible = text.visible = i < len(contacts)
            self._marked = bool(contacts)

    @property
    def red(self) -> set[str]:
        """The things drawn red now (in contact in the shown frame)."""
        return set(self._red)

    def set_path(self, robot: str, points: Array, colour: tuple[int, int, int]) -> None:
        """Draw the robot's tool path through ``points`` (k, 3) as line segments."""
        if len(points) < 2:
            if robot in self.paths:
                self.paths[robot].visible = False
            return
        seg = np.stack([points[:-1], points[1:]], axis=1).astype(np.float32)
        h = self.paths.get(robot)
        if h is None:
            self.paths[robot] = self.server.scene.add_line_segments(
                f"/paths/{robot}",
                points=seg,
                colors=colour,
                thickness=2.0,
                thickness_units="screen",
            )
        else:
            h.points = seg
            h.visible = True


def _wxyz(R: Array) -> NDArray[np.float64]:
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=np.float64).reshape(9))
    return q
