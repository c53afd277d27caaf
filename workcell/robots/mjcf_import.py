"""MJCF import: :func:`from_mjcf` reads a MuJoCo model of an arm into a :class:`Robot`.

MuJoCo itself parses and compiles the file (``MjSpec.from_file``, then ``compile``:
defaults classes, includes, ``fromto``, mesh scaling and angle units are MuJoCo's own),
and the robot is read off the compiled model (:mod:`workcell.robots.tree` builds it):

- the chain of hinge and slide joints from ``base_body`` (default: the parent of the
  first body that has a joint; ``world`` when that is the world) to ``tip_body`` (or the
  body of ``tool_site``; default: the end of the longest chain); ``fk(q)`` is the tool
  site (else the tip body; with neither named, a gripper the file has keeps its TCP as
  the tool) in the base body's frame. Bodies without joints fold into the next joint's
  origin; a body with a ball or free joint, or with several joints, cannot be in the
  chain. Joint values are MuJoCo's ``qpos`` (a joint's ``ref`` is accounted for);
- limits from ``range`` (an unlimited hinge gets +-2 pi rad, an unlimited slide is
  refused); MJCF states no speeds: :func:`workcell.robots.meshfile.joint_speeds`' defaults
  (1 rad/s, 0.25 m/s, acceleration = speed / 0.25 s, jerk = acceleration / 0.05 s);
- named poses from ``<keyframe>`` keys (an unnamed key is ``key{k}``);
- geometry from the geoms (meshes as MuJoCo compiled them; boxes, spheres, capsules,
  cylinders and ellipsoids as closed meshes; planes, height fields and SDFs are left
  out) with their material's or own colour: a geom in groups 0-2 is drawn, one with
  ``contype`` or ``conaffinity`` collides (a mesh as its convex hull, as in MuJoCo); the
  file's inertias are not used (the cell gives links the mass of their meshes);
- the file's own parallel gripper (two opposed finger slides on a palm fixed to the last
  link: the Panda's hand) is kept as the robot's gripper (``gripper=False`` leaves it
  out, so :func:`~workcell.robots.parallel_gripper` can be attached); actuators,
  tendons and equalities are not read.

The file and every file it names are read by us, found as MuJoCo finds them, and given
to MuJoCo in memory (:mod:`workcell.robots.mjcf_files`): regular files only, together
within ``max_file_bytes``, meshes within ``max_facets``; with ``root`` (a server's
folder), every one of them must lie inside it. Units: metres, radians, seconds.
"""

from __future__ import annotations

import os
from pathlib import Path

import mujoco
import numpy as np
import trimesh

from workcell import limits
from workcell.errors import ModelError, WorkcellError
from workcell.robots.chain import Joint
from workcell.robots.meshfile import joint_speeds, primitive, sha256
from workcell.robots.mjcf_files import read_mjcf, spec_from_files
from workcell.robots.robot import Robot, RobotFile
from workcell.robots.tree import Shape, TreeLink, build_robot
from workcell.robots.urdf import CONTINUOUS_LIMIT
from workcell.spatial import pose_from_pos_quat

__all__ = ["from_mjcf"]

_T = mujoco.mjtGeom
_HINGE, _SLIDE, _BALL = (
    int(mujoco.mjtJoint.mjJNT_HINGE),
    int(mujoco.mjtJoint.mjJNT_SLIDE),
    int(mujoco.mjtJoint.mjJNT_BALL),
)
_DEFAULT_RGBA = (0.5, 0.5, 0.5, 1.0)


def _spec(path: Path, root: Path | None) -> tuple[mujoco.MjModel, bytes]:
    """MuJoCo's compile of the file (and the file's bytes), within the work limits; every
    file it names read by us, confined to ``root`` (:mod:`workcell.robots.mjcf_files`)."""
    what = f"MJCF file '{path}'"
    files = read_mjcf(path, root)
    spec = spec_from_files(files, what)
    try:
        model = spec.compile()
    except ValueError as exc:
        raise ModelError(f"{what}: MuJoCo cannot compile it: {files.explain(str(exc))}") from None
    for i in range(model.nmesh):
        limits.check("max_facets", int(model.mesh_facenum[i]), f"{what}: mesh {i}")
    sizes = [np.abs(a).max(initial=0.0) for a in (model.body_pos, model.geom_size, model.site_pos)]
    limits.check("max_coordinate", float(max(sizes)), f"{what}: a body, geom or site")
    return model, files.data


