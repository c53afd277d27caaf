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
  collide, a convex one as itself, any other as its hull when that fits it, else as
  CoACD pieces, all decomposed in one batch at the end of the read
  (:mod:`workcell.robots.linkshapes`: bounded in time, in child processes, cached);
- the file is read within ``max_file_bytes`` and parsed by expat with every entity
  declaration refused (:func:`workcell.robots.meshfile.parse_xml`).

Mesh files are looked for as :mod:`workcell.robots.urdf_doc` says (``packages``,
``search``, beside the URDF, the ROS layout, pybullet's ``package://meshes/...``). A mesh
file found nowhere never stops the import (the kinematics are all in the file): one
warning lists each such file as the URDF wrote it, the element, and every place tried; a
missing visual mesh is drawn with the link's collision geometry, anything else is
replaced by a capsule between the link's joint origins (:mod:`workcell.robots.standin`).
``strict=True`` makes a missing file a ModelError instead.

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
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np
import trimesh

from workcell.checks import is_finite_number
from workcell.errors import ModelError, WorkcellError
from workcell.files import read_bytes
from workcell.robots.chain import Joint
from workcell.robots.linkshapes import LINK_CONCAVITY, LINK_SECONDS, LinkBatch
from workcell.robots.meshfile import joint_speeds, parse_xml, sha256
from workcell.robots.robot import Robot, RobotFile
from workcell.robots.standin import capsule
from workcell.robots.tree import TreeLink, build_robot
from workcell.robots.urdf_doc import UrdfDoc

__all__ = ["CONTINUOUS_LIMIT", "from_urdf"]

CONTINUOUS_LIMIT = 2.0 * math.pi  # rad: +- this for a continuous joint
_KINDS = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic"}
_UNSUPPORTED = ("planar", "floating")


def _joint(
    doc: UrdfDoc, el: ET.Element, links: Mapping[str, ET.Element]
) -> tuple[str, str, TreeLink]:
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


def _tree(doc: UrdfDoc, robot: ET.Element) -> dict[str, TreeLink]:
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
    if not doc.geometry:
        return tree
    queued: dict[str, list[tuple[int, int]]] = {}
    for n, el in elements.items():
        doc.queued = []
        where = doc.at(el, "link", n)
        tree[n].shapes = doc.shapes(
            el, where, lambda n=n, el=el, w=where: _standin(doc, tree, n, el, w)
        )
        queued[n] = doc.queued
    pieces = doc.batch.run() if doc.batch is not None else []
    for n, entries in queued.items():  # the decomposed meshes get their pieces
        for k, j in entries:
            tree[n].shapes[k] = replace(tree[n].shapes[k], pieces=pieces[j])
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
    concavity: float | None = LINK_CONCAVITY,
    link_seconds: float = LINK_SECONDS,
    strict: bool = False,
    root: str | os.PathLike | None = None,
) -> Robot:
    """The robot of URDF file ``path``: the chain from ``base_link`` to ``tip_link`` (see
    the module doc for the defaults, what is read, and how mesh files are found).

    ``packages`` maps ROS package names to folders; ``search`` lists folders where
    ``package://PKG/REL`` is looked up as ``REL``; ``name`` names the robot (default: the
    file's robot name); ``gripper`` False leaves a parallel gripper of the file out;
    ``geometry`` False reads the kinematics only (no mesh is read: fast, invisible);
    ``concavity``: the CoACD error bound for non-convex collision meshes (None: collide
    as their convex hulls, as MuJoCo's own URDF import does; see
    :mod:`workcell.robots.linkshapes`: a mesh close to its hull is its hull, the others
    are decomposed together on all cores the first time, then come from the cache);
    ``link_seconds``: the wall time one link's decomposition may take (s) before the
    link collides as its hull, with a warning; ``strict``: a mesh file found nowhere is a
    ModelError (default: a warning, and the link's capsule stand-in); ``root``: no file
    outside this folder is read (meshes included). ModelError naming the element for a
    file that cannot be used.
    """
    p = Path(path)
    data = read_bytes(p, what="URDF file", error=ModelError)
    pk = {str(k): Path(os.path.abspath(v)) for k, v in (packages or {}).items()}
    sr = [Path(os.path.abspath(s)) for s in search]
    doc = UrdfDoc(
        Path(os.path.abspath(p)), {}, pk, sr, None if root is None else Path(root), strict=strict
    )
    doc.geometry = bool(geometry)
    top, doc.lines = parse_xml(data, doc.what)
    if top.tag != "robot":
        raise ModelError(f"{doc.what}: the top element is <{top.tag}>, not <robot>")
    robot_name = name or top.get("name") or p.stem
    if concavity is not None:
        doc.batch = LinkBatch(doc.what, robot_name, concavity, _seconds(link_seconds))
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
        "link_seconds": link_seconds,
        "strict": strict,
    }
    doc.missing.warn()
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


def _standin(
    doc: UrdfDoc, tree: Mapping[str, TreeLink], name: str, el: ET.Element, where: str
) -> trimesh.Trimesh:
    """The capsule stand-in of link ``name`` (:mod:`workcell.robots.standin`)."""
    ends = [t.origin[:3, 3] for t in tree.values() if t.parent == name]
    com, mass, inertia = doc.inertial(el, where)
    parent = float(np.linalg.norm(tree[name].origin[:3, 3]))
    return capsule(ends, com=com, mass=mass, inertia=inertia, parent_length=parent)


def _seconds(value: float) -> float:
    if not (is_finite_number(value) and value > 0):
        raise ModelError(f"link_seconds must be a number of seconds > 0, got {value!r}")
    return float(value)


def _below(tree: Mapping[str, TreeLink], name: str | None, ancestor: str) -> bool:
    while name is not None:
        if name == ancestor:
            return True
        name = tree[name].parent
    return False
