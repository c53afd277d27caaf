"""URDF import: :func:`from_urdf` reads a robot description into a :class:`Robot`.

What is read (`URDF <http://wiki.ros.org/urdf/XML>`_, the ROS robot description):

- the chain of movable joints from ``base_link`` (default: the root link) to ``tip_link``
  (default: ``tool0`` when the file has it below the base, else the end of the longest
  chain); fixed joints fold into the next joint's origin, those after the last movable
  joint into the tool, so ``fk(q)`` is the tip link's frame in the base link's frame
  (:mod:`workcell.robots.tree`); other branches are left out (with a warning), except a
  parallel gripper fixed to the last link, which is kept as the robot's gripper;
- joints: ``revolute`` and ``prismatic`` with ``<limit lower upper velocity>``,
  ``continuous`` (limits of +-2 pi rad, two turns, so every angle has a value inside);
  ``effort`` is ignored; ``planar`` and ``floating`` joints (and ``mimic`` joints) cannot
  be in the chain; a missing ``velocity``, accelerations and jerks: the defaults of
  :func:`workcell.robots.meshfile.joint_speeds` (1 rad/s or 0.25 m/s; acceleration =
  speed / 0.25 s, jerk = acceleration / 0.05 s);
- geometry: ``<visual>`` and ``<collision>`` with ``<origin>``; ``mesh`` (STL, OBJ, PLY,
  DAE, with ``scale``), ``box``, ``cylinder``, ``sphere`` (and ``capsule``); colours from
  ``<material>`` (inline, or by name from the robot's materials), else the mesh file's
  own (a DAE's materials). Visual meshes are drawn and carry the mass; collision meshes
  collide, a convex one as itself, any other as its CoACD pieces
  (:func:`workcell.decompose.decompose`, cached on disk);
- the file is read within ``max_file_bytes`` and parsed by expat with every entity
  declaration refused (:func:`workcell.robots.meshfile.parse_xml`).

Mesh file names: ``package://PKG/REL`` is looked up as ``packages[PKG]/REL``, then
``S/REL`` for each folder S of ``search``, then under the URDF's folder and its parent
(the ROS layout ``PKG/urdf/robot.urdf``: real files name packages such as
``kuka_kr16_support`` whose folder is called otherwise); ``file:///abs`` and plain paths
are taken as they are (relative to the URDF's folder). A visual mesh that is found
nowhere falls back to the link's collision geometry with a warning; any other missing
file raises ModelError listing every place tried. With ``root`` (a server's folder),
places outside it are not tried.

Errors (ModelError, naming the element and its line): malformed XML, a missing link, a
link with two parents, a loop, an unknown or unsupported joint type, bad numbers.

Xacro: this module reads URDF only; turn a ``.xacro`` into URDF with the test-only
``xacrodoc`` package (no ROS needed), telling it where the packages are::

    from xacrodoc import XacroDoc, packages
    packages.update_package_cache({"kuka_kr6_support": ".../kuka_kr6",
                                   "kuka_resources": ".../kuka_resources"})
    text = XacroDoc.from_file(".../kr6r700sixx.xacro", resolve_packages=False).to_urdf_string()

then write ``text`` to a ``.urdf`` file and import it. Units: metres, radians, seconds.
"""

from __future__ import annotations

import math
import os
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import trimesh

from workcell import limits
from workcell.decompose import DEFAULT_CONCAVITY, decompose
from workcell.errors import ModelError, WorkcellError
from workcell.files import leaves_root, read_bytes
from workcell.meshgeoms import is_convex
from workcell.robots.chain import Joint
from workcell.robots.meshfile import joint_speeds, load_mesh, parse_xml, primitive, sha256
from workcell.robots.robot import Robot, RobotFile
from workcell.robots.tree import Shape, TreeLink, build_robot
from workcell.spatial import rot_x, rot_y, rot_z, translation

__all__ = ["CONTINUOUS_LIMIT", "from_urdf"]

CONTINUOUS_LIMIT = 2.0 * math.pi  # rad: +- this for a continuous joint
_KINDS = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic"}
_UNSUPPORTED = ("planar", "floating")


