"""Robots to MuJoCo through MjSpec: one body per link, one joint per DH row, a tool site.

Standard DH: joint i turns about z of frame i-1, so body i is frame i-1; it sits in body
i-1 at what row i-1 adds besides its own joint motion. Modified DH: joint i turns about
z of frame i, so body i is frame i. Names carry a prefix (``"puma_1."``) so several
robots can share a cell; ``/`` is never used (dm_control reserves it).
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.robots.robot import Joint, Robot
from workcell.spatial import quat_from_matrix, rot_x, rot_z, translation

__all__ = ["TOOL_SITE", "body_name", "joint_name", "kinematic_model", "robot_spec"]

TOOL_SITE = "tool"


def body_name(prefix: str, i: int) -> str:
    """Name of link i's body (0 = base)."""
    return f"{prefix}link{i}"


def joint_name(robot: Robot, prefix: str, i: int) -> str:
    """MJCF name of joint i (0-based)."""
    return f"{prefix}{robot.joints[i].name}"


def _pos_quat(T: NDArray[np.float64]) -> tuple[list[float], list[float]]:
    return T[:3, 3].tolist(), quat_from_matrix(T[:3, :3]).tolist()


def fixed_part(j: Joint, convention: str) -> NDArray[np.float64]:
    """The constant part of a DH row once the joint's own motion about/along z is taken out.

    Standard: Rz(theta0) Tz(d0) Tx(a) Rx(alpha); modified: Rx(alpha) Tx(a) Rz(theta0) Tz(d0),
    where theta0 = offset, d0 = d for a revolute joint and theta0 = theta, d0 = offset for a
    prismatic one (a rotation and a translation along the same axis commute).
    """
    theta0, d0 = (j.theta, j.offset) if j.kind == "prismatic" else (j.offset, j.d)
    rz = translation(0, 0, d0) @ rot_z(theta0)
    xa = translation(j.a, 0, 0) @ rot_x(j.alpha)
    return xa @ rz if convention == "modified" else rz @ xa


def robot_spec(robot: Robot, *, prefix: str = "", mass: float = 0.1) -> mujoco.MjSpec:
    """An MjSpec of the robot's kinematic chain, with the tool site ``{prefix}tool``.

    Each link body gets a small placeholder inertia (``mass`` kg, a 5 cm solid sphere) so
    the model compiles; callers that add link solids replace it. Joint ranges are the
    robot's limits (radians / metres).
    """
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    spec.modelname = robot.name
    inertia = [0.4 * mass * 0.05**2] * 3
    parent = spec.worldbody.add_body(name=body_name(prefix, 0))
    parent.pos, parent.quat = _pos_quat(robot.base)
    parent.mass, parent.inertia = mass, inertia
    for i, j in enumerate(robot.joints):
        body = parent.add_body(name=body_name(prefix, i + 1))
        body.mass, body.inertia = mass, inertia
        if robot.convention == "standard":
            placement = fixed_part(robot.joints[i - 1], "standard") if i > 0 else np.eye(4)
        else:
            placement = fixed_part(j, "modified")
        body.pos, body.quat = _pos_quat(placement)
        kind = mujoco.mjtJoint.mjJNT_SLIDE if j.kind == "prismatic" else mujoco.mjtJoint.mjJNT_HINGE
        body.add_joint(
            name=joint_name(robot, prefix, i),
            type=kind,
            axis=[0, 0, 1],
            range=list(j.limits),
            limited=mujoco.mjtLimited.mjLIMITED_TRUE,
        )
        parent = body
    last = fixed_part(robot.joints[-1], "standard") if robot.convention == "standard" else np.eye(4)
    pos, quat = _pos_quat(last @ robot.tool)
    parent.add_site(name=f"{prefix}{TOOL_SITE}", pos=pos, quat=quat)
    return spec


def kinematic_model(robot: Robot, *, prefix: str = "") -> mujoco.MjModel:
    """Compiled kinematic-only model of the robot (placeholder inertias, no geometry)."""
    return robot_spec(robot, prefix=prefix).compile()
