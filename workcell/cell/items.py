"""What a :class:`~workcell.cell.workcell.Workcell` holds, as frozen records: static and
movable parts, robot placements and cameras; the rule for valid (MJCF-safe) cell names;
the default part colours; and how the cell builds a library robot with a gripper.

Poses are 4x4 rigid transforms (m), joint values rad/m, densities kg/m^3, fields of view
deg. All names here are importable from :mod:`workcell.cell.workcell` as well.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.checks import checked_name
from workcell.errors import ModelError
from workcell.modeller.model import MAX_NAME_LENGTH
from workcell.robots import attach_gripper, get, library, parallel_gripper
from workcell.robots.robot import Robot

__all__ = [
    "BUILTIN_ROBOTS",
    "GRIPPER_PARAMETERS",
    "MOVABLE_COLOURS",
    "STATIC_COLOURS",
    "Camera",
    "MovablePart",
    "RobotPlacement",
    "StaticPart",
    "build_robot",
    "check_cell_name",
    "look_at",
]

# the default colours (RGBA), by kind, one after another per part: muted tones for what
# stands still, vivid ones for what robots carry, none close to the robots' pale arms,
# dark bases and orange fingers, nor to the blue-grey floor of the pictures
STATIC_COLOURS = (
    (0.55, 0.45, 0.35, 1.0),  # wood
    (0.36, 0.50, 0.72, 1.0),  # slate blue
    (0.42, 0.62, 0.45, 1.0),  # sage
    (0.72, 0.64, 0.46, 1.0),  # sand
    (0.56, 0.42, 0.58, 1.0),  # mauve
    (0.40, 0.62, 0.64, 1.0),  # teal
)
MOVABLE_COLOURS = (
    (0.86, 0.18, 0.14, 1.0),  # red
    (0.15, 0.62, 0.25, 1.0),  # green
    (0.96, 0.78, 0.10, 1.0),  # yellow
    (0.14, 0.42, 0.92, 1.0),  # blue
    (0.82, 0.22, 0.72, 1.0),  # magenta
    (0.10, 0.78, 0.82, 1.0),  # cyan
)
BUILTIN_ROBOTS: Mapping[str, Callable[[], Robot]] = MappingProxyType(
    {name: functools.partial(get, name) for name in library()}
)
"""The library robots by name (:func:`workcell.robots.get`), as the cell builds them."""
GRIPPER_PARAMETERS = (
    "name",
    "max_opening",
    "finger_length",
    "finger_width",
    "finger_thickness",
    "palm_height",
    "tcp_depth",
)
_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_\-]*")

Array = NDArray[np.float64]


def check_cell_name(name: object, kind: str = "item") -> str:
    """Return ``name`` if it is a valid (MJCF-safe) cell name, else raise ModelError."""
    rule = "use a letter or '_' followed by letters, digits, '_' or '-' (no '.', no '/')"
    return checked_name(name, _NAME_RE, f"{kind} name", rule, MAX_NAME_LENGTH)


@dataclass(frozen=True, eq=False)
class StaticPart:
    """A fixed part: ``entity`` (level, name) of the cell's model at world ``pose`` (4x4)."""

    name: str
    entity: tuple[str, str]
    pose: Array
    colour: tuple[float, ...]


@dataclass(frozen=True, eq=False)
class MovablePart:
    """A movable part (free body when compiled): as :class:`StaticPart` plus ``density`` (kg/m^3)."""

    name: str
    entity: tuple[str, str]
    pose: Array
    colour: tuple[float, ...]
    density: float


@dataclass(frozen=True, eq=False)
class RobotPlacement:
    """A robot in the cell.

    ``robot`` as built (gripper attached if any); ``base`` (4x4) the world pose of the
    robot's base frame, so the world pose of its tool is ``base @ robot.fk(q)``; ``q``
    the initial joint values (rad/m). ``builtin`` names the library robot it came from
    ("ur5e", "puma260", ...; None for a custom robot), ``gripper_parameters`` the
    :func:`parallel_gripper` arguments the cell attached (None: no gripper, or the
    robot's own) and ``bare`` the Robot as given before that (None: ``robot``).
    """

    name: str
    robot: Robot
    base: Array
    q: Array
    builtin: str | None = None
    gripper_parameters: Mapping[str, Any] | None = field(default=None)
    bare: Robot | None = None

    @property
    def world_base(self) -> Array:
        """World pose of the robot's link 0 body: ``base @ robot.base``."""
        return self.base @ self.robot.base

    def tool_pose(self, q: ArrayLike | None = None) -> Array:
        """World pose of the tool at ``q`` (default: the initial q)."""
        return self.base @ self.robot.fk(self.q if q is None else q)


@dataclass(frozen=True, eq=False)
class Camera:
    """A named camera at ``position`` looking at ``target`` (m) with vertical field ``fovy`` (deg)."""

    name: str
    position: Array
    target: Array
    fovy: float

    def pose(self) -> Array:
        """World pose of the camera frame (MuJoCo convention: looks along -z, y up)."""
        return look_at(self.position, self.target)


def look_at(position: ArrayLike, target: ArrayLike) -> Array:
    """Camera frame at ``position`` whose -z axis points to ``target``; x horizontal.

    When the view is vertical the world y axis serves as the up hint instead of z.
    """
    p = np.asarray(position, dtype=np.float64)
    z = p - np.asarray(target, dtype=np.float64)
    z = z / np.linalg.norm(z)
    up = np.array([0.0, 0.0, 1.0])
    if abs(z @ up) > 1 - 1e-9:
        up = np.array([0.0, 1.0, 0.0])
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, y, z, p
    return T


def build_robot(builtin: str, gripper: Mapping[str, Any] | None) -> Robot:
    """The library robot ``builtin`` with a parallel gripper of ``gripper`` parameters (or none)."""
    if builtin not in BUILTIN_ROBOTS:
        raise ModelError(f"unknown built-in robot {builtin!r}; known: {', '.join(BUILTIN_ROBOTS)}")
    robot = get(builtin)
    if gripper is None:
        return robot
    if not isinstance(gripper, Mapping):
        raise ModelError(f"gripper parameters must be a mapping, got {gripper!r}")
    bad = sorted(set(gripper) - set(GRIPPER_PARAMETERS))
    if bad:
        raise ModelError(
            f"unknown gripper parameter(s) {bad}; valid: {', '.join(GRIPPER_PARAMETERS)}"
        )
    return attach_gripper(robot, parallel_gripper(**gripper))
