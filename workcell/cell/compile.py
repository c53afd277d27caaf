"""Compile a :class:`Workcell` to MuJoCo through MjSpec, and export it as MJCF + STL meshes.

Contents of the compiled model (all names MJCF-safe, never '/'):

- ``ground``: a plane at z = 0;
- static part ``P``: geoms of the worldbody at the part's pose: ``P.visual`` (the exact
  mesh, ``inertia="exact"``, no contacts, group 2) and ``P.col{i}`` (convex collision
  pieces, group 3; see :func:`workcell.meshgeoms.collision_pieces`: a convex part is its
  own piece, a non-convex one is split by CoACD within the error bound ``concavity``);
- movable part ``P``: a body ``P`` at its pose with a free joint ``P.free``, one visual
  mesh geom ``P.visual`` carrying the mass (exact inertia at the part's density) and
  collision geoms ``P.col{i}`` with density 0;
- robot ``R``: :func:`workcell.robots.mjcf.robot_spec` attached with prefix ``"R."``;
  its link 0 body sits at ``base @ robot.base`` in the world;
- one weld equality ``grasp.R.P`` per (robot with gripper, movable part), inactive,
  body1 = the gripper body, body2 = the part, with explicit ``data`` (anchor 0, relpose
  identity, torquescale 1; the simulator writes the captured relative pose on grasp)
  and a stiff ``solref`` (0.004, 1);
- camera ``C``: an MJCF camera at the position, turned so its -z axis points to the target;
- physics settings, which the kinematic simulator ignores: the robots' position actuators
  (one per arm joint and finger slide, named as the joint: ``puma_1.j1``,
  ``puma_1.gripper.left_slide``), ``gravcomp`` on robot bodies and joint armature (see
  :mod:`workcell.robots.mjcf`), ``timestep`` (s), the ``implicitfast`` integrator (it
  integrates the servos' damping implicitly, stable at the default timestep) and stiff
  contacts (every collision geom, the ground included, has ``solref`` =
  :data:`~workcell.meshgeoms.CONTACT_SOLREF` and ``solimp`` =
  :data:`~workcell.meshgeoms.CONTACT_SOLIMP`: with MuJoCo's default contacts a resting
  part sinks ~0.2 mm and a faceted one creeps ~0.2 mm/s; these give ~0.002 mm and none),
  so the exported file plays in MuJoCo's viewer with its actuators. Each actuator's bias
  holds its joint's initial value q0 at ctrl 0 (``biasprm[0] = kp q0``: force =
  ``kp (ctrl + q0 - q) - kv qdot``, ctrl range = joint range - q0), so a freshly loaded
  export (ctrl = 0, in the viewer or a new ``MjData``) holds the initial pose instead of
  swinging the arms to q = 0; ``ctrl = q - q0`` drives a joint to q. The keyframe
  ``initial`` is the initial pose with ctrl 0. A comment at the top of the XML says so.

Initial joint values live in ``qpos0`` through each joint's ``ref``: the link bodies are
written at their pose for the initial q (body frame ``origin @ M(q0)``, the joint's motion) and
``ref = q0``, so MuJoCo's joint value is the robot's joint value (``qpos = q`` gives
``fk(q)``) and ``qpos0``, the XML's default pose and ``mj_resetData`` are the initial
configuration. The exported XML contains no ``<frame>`` element (dm_control 1.0.50's
schema lacks it): robots are attached through an identity frame, which is not written.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from workcell.cell.workcell import Workcell
from workcell.checks import is_finite_number
from workcell.decompose import DEFAULT_CONCAVITY
from workcell.errors import GeometryError, ModelError
from workcell.files import check_folder, write_files
from workcell.meshgeoms import (
    CONTACT_SOLIMP,
    CONTACT_SOLREF,
    MESHDIR,
    MeshAssets,
    add_mesh_geoms,
    collision_meshes,
    collision_pieces,
    decompose_ahead,
)
from workcell.modeller.model import Model
from workcell.robots.mjcf import (
    body_name,
    finger_joint_names,
    gripper_body_name,
    joint_name,
    robot_spec,
    spec_to_xml,
)
from workcell.spatial import pos_quat_from_pose, pose_from_pos_quat

__all__ = [
    "DEFAULT_TIMESTEP",
    "GRASP_SOLREF",
    "GROUND",
    "INITIAL_KEY",
    "WELD_DATA",
    "CompiledCell",
    "compile_cell",
    "export_cell",
    "subtree_bodies",
]

GROUND = "ground"
INITIAL_KEY = "initial"
DEFAULT_TIMESTEP = 0.002  # s: MuJoCo's default; the grasp weld's solref needs <= 0.002
GRASP_SOLREF = (0.004, 1.0)
# anchor (3) | relpos (3) | relquat wxyz (4) | torquescale | flag (0: relpose given)
WELD_DATA = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0)


@dataclass
class CompiledCell:
    """A compiled cell: the MjSpec, the MjModel and the names of what the simulator needs.

    Maps by cell name: ``robot_prefixes`` ("puma_1" -> "puma_1."), ``joint_names``
    (arm joints in DH order), ``finger_joints`` (left, right slides; robots with a
    gripper), ``tool_sites``, ``gripper_bodies``, ``part_bodies`` (movable parts),
    ``free_joints`` (movable parts), ``welds`` ((robot, part) -> equality name),
    ``cameras``, ``actuators`` (the robot's position actuators: arm joints in DH order,
    then the fingers), ``holds`` (joint name -> the joint value its actuator holds at
    ctrl 0: the initial value), ``initial_ctrl`` (joint name -> the ``initial`` keyframe's
    ctrl: 0). ``assets`` holds the mesh files (name -> STL bytes).
    """

    spec: mujoco.MjSpec
    model: mujoco.MjModel
    robot_prefixes: dict[str, str] = field(default_factory=dict)
    joint_names: dict[str, tuple[str, ...]] = field(default_factory=dict)
    finger_joints: dict[str, tuple[str, str]] = field(default_factory=dict)
    tool_sites: dict[str, str] = field(default_factory=dict)
    gripper_bodies: dict[str, str] = field(default_factory=dict)
    part_bodies: dict[str, str] = field(default_factory=dict)
    free_joints: dict[str, str] = field(default_factory=dict)
    welds: dict[tuple[str, str], str] = field(default_factory=dict)
    cameras: dict[str, str] = field(default_factory=dict)
    actuators: dict[str, tuple[str, ...]] = field(default_factory=dict)
    initial_ctrl: dict[str, float] = field(default_factory=dict)
    holds: dict[str, float] = field(default_factory=dict)
    assets: Mapping[str, bytes] = field(default_factory=dict)


def _add_part_geoms(
    parent: mujoco.MjsBody,
    model: Model,
    name: str,
    entity: tuple[str, str],
    colour: tuple[float, ...],
    pose: np.ndarray,
    density: float,
    reg: MeshAssets,
    concavity: float,
) -> None:
    """Mesh assets of a part, its visual (mass-carrying) geoms and collision geoms in ``parent``.

    An object gets one visual mesh per placed block (each a closed solid; overlapping
    blocks would make one concatenated mesh that MuJoCo refuses); its mass is the sum of
    its blocks' masses.
    """
    if entity[0] == "object" and len(parts := model.world_parts(entity)) > 1:
        visuals = [(f"{name}.mesh{k}", f"{name}.visual{k}", p.mesh) for k, p in enumerate(parts)]
    else:
        visuals = [(f"{name}.mesh", f"{name}.visual", model.world_mesh(entity))]
    if any(len(mesh.faces) == 0 for _, _, mesh in visuals):  # e.g. an operand moved away
        raise GeometryError(f"part '{name}': {entity[0]} '{entity[1]}' is empty (no faces)")
    meshes = [reg.add(vis, mesh) for vis, _, mesh in visuals]
    col = collision_pieces(model, entity, concavity)
    cols = meshes if col.convex else collision_meshes(reg, name, col.pieces, False, meshes[0])
    pos, quat = pos_quat_from_pose(pose)
    add_mesh_geoms(
        parent,
        [(geom, mesh) for (_, geom, _), mesh in zip(visuals, meshes, strict=True)],
        cols,
        collision_prefix=name,
        pos=pos,
        quat=quat,
        density=density,
        rgba=list(colour),
    )


def _set_initial_q(child: mujoco.MjSpec, robot, q: np.ndarray) -> None:  # noqa: ANN001
    """Write the link bodies at q and set each joint's ``ref`` to q (so qpos0 = q)."""
    for i, jt in enumerate(robot.joints):
        body = child.body(body_name("", i + 1))
        T = pose_from_pos_quat(body.pos, body.quat) @ jt.motion(float(q[i]))
        body.pos, body.quat = pos_quat_from_pose(T)
        child.joint(joint_name(robot, "", i)).ref = float(q[i])