class _Doc:
    """One URDF document: elements' lines, materials, and how its files are found."""

    def __init__(
        self,
        path: Path,
        lines: dict[ET.Element, int],
        packages: Mapping[str, Path],
        search: Sequence[Path],
        root: Path | None,
    ) -> None:
        self.path, self.lines, self.packages, self.search = path, lines, packages, search
        self.root = None if root is None else Path(os.path.realpath(root))
        self.materials: dict[str, tuple[float, ...]] = {}
        self.what = f"URDF file '{path}'"
        self.geometry, self.concavity = True, DEFAULT_CONCAVITY

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

    # ------------------------------------------------------------------ files
    def places(self, uri: str) -> list[Path]:
        """Where mesh file ``uri`` is looked for, in order (module doc)."""
        here = self.path.parent
        if uri.startswith("package://"):
            pkg, _, rel = uri[len("package://") :].partition("/")
            folders = [self.packages[pkg]] if pkg in self.packages else []
            return [f / rel for f in (*folders, *self.search, here, here.parent)]
        if uri.startswith("file://"):
            return [Path(uri[len("file://") :])]
        return [here / uri]

    def find(self, uri: str, where: str) -> Path | None:
        """The first existing place of ``uri``; None (and the places in ``self.tried``)."""
        self.uri, self.tried = uri, []
        for p in self.places(uri):
            real = Path(os.path.realpath(p))
            why = None if self.root is None else leaves_root(real, self.root)
            if why is not None:
                self.tried.append(f"{p} ({why.removeprefix('it ')}: not tried)")
            elif real.is_file():
                return real
            else:
                self.tried.append(str(p))
        return None


def _geometry(doc: _Doc, el: ET.Element, where: str) -> list[tuple[trimesh.Trimesh, tuple | None]]:
    """The meshes of a <visual> or <collision> (with their own colours), or None parts
    when a mesh file is missing (``doc.tried`` says where it was looked for)."""
    g = el.find("geometry")
    shape = None if g is None else next(iter(g), None)
    if shape is None:
        raise doc.fail(where, f"<{el.tag}> needs a <geometry> with a mesh, box, cylinder or sphere")
    w = f"{where} {shape.tag}"
    if shape.tag == "mesh":
        uri = shape.get("filename")
        if not uri:
            raise doc.fail(where, "<mesh> needs a filename")
        scale = doc.floats(shape, "scale", 3, (1.0, 1.0, 1.0), where)
        found = doc.find(uri, where)
        if found is None:
            return []
        return load_mesh(found, scale=scale, what=f"{doc.what}: {where}")  # type: ignore[arg-type]
    sizes = {
        "box": ("size", 3),
        "cylinder": ("radius", 1),
        "sphere": ("radius", 1),
        "capsule": ("radius", 1),
    }
    if shape.tag not in sizes:
        raise doc.fail(where, f"unknown geometry <{shape.tag}>; known: mesh, {', '.join(sizes)}")
    attr, n = sizes[shape.tag]
    size = doc.floats(shape, attr, n, (), w)
    if shape.tag in ("cylinder", "capsule"):
        size += doc.floats(shape, "length", 1, (), w)
    return [(primitive(shape.tag, size=size, what=f"{doc.what}: {w}"), None)]


def _shapes(doc: _Doc, link: ET.Element, where: str) -> list[Shape]:
    """A link's collision shapes (hidden, colliding) and visual shapes (module doc)."""
    shapes: list[Shape] = []
    for k, el in enumerate(link.findall("collision")):
        w = f"{where} collision {k + 1}"
        parts = _geometry(doc, el, w)
        if not parts:
            raise doc.fail(w, f"mesh file '{doc.uri}' not found; tried: {'; '.join(doc.tried)}")
        T = doc.origin(el, w)
        for mesh, _ in parts:
            pieces = ()  # convex, or its hull when asked (concavity None)
            if doc.concavity is not None and not is_convex(mesh):
                pieces = tuple(decompose(mesh, doc.concavity, label=where))
            shapes.append(Shape(mesh, T, None, visible=False, pieces=pieces))
    collisions = list(shapes)
    for k, el in enumerate(link.findall("visual")):
        w = f"{where} visual {k + 1}"
        colour = doc.colour(el.find("material"), w)
        parts = _geometry(doc, el, w)
        if not parts:
            if not collisions:
                raise doc.fail(w, f"mesh file '{doc.uri}' not found; tried: {'; '.join(doc.tried)}")
            warnings.warn(
                f"{doc.what}: {w}: mesh file '{doc.uri}' not found (tried: {'; '.join(doc.tried)}); "
                "the link is drawn with its collision geometry instead",
                stacklevel=4,
            )
            shapes.extend(Shape(s.mesh, s.transform, colour) for s in collisions)
            continue
        T = doc.origin(el, w)
        shapes.extend(Shape(mesh, T, colour or own) for mesh, own in parts)
    return shapes


