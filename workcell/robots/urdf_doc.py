"""One URDF document while it is read: numbers, origins, colours, files and link shapes.

Used by :mod:`workcell.robots.urdf` (which reads the joints and builds the robot).

Mesh file names (:meth:`UrdfDoc.places`): ``package://PKG/REL`` is looked up as
``packages[PKG]/REL``, then ``S/REL`` for each folder S of ``search``, then ``REL`` under
the URDF's folder and its parent (the ROS layout ``PKG/urdf/robot.urdf``: real files
name packages such as ``kuka_kr16_support`` whose folder is called otherwise), then the
whole ``PKG/REL`` under the URDF's folder and its parents up to three levels up
(pybullet's files write ``package://meshes/link0.obj`` for ``meshes/`` beside the URDF);
``file:///abs`` and plain paths are taken as they are (relative to the URDF's folder).
With ``root`` (a server's folder), places outside it are not tried.

Link shapes (:meth:`UrdfDoc.shapes`): collision elements are hidden, colliding shapes
(a non-convex mesh is queued in the document's :class:`~workcell.robots.linkshapes.LinkBatch`
for its convex pieces), visual elements drawn ones. A mesh file found nowhere is listed
in the document's :class:`~workcell.robots.standin.Missing` (an error at once with
``strict``); a missing visual mesh is replaced by the link's collision geometry when it
has some, anything else by the link's capsule stand-in
(:func:`workcell.robots.standin.capsule`, sized from the link's ``<inertial>`` or its
joints).
"""

from __future__ import annotations

import math
import os
import stat
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np
import trimesh

from workcell import limits
from workcell.errors import ModelError
from workcell.files import leaves_root
from workcell.meshgeoms import is_convex
from workcell.robots.linkshapes import LinkBatch
from workcell.robots.meshfile import load_mesh, primitive
from workcell.robots.standin import Missing
from workcell.robots.tree import Shape
from workcell.spatial import rot_x, rot_y, rot_z, translation
from workcell.tempfiles import kind

__all__ = ["UrdfDoc"]

_PARENTS = 3  # folders above the URDF's where a whole package:// path is looked for
_SIZES = {"box": ("size", 3), "cylinder": ("radius", 1), "sphere": ("radius", 1)}
_SIZES["capsule"] = ("radius", 1)