def _comment(cell: Workcell) -> str:
    """The note at the top of the exported XML: how its actuators hold the initial pose
    (no '--' in it: XML comments may not hold one)."""
    text = (
        f" workcell cell '{cell.name}'. Every robot joint and finger has a position actuator "
        "named as its joint whose ctrl is the joint's offset (rad, m) from its initial "
        "value (the joint's ref): force = kp (ctrl + ref - q) - kv qdot. A freshly loaded "
        "model (ctrl 0, in MuJoCo's viewer or a new MjData) holds the initial pose; to send "
        "joint j to q, set ctrl = q - ref. Keyframe 'initial' is that pose at rest. To view "
        "it, run python -m mujoco.viewer and drop this file on its window. "
    )
    while "--" in text:
        text = text.replace("--", "- -")
    return text


def _build(cell: Workcell, timestep: float, concavity: float) -> CompiledCell:
    if not (is_finite_number(timestep) and timestep > 0):
        raise GeometryError(f"timestep must be a finite number of seconds > 0, got {timestep!r}")
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    spec.option.timestep = float(timestep)
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.compiler.meshdir = MESHDIR
    spec.modelname = cell.name
    reg = MeshAssets(spec)
    assets = reg.assets
    out = CompiledCell(spec=spec, model=None)  # type: ignore[arg-type]
    spec.worldbody.add_geom(
        name=GROUND,
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[0.0, 0.0, 0.05],
        rgba=[0.85, 0.85, 0.85, 1.0],
        solref=list(CONTACT_SOLREF),
        solimp=list(CONTACT_SOLIMP),
    )
    spec.worldbody.add_light(name="light", pos=[0, 0, 3], dir=[0, 0, -1])
    m = cell.model
    parts = [*cell.static_parts.values(), *cell.movable_parts.values()]
    decompose_ahead(m, [p.entity for p in parts], concavity)
    for p in cell.static_parts.values():
        _add_part_geoms(
            spec.worldbody, m, p.name, p.entity, p.colour, p.pose, 1000.0, reg, concavity
        )
    for p in cell.movable_parts.values():
        body = spec.worldbody.add_body(name=p.name)
        body.pos, body.quat = pos_quat_from_pose(p.pose)
        body.add_freejoint(name=f"{p.name}.free")
        _add_part_geoms(body, m, p.name, p.entity, p.colour, np.eye(4), p.density, reg, concavity)
        out.part_bodies[p.name] = p.name
        out.free_joints[p.name] = f"{p.name}.free"
    for r in cell.robots.values():
        prefix = f"{r.name}."
        child = robot_spec(r.robot, prefix="")
        link0 = child.body(body_name("", 0))
        link0.pos, link0.quat = pos_quat_from_pose(r.world_base)
        _set_initial_q(child, r.robot, r.q)
        for file, data in child.assets.items():  # attach prefixes mesh file names too
            assets[f"{prefix}{file}"] = data
        frame = spec.worldbody.add_frame()  # identity: not written to the XML
        spec.attach(child, frame=frame, prefix=prefix)
        out.robot_prefixes[r.name] = prefix
        out.joint_names[r.name] = tuple(joint_name(r.robot, prefix, i) for i in range(r.robot.dof))
        out.tool_sites[r.name] = f"{prefix}tool"
        out.actuators[r.name] = out.joint_names[r.name]  # actuators are named as their joints
        if r.robot.gripper is not None:
            out.gripper_bodies[r.name] = gripper_body_name(r.robot, prefix)
            out.finger_joints[r.name] = finger_joint_names(r.robot, prefix)
            out.actuators[r.name] += out.finger_joints[r.name]
    for rname, gbody in out.gripper_bodies.items():
        for pname, pbody in out.part_bodies.items():
            ename = f"grasp.{rname}.{pname}"
            spec.add_equality(
                name=ename,
                type=mujoco.mjtEq.mjEQ_WELD,
                objtype=mujoco.mjtObj.mjOBJ_BODY,
                name1=gbody,
                name2=pbody,
                active=False,
                data=list(WELD_DATA),
                solref=list(GRASP_SOLREF),
            )
            out.welds[(rname, pname)] = ename
    for c in cell.cameras.values():
        pos, quat = pos_quat_from_pose(c.pose())
        spec.worldbody.add_camera(name=c.name, pos=pos, quat=quat, fovy=c.fovy)
        out.cameras[c.name] = c.name
    targets = {}  # each actuator's initial target: its joint's initial value
    for r in cell.robots.values():
        targets.update(zip(out.joint_names[r.name], np.asarray(r.q, dtype=float), strict=True))
        if r.robot.gripper is not None:  # fingers open
            targets.update(dict.fromkeys(out.finger_joints[r.name], r.robot.gripper.finger_travel))
    for name, q0 in targets.items():  # hold q0 at ctrl = 0: force = kp (ctrl + q0 - q) - kv qdot
        act = spec.actuator(name)
        act.biasprm[0] = act.gainprm[0] * q0
        act.ctrlrange = [act.ctrlrange[0] - q0, act.ctrlrange[1] - q0]
    if targets:
        spec.add_key(name=INITIAL_KEY, ctrl=[0.0] * len(targets))
    out.initial_ctrl = dict.fromkeys(targets, 0.0)
    out.holds = targets
    spec.comment = _comment(cell)
    spec.assets = assets
    out.assets = assets
    return out