def _joint(doc: _Doc, el: ET.Element, links: Mapping[str, ET.Element]) -> tuple[str, str, TreeLink]:
    """(parent, child, the child's TreeLink without shapes) of a <joint>."""
    name = el.get("name")
    where = doc.at(el, "joint", name)
    if not name:
        raise doc.fail(where, "a <joint> needs a name")
    kind = el.get("type", "")
    ends = []
    for end in ("parent", "child"):
        e = el.find(end)
        link = None if e is None else e.get("link")
        if not link:
            raise doc.fail(where, f"needs <{end} link=...>")
        if link not in links:
            raise doc.fail(where, f"{end} link '{link}' does not exist; links: {', '.join(links)}")
        ends.append(link)
    origin = doc.origin(el, where)
    tl = TreeLink(ends[1], ends[0], origin, what=where)
    if kind == "fixed":
        return ends[0], ends[1], tl
    if kind in _UNSUPPORTED:
        tl.unsupported = (
            f"a {kind} joint cannot be in a robot's chain (revolute, continuous, prismatic)"
        )
        return ends[0], ends[1], tl
    if kind not in _KINDS:
        raise doc.fail(
            where,
            f"unknown joint type {kind!r}; URDF types: revolute, continuous, "
            "prismatic, fixed, floating, planar",
        )
    if el.find("mimic") is not None:
        tl.unsupported = "a mimic joint cannot be in a robot's chain"
    axis = doc.floats(el.find("axis"), "xyz", 3, (1.0, 0.0, 0.0), where)
    lim = el.find("limit")
    if kind == "continuous":
        lo, hi = -CONTINUOUS_LIMIT, CONTINUOUS_LIMIT
    elif lim is None:
        raise doc.fail(where, f"a {kind} joint needs <limit lower=... upper=... velocity=...>")
    else:
        (lo,), (hi,) = (doc.floats(lim, a, 1, (0.0,), where) for a in ("lower", "upper"))
        if not lo < hi:
            raise doc.fail(where, f"limit lower {lo} must be below upper {hi}")
    (speed,) = doc.floats(lim, "velocity", 1, (0.0,), where)
    try:
        tl.joint = Joint(
            name, origin, axis, _KINDS[kind], limits=(lo, hi), **joint_speeds(_KINDS[kind], speed)
        )
    except WorkcellError as exc:
        raise doc.fail(where, str(exc)) from exc
    return ends[0], ends[1], tl


def _tree(doc: _Doc, robot: ET.Element) -> dict[str, TreeLink]:
    """Every link of the file as a TreeLink (shapes included), loops refused."""
    for m in robot.findall("material"):
        c = doc.colour(m, doc.at(m, "material", m.get("name")))
        if m.get("name") and c is not None:
            doc.materials[m.get("name", "")] = c
    elements: dict[str, ET.Element] = {}
    for el in robot.findall("link"):
        name = el.get("name")
        if not name:
            raise doc.fail(doc.at(el, "link"), "a <link> needs a name")
        if name in elements:
            raise doc.fail(doc.at(el, "link", name), "another link has this name")
        elements[name] = el
    if not elements:
        raise ModelError(f"{doc.what}: the robot has no <link>")
    tree = {n: TreeLink(n, None, what=doc.at(el, "link", n)) for n, el in elements.items()}
    by_child: dict[str, str] = {}
    for el in robot.findall("joint"):
        _, child, tl = _joint(doc, el, elements)
        if child in by_child:
            raise doc.fail(
                tl.what,
                f"link '{child}' is already the child of joint "
                f"'{by_child[child]}'; a link has one parent",
            )
        by_child[child] = el.get("name", "")
        tree[child] = tl
    for start in tree:  # every walk up must end at a root
        seen, n = [], start
        while n is not None:
            if n in seen:
                loop = seen[seen.index(n) :]
                raise ModelError(
                    f"{doc.what}: the joints {', '.join(by_child[x] for x in loop)} "
                    f"form a loop (links {' -> '.join(loop)})"
                )
            seen.append(n)
            n = tree[n].parent
    for n, el in elements.items():
        if doc.geometry:
            tree[n].shapes = _shapes(doc, el, doc.at(el, "link", n))
    return tree