def _geom_mesh(m: mujoco.MjModel, g: int) -> trimesh.Trimesh | None:
    """Geom g as a closed mesh in its own frame (None for planes, height fields, SDFs)."""
    t, s = int(m.geom_type[g]), m.geom_size[g]
    what = f"geom {m.geom(g).name or g}"
    if t == int(_T.mjGEOM_MESH):
        i = m.geom_dataid[g]
        v0, nv, f0, nf = m.mesh_vertadr[i], m.mesh_vertnum[i], m.mesh_faceadr[i], m.mesh_facenum[i]
        return trimesh.Trimesh(m.mesh_vert[v0 : v0 + nv].copy(), m.mesh_face[f0 : f0 + nf].copy())
    sizes = {
        int(_T.mjGEOM_BOX): ("box", 2 * s),
        int(_T.mjGEOM_SPHERE): ("sphere", s[:1]),
        int(_T.mjGEOM_CAPSULE): ("capsule", (s[0], 2 * s[1])),
        int(_T.mjGEOM_CYLINDER): ("cylinder", (s[0], 2 * s[1])),
        int(_T.mjGEOM_ELLIPSOID): ("ellipsoid", s),
    }
    if t not in sizes:
        return None
    kind, size = sizes[t]
    return primitive(kind, size=tuple(float(v) for v in size), what=what)


def _shapes(m: mujoco.MjModel, body: int) -> list[Shape]:
    out = []
    for g in np.flatnonzero(m.geom_bodyid == body):
        visible = int(m.geom_group[g]) <= 2
        collides = bool(m.geom_contype[g] or m.geom_conaffinity[g])
        if not (visible or collides):
            continue
        mesh = _geom_mesh(m, int(g))
        if mesh is None:
            continue
        rgba = tuple(float(v) for v in m.geom_rgba[g])
        if m.geom_matid[g] >= 0 and np.allclose(rgba, _DEFAULT_RGBA):
            rgba = tuple(float(v) for v in m.mat_rgba[m.geom_matid[g]])
        T = pose_from_pos_quat(m.geom_pos[g], m.geom_quat[g])
        out.append(Shape(mesh, T, rgba, visible=visible, pieces=() if collides else None))
    return out


def _name(m: mujoco.MjModel, kind: str, i: int) -> str:
    obj = m.body(i) if kind == "body" else m.joint(i)
    return obj.name or f"{kind}{i}"


def _link(m: mujoco.MjModel, b: int, names: list[str], geometry: bool) -> TreeLink:
    """Body b as a TreeLink: its pose at q = 0 in its parent's frame and its joint."""
    origin = pose_from_pos_quat(m.body_pos[b], m.body_quat[b])
    parent = None if b == 0 else names[m.body_parentid[b]]
    link = TreeLink(names[b], parent, origin, what=f"body '{names[b]}'")
    link.shapes = _shapes(m, b) if geometry else []
    n = int(m.body_jntnum[b])
    if n == 0:
        return link
    if n > 1:
        link.unsupported = f"it has {n} joints; a chain body has one hinge or slide"
        return link
    j = int(m.body_jntadr[b])
    jname = _name(m, "joint", j)
    if int(m.jnt_type[j]) not in (_HINGE, _SLIDE):
        kind = "ball" if int(m.jnt_type[j]) == _BALL else "free"
        link.unsupported = f"its joint '{jname}' is a {kind} joint; a chain has hinges and slides"
        return link
    kind = "revolute" if int(m.jnt_type[j]) == _HINGE else "prismatic"
    if m.jnt_limited[j]:
        lo, hi = (float(v) for v in m.jnt_range[j])
    elif kind == "revolute":
        lo, hi = -CONTINUOUS_LIMIT, CONTINUOUS_LIMIT
    else:
        link.unsupported = f"slide joint '{jname}' has no range; give it one"
        return link
    ref = float(m.qpos0[m.jnt_qposadr[j]])
    try:
        joint = Joint(
            jname,
            np.eye(4),
            m.jnt_axis[j].copy(),
            kind,
            limits=(lo, hi),
            axis_point=m.jnt_pos[j].copy(),
            **joint_speeds(kind, None),
        )
        # the body's pose is the pose at qpos0 = ref: at q = 0 it is turned back by ref
        link.joint = joint
        link.origin = origin @ joint.motion(-ref)
    except WorkcellError as exc:
        raise ModelError(f"body '{names[b]}': joint '{jname}': {exc}") from exc
    return link