class UrdfDoc:
    """One URDF document: elements' lines, materials, how its files are found, the meshes
    it misses and the non-convex ones it queues (module doc)."""

    def __init__(
        self,
        path: Path,
        lines: dict[ET.Element, int],
        packages: Mapping[str, Path],
        search: Sequence[Path],
        root: Path | None,
        *,
        strict: bool = False,
    ) -> None:
        self.path, self.lines, self.packages, self.search = path, lines, packages, search
        self.root = None if root is None else Path(os.path.realpath(root))
        self.materials: dict[str, tuple[float, ...]] = {}
        self.what = f"URDF file '{path}'"
        self.geometry = True
        self.batch: LinkBatch | None = None  # non-convex collision meshes to decompose
        self.queued: list[tuple[int, int]] = []  # (shape index, batch index) in a link
        self.missing = Missing(self.what, strict)
        self.uri, self.tried = "", []

    def at(self, el: ET.Element, kind: str, name: str | None = None) -> str:
        shown = f" '{name}'" if name is not None else ""
        return f"{kind}{shown} (line {self.lines.get(el, '?')})"

    def fail(self, where: str, msg: str) -> ModelError:
        return ModelError(f"{self.what}: {where}: {msg}")

    def floats(
        self, el: ET.Element | None, attr: str, n: int, default: tuple[float, ...], where: str
    ) -> tuple[float, ...]:
        text = None if el is None else el.get(attr)
        if text is None:
            return default
        try:
            v = tuple(float(x) for x in text.split())
        except ValueError:
            v = ()
        if len(v) != n or not all(math.isfinite(x) for x in v):
            raise self.fail(where, f"{el.tag} {attr}={text!r} must be {n} finite number(s)")
        return v

    def origin(self, el: ET.Element | None, where: str) -> np.ndarray:
        o = None if el is None else el.find("origin")
        xyz = self.floats(o, "xyz", 3, (0.0, 0.0, 0.0), where)
        r, p, y = self.floats(o, "rpy", 3, (0.0, 0.0, 0.0), where)
        limits.check("max_coordinate", max(abs(v) for v in xyz), where)
        return translation(*xyz) @ rot_z(y) @ rot_y(p) @ rot_x(r)  # URDF: fixed axes x, y, z

    def colour(self, el: ET.Element | None, where: str) -> tuple[float, ...] | None:
        if el is None:
            return None
        c = el.find("color")
        if c is not None:
            rgba = self.floats(c, "rgba", 4, (0.7, 0.7, 0.72, 1.0), where)
            if not all(0 <= v <= 1 for v in rgba):
                raise self.fail(where, f"colour rgba {list(rgba)} must be 4 numbers in [0, 1]")
            return rgba
        return self.materials.get(el.get("name", ""))

    def inertial(
        self, link: ET.Element, where: str
    ) -> tuple[np.ndarray | None, float, np.ndarray | None]:
        """(centre of mass (3,) m, mass kg, principal moments (3,) kg m^2) of a link's
        ``<inertial>`` (None, 0, None without one)."""
        el = link.find("inertial")
        if el is None:
            return None, 0.0, None
        com = self.origin(el, where)[:3, 3]
        (mass,) = self.floats(el.find("mass"), "value", 1, (0.0,), where)
        i = el.find("inertia")
        if i is None:
            return com, mass, None
        xx, xy, xz, yy, yz, zz = (
            self.floats(i, a, 1, (0.0,), where)[0]
            for a in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
        )
        tensor = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        return com, mass, np.linalg.eigvalsh(tensor)

    # ------------------------------------------------------------------ files
    def places(self, uri: str) -> list[Path]:
        """Where mesh file ``uri`` is looked for, in order (module doc)."""
        here = self.path.parent
        if uri.startswith("package://"):
            whole = uri[len("package://") :]
            pkg, _, rel = whole.partition("/")
            folders = [self.packages[pkg]] if pkg in self.packages else []
            out = [f / rel for f in (*folders, *self.search, here, here.parent) if rel]
            out += [f / whole for f in (here, *list(here.parents)[:_PARENTS])]
            return list(dict.fromkeys(out))
        if uri.startswith("file://"):
            return [Path(uri[len("file://") :])]
        return [here / uri]

    def find(self, uri: str) -> Path | None:
        """The first existing place of ``uri``; None (and the places in ``self.tried``)."""
        self.uri, self.tried = uri, []
        for p in self.places(uri):
            real = Path(os.path.realpath(p))
            why = None if self.root is None else leaves_root(real, self.root)
            if why is not None:
                self.tried.append(f"{p} ({why.removeprefix('it ')}: not tried)")
            elif real.is_file():
                return real
            elif real.exists():  # a folder, FIFO, device: passed over, never opened
                mode = real.stat().st_mode
                what = "a folder" if stat.S_ISDIR(mode) else kind(mode)
                self.tried.append(f"{p} ({what}, not a regular file)")
            else:
                self.tried.append(str(p))
        return None

    # ------------------------------------------------------------------ shapes
    def parts(self, el: ET.Element, where: str) -> list[tuple[trimesh.Trimesh, tuple | None]]:
        """The meshes of a <visual> or <collision> (with their own colours); [] when its
        mesh file is missing (``self.uri`` and ``self.tried`` say which and where)."""
        g = el.find("geometry")
        shape = None if g is None else next(iter(g), None)
        if shape is None:
            raise self.fail(
                where, f"<{el.tag}> needs a <geometry> with a mesh, box, cylinder or sphere"
            )
        w = f"{where} {shape.tag}"
        if shape.tag == "mesh":
            uri = shape.get("filename")
            if not uri:
                raise self.fail(where, "<mesh> needs a filename")
            scale = self.floats(shape, "scale", 3, (1.0, 1.0, 1.0), where)
            found = self.find(uri)
            if found is None:
                return []
            return load_mesh(found, scale=scale, what=f"{self.what}: {where}")  # type: ignore[arg-type]
        if shape.tag not in _SIZES:
            raise self.fail(
                where, f"unknown geometry <{shape.tag}>; known: mesh, {', '.join(_SIZES)}"
            )
        attr, n = _SIZES[shape.tag]
        size = self.floats(shape, attr, n, (), w)
        if shape.tag in ("cylinder", "capsule"):
            size += self.floats(shape, "length", 1, (), w)
        return [(primitive(shape.tag, size=size, what=f"{self.what}: {w}"), None)]

    def shapes(
        self, link: ET.Element, where: str, standin: Callable[[], trimesh.Trimesh]
    ) -> list[Shape]:
        """A link's collision shapes (hidden, colliding) and visual shapes (module doc);
        ``standin()`` makes the link's capsule stand-in when a mesh file is missing."""
        shapes: list[Shape] = []
        eye = np.eye(4)
        for k, el in enumerate(link.findall("collision")):
            w = f"{where} collision {k + 1}"
            parts = self.parts(el, w)
            if not parts:
                self.missing.add(self.uri, w, self.tried, "a capsule between its joints stands in")
                if not any(s.mesh.metadata.get("standin") for s in shapes):
                    shapes.append(Shape(_mark(standin()), eye, None, visible=False, pieces=()))
                continue
            T = self.origin(el, w)
            for mesh, _ in parts:
                # convex, or its hull when asked (no batch): its own hull; else queued
                if self.batch is not None and not is_convex(mesh):
                    self.queued.append((len(shapes), self.batch.add(mesh, w)))
                shapes.append(Shape(mesh, T, None, visible=False, pieces=()))
        collisions = list(shapes)
        replaced = False
        for k, el in enumerate(link.findall("visual")):
            w = f"{where} visual {k + 1}"
            colour = self.colour(el.find("material"), w)
            parts = self.parts(el, w)
            if parts:
                T = self.origin(el, w)
                shapes.extend(Shape(mesh, T, colour or own) for mesh, own in parts)
                continue
            instead = "drawn with its collision geometry"
            if not collisions:
                instead = "a capsule between its joints stands in"
                collisions = [Shape(_mark(standin()), eye, None, visible=False, pieces=None)]
            self.missing.add(self.uri, w, self.tried, instead)
            if not replaced:  # the link is drawn once with what stands in
                shapes.extend(Shape(s.mesh, s.transform, colour) for s in collisions)
                replaced = True
        return shapes


def _mark(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    mesh.metadata["standin"] = True
    return mesh
