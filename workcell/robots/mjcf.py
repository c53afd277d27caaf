"""Robots to MuJoCo through MjSpec: one body per link, one joint per chain joint, link meshes, a tool site.

Body i is link frame i (:mod:`workcell.robots.chain`): it sits in body i-1 at the joint's
``origin`` and carries a hinge (revolute) or slide (prismatic) with the joint's ``axis``
and, for a hinge, ``pos`` = its ``axis_point``, so MuJoCo's body frame follows
``origin @ M(q)`` exactly. A solid that :class:`LinkGeometry` places in link frame i sits
in body i at its ``transform``. Names carry a prefix
(``"puma_1."``) so several robots can share a cell; ``/`` is never used (dm_control
reserves it).

Link solids (``robot.geometry``) become, per solid, one visual mesh geom (the exact mesh,
``inertia="exact"``, ``density`` kg/m^3, group 2, no contacts) and convex collision geoms
(group 3, density 0; see :mod:`workcell.meshgeoms` for the pieces), so each body's
mass and inertia are those of its exact meshes. A mesh entry (``LinkGeometry.mesh``, e.g.
from a robot description's file) gives its mesh as the visual geom and its own convex
``collision`` pieces (else its hull; none when ``collides`` is False) as the collision
geoms; an open mesh (a DAE surface) carries the mass of its convex hull, a flat one none
(:mod:`workcell.robots.mjcf_geoms`).
A body without mass-carrying solids keeps a small placeholder inertia. A gripper read
from a robot file has mesh parts, placed the same way. A gripper (``robot.gripper``) is a body ``{prefix}{gripper}`` fixed to
the last link at its mount, with the palm, and two finger bodies on slide joints
``{prefix}{gripper}.left_slide`` / ``.right_slide`` (axis +y / -y of the gripper frame,
range [0, finger_travel] m, q = 0 closed, q = finger_travel fully open, which is the
joints' reference and initial value, as the solids are drawn). The tool site sits at
``robot.tool``. Bodies on links up to two apart get ``<exclude>`` pairs (the gripper's
bodies count as the last link).

For physics (the kinematic simulator ignores all of this): collision geoms have stiff
contacts (``solref`` and ``solimp`` of :mod:`workcell.meshgeoms`); every
body has ``gravcomp="1"`` (the arm carries its own weight, as a real arm's
gravity-compensating servos do; a payload is not compensated); every arm joint has an
``armature`` (the reflected inertia of a geared motor's rotor, kg m^2 or kg;
:data:`ARMATURE`); and every arm joint and finger slide has a position actuator of the
joint's name (``{prefix}j1`` ...,
``{prefix}{gripper}.left_slide`` ...): ``ctrl`` = target joint value, ctrl range = joint
range, force ``kp (ctrl - q) - kv qdot`` without force limits (the peak forces a run
needs are reported by the physics mode instead). The gains give each joint on its own a
critically damped servo of natural frequency :data:`SERVO_FREQUENCY`:
``kp = I w^2``, ``kv = 2 zeta I w`` with I the joint's diagonal entry of the mass matrix
(armature included) at q = 0.

Mesh assets are binary STL files named ``{prefix}{block}.stl``, held in ``spec.assets``;
:func:`export_robot` writes them beside the XML (``meshdir="meshes"``, relative), at full
precision (:func:`spec_to_xml`, :mod:`workcell.robots.mjcf_xml`).
"""

from __future__ import annotations

import os
from pathlib import Path

import mujoco
import numpy as np

from workcell.errors import GeometryError, ModelError
from workcell.files import write_files
from workcell.meshgeoms import MESHDIR, MeshAssets
from workcell.robots.gripper import GripperPart
from workcell.robots.mjcf_geoms import add_mesh, add_solid
from workcell.robots.mjcf_xml import spec_to_xml
from workcell.robots.robot import Robot
from workcell.spatial import invert, pos_quat_from_pose

__all__ = [
    "ARMATURE",
    "ARM_DENSITY",
    "SERVO_DAMPING",
    "SERVO_FREQUENCY",
    "TOOL_SITE",
    "body_name",
    "export_robot",
    "finger_joint_names",
    "gripper_body_name",
    "joint_name",
    "kinematic_model",
    "robot_spec",
    "spec_to_xml",
]

TOOL_SITE = "tool"
ARM_DENSITY = 2700.0  # kg/m^3, aluminium
ARMATURE = 0.02  # kg m^2 (revolute) or kg (prismatic): a small geared motor's reflected rotor
SERVO_FREQUENCY = 15.0  # Hz: natural frequency of each joint's position servo
SERVO_DAMPING = 1.0  # damping ratio of each joint's position servo