def from_mjcf(
    path: str | os.PathLike,
    *,
    base_body: str | None = None,
    tip_body: str | None = None,
    tool_site: str | None = None,
    name: str | None = None,
    gripper: bool = True,
    geometry: bool = True,
    root: str | os.PathLike | None = None,
) -> Robot:
    """The robot of MJCF file ``path``: the hinge/slide chain from ``base_body`` to
    ``tip_body`` (or ``tool_site``'s body), see the module doc for the defaults and what
    is read. ``name`` names the robot (default: the model's name); ``gripper`` False
    leaves the file's parallel gripper out; ``geometry`` False reads no geoms; ``root``:
    no file outside this folder is read. ModelError for a file that cannot be used.
    """
    p = Path(os.path.abspath(path))
    what = f"MJCF file '{path}'"
    m, data = _spec(p, None if root is None else Path(root))
    names = [_name(m, "body", b) for b in range(m.nbody)]
    names[0] = "world"
    tree = {names[b]: _link(m, b, names, geometry) for b in range(m.nbody)}
    if len(tree) != m.nbody:
        raise ModelError(f"{what}: body names repeat; name the bodies uniquely")

    def body(arg: str, value: str) -> str:
        if value not in tree:
            raise ModelError(f"{what}: {arg} '{value}' is not a body; bodies: {', '.join(names)}")
        return value

    tool = None
    tip = None if tip_body is None else body("tip_body", tip_body)
    if tool_site is not None:
        known = [m.site(i).name for i in range(m.nsite)]
        if tool_site not in known:
            raise ModelError(
                f"{what}: tool_site '{tool_site}' is not a site; sites: "
                f"{', '.join(n for n in known if n) or 'none'}"
            )
        s = m.site(tool_site).id
        on = names[m.site_bodyid[s]]
        if tip is not None and tip != on:
            raise ModelError(
                f"{what}: tool_site '{tool_site}' is on body '{on}', not on tip_body '{tip}'"
            )
        tip, tool = on, pose_from_pos_quat(m.site_pos[s], m.site_quat[s])
    if base_body is None:
        jointed = np.flatnonzero(m.body_jntnum > 0)
        if not len(jointed):
            raise ModelError(f"{what}: no body has a joint")
        base = names[m.body_parentid[jointed[0]]]
    else:
        base = body("base_body", base_body)
    poses = {}
    for k in range(m.nkey):
        qpos = m.key_qpos[k]
        values = {
            _name(m, "joint", j): float(qpos[m.jnt_qposadr[j]])
            for j in range(m.njnt)
            if int(m.jnt_type[j]) in (_HINGE, _SLIDE)
        }
        poses[m.key(k).name or f"key{k}"] = values
    options = {
        "base_body": base_body,
        "tip_body": tip_body,
        "tool_site": tool_site,
        "name": name,
        "gripper": gripper,
        "geometry": geometry,
    }
    model_name = bytes(m.names[: m.names.index(b"\0")]).decode(errors="replace")
    return build_robot(
        tree,
        base=base,
        tip=tip,
        tool=tool,
        name=name or model_name or p.stem,
        source=f"MJCF file '{p.name}'" + (f", tool site {tool_site}" if tool_site else ""),
        file=RobotFile("mjcf", str(p), sha256(data), options),
        poses=poses,
        keep_gripper=gripper,
        what=what,
    )
