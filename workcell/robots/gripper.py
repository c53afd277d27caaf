"""A parallel-jaw gripper swept from 2-D profiles (thesis §4: "a swept gripper").

Gripper frame: origin at the mounting face (the robot's flange), z the approach
direction, the jaws close along y. The palm is an extruded chamfered rectangle from
z = 0 to ``palm_height``; each finger is a tapered profile drawn in the y-z plane and
extruded across x by ``finger_width``, its flat inner (gripping) face at
y = +-opening/2. The solids are stored fully open (opening = ``max_opening``); each
finger travels ``finger_travel = max_opening / 2`` towards the centre plane y = 0.
The tool-centre point (TCP) lies on the z axis between the finger tips, ``tcp_depth``
back from them, with the flange's orientation. Units: metres.

:func:`attach_gripper` mounts a gripper on a robot's last link: the robot's tool
becomes ``mount @ tcp`` and its model and geometry gain the gripper's solids.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell import solids, spatial
from workcell.errors import GeometryError, ModelError
from workcell.modeller.model import Model, check_name
from workcell.modeller.surface import Surface
from workcell.robots.geometry import copy_blocks
from workcell.robots.robot import LinkGeometry, Robot
from workcell.spatial import as_transform

__all__ = ["Gripper", "GripperPart", "attach_gripper", "default_mount", "parallel_gripper"]

Array = NDArray[np.float64]
Role = Literal["palm", "left", "right"]

PALM_COLOUR = (0.20, 0.22, 0.25, 1.0)
FINGER_COLOUR = (0.75, 0.45, 0.15, 1.0)

# block (x, y, z) -> gripper (y, z, x): a profile drawn in y-z, swept along +x
_PROFILE_YZ = np.array(
    [[0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
)


@dataclass(frozen=True, eq=False)
class GripperPart:
    """One gripper solid: ``role`` palm, left (+y) or right (-y) finger; ``block`` placed by
    ``transform`` (4x4, m) in the gripper frame, fingers fully open; RGBA ``colour``."""

    role: Role
    block: str
    transform: Array
    colour: tuple[float, ...] | None = None


@dataclass(frozen=True, eq=False)
class Gripper:
    """A parallel-jaw gripper: solids in ``model``, placed by ``geometry`` in the gripper frame.

    ``max_opening`` (m) between the jaws fully open; ``finger_travel`` (m) of each finger
    (max_opening / 2); ``tcp`` (4x4) the tool-centre point in the gripper frame; ``mount``
    (4x4) the gripper frame in the robot's last DH frame (identity until attached).
    """

    name: str
    model: Model
    geometry: tuple[GripperPart, ...]
    max_opening: float
    finger_travel: float
    tcp: Array
    mount: Array = field(default_factory=lambda: np.eye(4))

    def part(self, role: Role) -> GripperPart:
        """The (first) part with ``role``: ``"palm"``, ``"left"`` or ``"right"``."""
        for p in self.geometry:
            if p.role == role:
                return p
        raise ModelError(f"gripper '{self.name}' has no {role} part")

    def finger_tips(self, opening: float | None = None) -> Array:
        """Tip-face centres (2, 3) of the left and right fingers' inner faces (m, gripper frame).

        At ``opening`` (m, default ``max_opening``) between the jaws: the finger-tip ends
        of the gripping faces, x = 0, y = +-opening/2.
        """
        o = self.max_opening if opening is None else float(opening)
        if not 0.0 <= o <= self.max_opening + 1e-12:
            raise GeometryError(
                f"gripper '{self.name}': opening must be in [0, {self.max_opening}] m, got {o}"
            )
        left = self.part("left")
        V = spatial.transform_points(
            left.transform, self.model.world_mesh(("block", left.block)).vertices
        )
        z = float(V[:, 2].max())
        return np.array([[0.0, o / 2, z], [0.0, -o / 2, z]])


def _chamfered_rectangle(wx: float, wy: float, c: float) -> Array:
    """Counter-clockwise outline of a centred wx x wy rectangle with corners cut by c (m)."""
    x, y = wx / 2, wy / 2
    return np.array(
        [
            (x - c, -y),
            (x, -y + c),
            (x, y - c),
            (x - c, y),
            (-x + c, y),
            (-x, y - c),
            (-x, -y + c),
            (-x + c, -y),
        ]
    )


def parallel_gripper(
    name: str = "gripper",
    *,
    max_opening: float = 0.08,
    finger_length: float = 0.05,
    finger_width: float = 0.02,
    finger_thickness: float = 0.012,
    palm_height: float = 0.03,
    tcp_depth: float | None = None,
) -> Gripper:
    """A parallel-jaw gripper with swept palm and fingers (see the module doc).

    ``max_opening`` (m) between the open jaws; ``finger_length`` (m) beyond the palm;
    ``finger_width`` (m, across x) and ``finger_thickness`` (m, along y, at the root; the
    outside tapers to 60 % at the tip); ``palm_height`` (m, along z); ``tcp_depth`` (m)
    from the finger tips back to the TCP (default finger_length / 4).
    """
    check_name(name)
    dims = {
        "max_opening": max_opening,
        "finger_length": finger_length,
        "finger_width": finger_width,
        "finger_thickness": finger_thickness,
        "palm_height": palm_height,
    }
    for key, v in dims.items():
        number = isinstance(v, (int, float)) and not isinstance(v, bool)
        if not (number and np.isfinite(v) and v > 0):
            raise GeometryError(f"gripper '{name}': {key} must be a positive number (m), got {v!r}")
    depth = finger_length / 4 if tcp_depth is None else tcp_depth
    if not (np.isfinite(depth) and 0 <= depth <= finger_length):
        raise GeometryError(
            f"gripper '{name}': tcp_depth must be in [0, finger_length = {finger_length}] m, got {depth!r}"
        )
    m = Model()
    half, th, top = max_opening / 2, finger_thickness, palm_height + finger_length
    # palm: covers both fingers at full opening
    wx, wy = 1.6 * finger_width, max_opening + 2.4 * th
    palm = Surface(_chamfered_rectangle(wx, wy, 0.2 * min(wx, wy)), name="palm")
    solids.extrude(m, "palm", palm, height=palm_height, colour=PALM_COLOUR)
    parts = [GripperPart("palm", "palm", np.eye(4), PALM_COLOUR)]
    # fingers: profile (y, z), inner face flat at y = +-half, rooted a little inside the palm
    root = palm_height * 0.5
    for role, sign in (("left", 1.0), ("right", -1.0)):
        prof = np.array(
            [(half, root), (half + th, root), (half + 0.6 * th, top), (half, top)]
        ) * np.array([sign, 1.0])
        block = f"finger_{role[0]}"
        solids.extrude(
            m, block, Surface(prof, name=block), height=finger_width, colour=FINGER_COLOUR
        )
        T = spatial.translation(-finger_width / 2, 0, 0) @ _PROFILE_YZ
        parts.append(GripperPart(role, block, T, FINGER_COLOUR))  # type: ignore[arg-type]
    return Gripper(
        name=name,
        model=m,
        geometry=tuple(parts),
        max_opening=float(max_opening),
        finger_travel=float(half),
        tcp=spatial.translation(0, 0, top - depth),
    )


def default_mount(robot: Robot) -> Array:
    """Where a gripper goes by default, in the last DH frame: the robot's tool (its flange).

    A robot whose tool is the identity (the Puma 560 of the literature puts it at the
    wrist centre) gets its flange face instead: the highest point along z of its
    last link's solids, Tz(z_top) (the identity when the last link has no solids).
    """
    if not np.allclose(robot.tool, np.eye(4), atol=1e-12) or not robot.geometry:
        return robot.tool.copy()
    top = 0.0
    for g in robot.geometry:
        if g.link == robot.dof:
            if g.mesh is not None:
                vertices = g.mesh.vertices
            elif robot.model is not None:
                vertices = robot.model.world_mesh(("block", g.block)).vertices
            else:
                continue
            V = spatial.transform_points(g.transform, vertices)
            top = max(top, float(V[:, 2].max()))
    return spatial.translation(0, 0, top)


def attach_gripper(robot: Robot, gripper: Gripper, *, mount: ArrayLike | None = None) -> Robot:
    """A copy of ``robot`` carrying ``gripper`` on its last link; the robot is not changed.

    ``mount`` (4x4, default :func:`default_mount`) places the gripper frame in the last DH frame.
    The result's ``tool`` is ``mount @ gripper.tcp`` (so ``fk`` gives the TCP), its
    ``model`` holds the robot's blocks plus the gripper's as ``"{gripper.name}.{block}"``,
    its ``geometry`` adds the gripper solids (fingers open) on the last link, and its
    ``gripper`` field is the gripper re-expressed in that model with ``mount`` set.
    Raises ModelError when the robot already has a gripper or a block name clashes.
    """
    if robot.gripper is not None:
        raise ModelError(
            f"robot '{robot.name}' already carries gripper '{robot.gripper.name}'; "
            "attach to the robot without a gripper"
        )
    M = (
        default_mount(robot)
        if mount is None
        else as_transform(mount, rigid=True, name="gripper mount")
    )
    model = Model()
    blocks = [g.block for g in robot.geometry if g.block is not None]
    if robot.model is not None and blocks:
        copy_blocks(robot.model, dict.fromkeys(blocks), model)
    names = copy_blocks(
        gripper.model, [p.block for p in gripper.geometry], model, prefix=f"{gripper.name}."
    )
    parts = tuple(replace(p, block=names[p.block]) for p in gripper.geometry)
    last = robot.dof
    extra = tuple(LinkGeometry(last, p.block, M @ p.transform, p.colour) for p in parts)
    g = replace(gripper, model=model, geometry=parts, mount=M.copy())
    return robot.with_(
        model=model, geometry=(*robot.geometry, *extra), tool=M @ gripper.tcp, gripper=g
    )