def body_name(prefix: str, i: int) -> str:
    """Name of link i's body (0 = base)."""
    return f"{prefix}link{i}"


def joint_name(robot: Robot, prefix: str, i: int) -> str:
    """MJCF name of joint i (0-based)."""
    return f"{prefix}{robot.joints[i].name}"


def gripper_body_name(robot: Robot, prefix: str = "") -> str:
    """Name of the gripper's (palm) body; ModelError when the robot has no gripper."""
    if robot.gripper is None:
        raise ModelError(f"robot '{robot.name}' has no gripper")
    return f"{prefix}{robot.gripper.name}"


def finger_joint_names(robot: Robot, prefix: str = "") -> tuple[str, str]:
    """Names of the left and right finger slide joints (q in m, 0 = closed)."""
    g = gripper_body_name(robot, prefix)
    return f"{g}.left_slide", f"{g}.right_slide"


def _check_prefix(prefix: str) -> None:
    if "/" in prefix:
        raise ModelError(
            f"prefix {prefix!r} contains '/', which dm_control reserves; use e.g. 'puma_1.'"
        )


def robot_spec(
    robot: Robot,
    *,
    prefix: str = "",
    geometry: bool = True,
    density: float = ARM_DENSITY,
    mass: float = 0.1,
    actuators: bool = True,
    armature: float = ARMATURE,
    servo_frequency: float = SERVO_FREQUENCY,
) -> mujoco.MjSpec:
    """An MjSpec of the robot with the tool site ``{prefix}tool`` (see the module doc).

    With ``geometry`` (and link solids on the robot) every link carries its meshes at
    ``density`` (kg/m^3) and the gripper, if any, its bodies and finger joints; the mesh
    bytes are in ``spec.assets``. Otherwise, and for links without solids, each body
    gets a placeholder inertia (``mass`` kg, a 5 cm solid sphere). Joint ranges are the
    robot's limits (radians / metres). Every body has ``gravcomp=1`` and every arm joint
    ``armature`` (kg m^2 or kg); with ``actuators``, every arm joint and finger slide
    gets a position servo of natural frequency ``servo_frequency`` (Hz; module doc).
    """
    _check_prefix(prefix)
    if not (np.isfinite(density) and density > 0):
        raise GeometryError(f"density must be a positive number (kg/m^3), got {density!r}")
    if not (np.isfinite(armature) and armature >= 0):
        raise GeometryError(f"armature must be a number >= 0 (kg m^2), got {armature!r}")
    if not (np.isfinite(servo_frequency) and servo_frequency > 0):
        raise GeometryError(f"servo_frequency must be a number > 0 (Hz), got {servo_frequency!r}")
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    spec.modelname = robot.name
    with_geo = geometry and bool(robot.geometry)
    gripper = robot.gripper if with_geo else None
    gripper_blocks = {p.block for p in gripper.geometry if p.block} if gripper else set()
    reg = MeshAssets(spec, prefix)
    cache: dict[str, tuple[str, list[str]]] = {}
    inertia = [0.4 * mass * 0.05**2] * 3

    def placeholder(body: mujoco.MjsBody) -> None:
        body.mass, body.inertia, body.explicitinertial = mass, inertia, True

    def fill(body: mujoco.MjsBody, k: int) -> None:
        solids = [] if not with_geo else robot.geometry
        mine = [
            g for g in solids if g.link == k and (g.block is None or g.block not in gripper_blocks)
        ]
        massive = False
        for g in mine:
            if g.mesh is not None:
                massive |= add_mesh(body, f"{prefix}link{k}.mesh", g, density, reg)
            else:
                add_solid(body, robot, g.block, g.transform, g.colour, density, reg, cache)
                massive = True
        if not massive:
            placeholder(body)

    def add_part(body: mujoco.MjsBody, p: GripperPart) -> bool:
        if p.mesh is not None:
            return add_mesh(body, f"{body.name}.mesh", p, density, reg)
        add_solid(body, robot, p.block, p.transform, p.colour, density, reg, cache)
        return True

    bodies: list[tuple[str, int]] = []
    parent = spec.worldbody.add_body(name=body_name(prefix, 0))
    parent.pos, parent.quat = pos_quat_from_pose(robot.base)
    fill(parent, 0)
    bodies.append((parent.name, 0))
    for i, j in enumerate(robot.joints):
        body = parent.add_body(name=body_name(prefix, i + 1))
        body.pos, body.quat = pos_quat_from_pose(j.origin)
        kind = mujoco.mjtJoint.mjJNT_SLIDE if j.kind == "prismatic" else mujoco.mjtJoint.mjJNT_HINGE
        body.add_joint(
            name=joint_name(robot, prefix, i),
            type=kind,
            axis=j.axis.tolist(),
            pos=j.axis_point.tolist(),
            range=list(j.limits),
            limited=mujoco.mjtLimited.mjLIMITED_TRUE,
            armature=float(armature),
        )
        fill(body, i + 1)
        bodies.append((body.name, i + 1))
        parent = body
    n = robot.dof
    if gripper is None:
        pos, quat = pos_quat_from_pose(robot.tool)
        parent.add_site(name=f"{prefix}{TOOL_SITE}", pos=pos, quat=quat)
    else:
        gname = gripper_body_name(robot, prefix)
        gbody = parent.add_body(name=gname)
        gbody.pos, gbody.quat = pos_quat_from_pose(gripper.mount)
        bodies.append((gname, n))
        palm = [add_part(gbody, p) for p in gripper.geometry if p.role == "palm"]
        if not any(palm):
            placeholder(gbody)
        for role, axis, jname in zip(
            ("left", "right"),
            ([0, 1, 0], [0, -1, 0]),
            finger_joint_names(robot, prefix),
            strict=True,
        ):
            fbody = gbody.add_body(name=f"{gname}.{role}")
            fbody.add_joint(
                name=jname,
                type=mujoco.mjtJoint.mjJNT_SLIDE,
                axis=axis,
                range=[0.0, gripper.finger_travel],
                limited=mujoco.mjtLimited.mjLIMITED_TRUE,
                ref=gripper.finger_travel,
            )
            parts = [add_part(fbody, p) for p in gripper.geometry if p.role == role]
            if not any(parts):
                placeholder(fbody)
            bodies.append((fbody.name, n))
        pos, quat = pos_quat_from_pose(invert(gripper.mount) @ robot.tool)
        gbody.add_site(name=f"{prefix}{TOOL_SITE}", pos=pos, quat=quat)
    for a in range(len(bodies)):
        for b in range(a + 1, len(bodies)):
            if abs(bodies[a][1] - bodies[b][1]) <= 2:
                spec.add_exclude(bodyname1=bodies[a][0], bodyname2=bodies[b][0])
    for b in spec.worldbody.find_all(mujoco.mjtObj.mjOBJ_BODY):
        b.gravcomp = 1.0
    spec.assets = reg.assets
    if actuators:
        _add_servos(spec, servo_frequency)
    return spec