def compile_cell(
    cell: Workcell,
    *,
    timestep: float = DEFAULT_TIMESTEP,
    concavity: float = DEFAULT_CONCAVITY,
) -> CompiledCell:
    """Build the cell's MjSpec and compile it (a MuJoCo error raises GeometryError).

    ``timestep`` (s): the physics timestep written into the model (the kinematic
    simulator does not use it). ``concavity``: the error bound of the convex
    decomposition of non-convex parts (CoACD's threshold, in (0, 1]; see
    :mod:`workcell.decompose`).
    """
    out = _build(cell, timestep, concavity)
    try:
        out.model = m = out.spec.compile()
    except ValueError as exc:
        raise GeometryError(f"cell '{cell.name}' does not compile in MuJoCo: {exc}") from exc
    if m.nkey:  # the key was written in joint-name order: put it in actuator order
        ctrl = [out.initial_ctrl[m.joint(j).name] for j in m.actuator_trnid[:, 0]]
        out.spec.key(INITIAL_KEY).ctrl = ctrl
        m.key_ctrl[m.key(INITIAL_KEY).id] = ctrl
    return out


def export_cell(
    cell: Workcell,
    out_dir: str | os.PathLike,
    *,
    file_name: str | None = None,
    timestep: float = DEFAULT_TIMESTEP,
    concavity: float = DEFAULT_CONCAVITY,
) -> Path:
    """Write the cell as one MJCF file plus STL meshes in ``out_dir/meshes``; return the XML path.

    The XML (default ``"{cell.name}.xml"``) names its meshes relative to itself, so the
    folder loads from any working directory, in plain MuJoCo and dm_control. The cell is
    compiled (with the physics ``timestep``, s, and the decomposition bound ``concavity``)
    before anything is written; every file is written atomically.
    """
    check_folder(out_dir, error=ModelError)  # before the compiling
    compiled = compile_cell(cell, timestep=timestep, concavity=concavity)
    try:
        xml = spec_to_xml(compiled.spec)
    except ValueError as exc:
        raise GeometryError(f"cell '{cell.name}' cannot be written as MJCF: {exc}") from exc
    name = file_name or f"{cell.name}.xml"
    files = {f"{MESHDIR}/{file}": data for file, data in compiled.assets.items()}
    write_files(out_dir, {**files, name: xml.encode("utf-8")}, error=ModelError)
    return Path(out_dir) / name


def subtree_bodies(model: mujoco.MjModel, root: int) -> list[int]:
    """Ids of body ``root`` and every body below it, ascending (MuJoCo numbers a body
    after its parent, so one pass in id order finds them all)."""
    inside = {root}
    for b in range(root + 1, model.nbody):
        if int(model.body_parentid[b]) in inside:
            inside.add(b)
    return sorted(inside)