def from_urdf(
    path: str | os.PathLike,
    *,
    packages: Mapping[str, str | os.PathLike] | None = None,
    search: Sequence[str | os.PathLike] = (),
    base_link: str | None = None,
    tip_link: str | None = None,
    name: str | None = None,
    gripper: bool = True,
    geometry: bool = True,
    concavity: float | None = DEFAULT_CONCAVITY,
    root: str | os.PathLike | None = None,
) -> Robot:
    """The robot of URDF file ``path``: the chain from ``base_link`` to ``tip_link`` (see
    the module doc for the defaults, what is read, and how mesh files are found).

    ``packages`` maps ROS package names to folders; ``search`` lists folders where
    ``package://PKG/REL`` is looked up as ``REL``; ``name`` names the robot (default: the
    file's robot name); ``gripper`` False leaves a parallel gripper of the file out;
    ``geometry`` False reads the kinematics only (no mesh is read: fast, invisible);
    ``concavity``: the CoACD error bound for non-convex collision meshes (None: collide
    as their convex hulls, as MuJoCo's own URDF import does; a decomposition takes
    seconds to minutes per mesh the first time, then comes from the cache); ``root``: no
    file outside this folder is read (meshes included). ModelError naming the element
    for a file that cannot be used.
    """
    p = Path(path)
    data = read_bytes(p, what="URDF file", error=ModelError)
    pk = {str(k): Path(os.path.abspath(v)) for k, v in (packages or {}).items()}
    sr = [Path(os.path.abspath(s)) for s in search]
    doc = _Doc(Path(os.path.abspath(p)), {}, pk, sr, None if root is None else Path(root))
    doc.geometry, doc.concavity = bool(geometry), concavity
    top, doc.lines = parse_xml(data, doc.what)
    if top.tag != "robot":
        raise ModelError(f"{doc.what}: the top element is <{top.tag}>, not <robot>")
    tree = _tree(doc, top)
    roots = [n for n, t in tree.items() if t.parent is None]
    given_base = base_link
    if base_link is None:
        if len(roots) != 1:
            raise ModelError(
                f"{doc.what}: links {', '.join(roots)} have no parent; "
                "name the base with base_link="
            )
        base_link = roots[0]
    for arg, value in (("base_link", base_link), ("tip_link", tip_link)):
        if value is not None and value not in tree:
            raise ModelError(f"{doc.what}: {arg} '{value}' is not a link; links: {', '.join(tree)}")
    tip = tip_link
    if tip is None:
        tip = "tool0" if "tool0" in tree and _below(tree, "tool0", base_link) else None
    options = {
        "packages": {k: str(v) for k, v in pk.items()},
        "search": [str(s) for s in sr],
        "base_link": given_base,
        "tip_link": tip_link,
        "name": name,
        "gripper": gripper,
        "geometry": geometry,
        "concavity": concavity,
    }
    robot_name = name or top.get("name") or p.stem
    return build_robot(
        tree,
        base=base_link,
        tip=tip,
        name=robot_name,
        source=f"URDF file '{p.name}'",
        file=RobotFile("urdf", str(doc.path), sha256(data), options),
        keep_gripper=gripper,
        what=doc.what,
    )


def _below(tree: Mapping[str, TreeLink], name: str | None, ancestor: str) -> bool:
    while name is not None:
        if name == ancestor:
            return True
        name = tree[name].parent
    return False