def _add_servos(spec: mujoco.MjSpec, frequency: float) -> None:
    """A position actuator on every joint of ``spec`` (module doc), gains from the joint's
    inertia at q = 0 in a compiled copy."""
    m = spec.copy().compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    w = 2.0 * np.pi * float(frequency)
    for j in range(m.njnt):
        inertia = float(M[m.jnt_dofadr[j], m.jnt_dofadr[j]])
        name = m.joint(j).name
        act = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=inertia * w * w, kv=2.0 * SERVO_DAMPING * inertia * w)
        act.ctrlrange = m.jnt_range[j].tolist()
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE


def kinematic_model(robot: Robot, *, prefix: str = "") -> mujoco.MjModel:
    """Compiled kinematic-only model of the robot (placeholder inertias, no geometry)."""
    return robot_spec(robot, prefix=prefix, geometry=False, actuators=False).compile()


def export_robot(
    robot: Robot,
    out_dir: str | os.PathLike,
    *,
    prefix: str = "",
    file_name: str | None = None,
    density: float = ARM_DENSITY,
) -> Path:
    """Write the robot as one MJCF file plus STL meshes in ``out_dir/meshes``; return the XML path.

    The XML (``file_name``, default ``"{prefix}{robot.name}.xml"``) names its meshes
    relative to itself (``meshdir="meshes"``), so the folder loads from any working
    directory, in plain MuJoCo and in dm_control. The model is compiled before anything
    is written (a MuJoCo error raises GeometryError); every file is written atomically.
    """
    spec = robot_spec(robot, prefix=prefix, density=density)
    spec.compiler.meshdir = MESHDIR
    try:
        spec.compile()
        xml = spec_to_xml(spec)
    except ValueError as exc:
        raise GeometryError(f"robot '{robot.name}' does not compile in MuJoCo: {exc}") from exc
    name = file_name or f"{prefix}{robot.name}.xml"
    files = {f"{MESHDIR}/{file}": data for file, data in spec.assets.items()}
    write_files(out_dir, {**files, name: xml.encode("utf-8")}, error=ModelError)
    return Path(out_dir) / name
