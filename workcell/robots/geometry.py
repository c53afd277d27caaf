"""Link solids of the built-in Pumas, built with the modeller the thesis's way (thesis §4).

The Puma is drawn from cylinders (pedestal, trunk, shoulder housing), translational
sweeps of profiles (upper arm and forearm: tapered capsule outlines extruded across
the arm), a sphere plus a cylinder at the wrist and a flange disc. Every solid is convex,
so its mesh is its own collision piece in MuJoCo.

Lengths along the arm come from the DH table (d1, a2, a3, d3, d4), so each link meets the
joint axes it turns about; cross-sections are those of a Puma 560 times ``scale``
(1 for the 560, about 0.46 = a2(260) / a2(560) for the 260). Each solid is one block of
``robot.model``; a :class:`~workcell.robots.robot.LinkGeometry` places it in DH frame
``link`` (0 = base frame, i = the frame after joint i). Units: metres.

Where things sit (standard DH, Puma convention): the shoulder offset d3 runs along the
shoulder axis z1; the forearm is centred on it (z2 = d3, i.e. y3 = 0) and the upper arm
sits outboard of the forearm, so the trunk never cuts through either.

:func:`copy_blocks` rebuilds blocks of one model in another (surfaces, boolean operands
and all), under prefixed names; the gripper uses it to merge its solids into a robot.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull

from workcell import solids, spatial
from workcell.errors import KinematicsError, ModelError
from workcell.modeller.model import Model, check_name
from workcell.modeller.surface import Surface
from workcell.robots.robot import LinkGeometry, Robot

__all__ = [
    "PUMA560_FLANGE",
    "capsule_profile",
    "copy_blocks",
    "flange_distance",
    "puma_geometry",
]

PUMA560_FLANGE = 0.05625  # m, wrist centre to flange of the Puma 560 (Fu, Gonzalez, Lee: d6)

# colours (RGBA)
BASE_COLOUR = (0.30, 0.32, 0.35, 1.0)
ARM_COLOUR = (0.86, 0.85, 0.80, 1.0)
WRIST_COLOUR = (0.55, 0.57, 0.60, 1.0)
FLANGE_COLOUR = (0.15, 0.15, 0.17, 1.0)

# facet counts: enough to look round, few enough to build in milliseconds
_N_CYL = 24
_N_ARC = 24
_SPHERE_M, _SPHERE_N = 16, 8

# Puma 560 cross-sections (m), multiplied by ``scale``
_PEDESTAL_R, _FOOT_R, _FOOT_H = 0.11, 0.16, 0.02
_TRUNK_R, _TRUNK_H = 0.09, 0.20
_SHOULDER_R, _SHOULDER_BACK = 0.10, 0.10
_UPPER_T, _UPPER_R_SHOULDER, _UPPER_R_ELBOW = 0.06, 0.085, 0.065
_FORE_W, _FORE_R_ELBOW, _FORE_R_WRIST = 0.08, 0.065, 0.04
_WRIST_R, _WRIST_CYL_R = 0.045, 0.028
_FLANGE_R, _FLANGE_T = 0.035, 0.008

_Rxm90 = spatial.rot_x(-np.pi / 2)
# block (x, y, z) -> DH frame 3 (x, z, -y): a profile drawn in x3-z3, swept along -y3
_PROFILE_XZ = np.array(
    [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
)


def capsule_profile(
    c0: tuple[float, float], r0: float, c1: tuple[float, float], r1: float, n: int = _N_ARC
) -> NDArray[np.float64]:
    """Counter-clockwise outline (K, 2) of the convex hull of two circles (m): a tapered capsule.

    Each circle is sampled at ``n`` points (vertices on the circle), so the outline is
    convex with at most 2n vertices.
    """
    t = 2 * np.pi * np.arange(n) / n
    ring = np.column_stack([np.cos(t), np.sin(t)])
    pts = np.concatenate([np.asarray(c0) + r0 * ring, np.asarray(c1) + r1 * ring])
    hull = ConvexHull(pts)
    return pts[hull.vertices]  # scipy lists 2-D hull vertices counter-clockwise


def flange_distance(robot: Robot, scale: float = 1.0) -> float:
    """Wrist centre to flange face along z6 (m).

    The robot's tool when it is a pure +z translation (the Puma 260's flange), else the
    Puma 560's d6 = 0.05625 m times ``scale``.
    """
    T = robot.tool
    if np.allclose(T[:3, :3], np.eye(3)) and np.allclose(T[:2, 3], 0.0) and T[2, 3] > 0:
        return float(T[2, 3])
    return PUMA560_FLANGE * scale


def puma_geometry(robot: Robot, *, scale: float) -> Robot:
    """``robot`` with Puma link solids in a new ``model`` and ``geometry`` (see the module doc).

    ``scale`` (> 0) multiplies the Puma 560's cross-sections; spans come from the DH table.
    Raises KinematicsError for a robot that is not a 6-joint standard-DH arm.
    """
    dh = [j.dh for j in robot.joints]
    if robot.dof != 6 or any(r is None or r.convention != "standard" for r in dh):
        raise KinematicsError(
            f"puma_geometry needs a 6-joint Puma built from standard DH rows; robot "
            f"'{robot.name}' has {robot.dof} joints, not all of them standard DH"
        )
    if not (np.isfinite(scale) and scale > 0):
        raise KinematicsError(f"puma_geometry: scale must be a positive number, got {scale!r}")
    if robot.gripper is not None:
        raise ModelError(
            f"robot '{robot.name}' carries gripper '{robot.gripper.name}': "
            "give the robot its link solids first, then attach the gripper"
        )
    d1, a2, a3, d3, d4 = dh[0].d, dh[1].a, dh[2].a, dh[2].d, dh[3].d  # type: ignore[union-attr]
    s = float(scale)
    m = Model()
    geo: list[LinkGeometry] = []

    def add(link: int, block: str, T: NDArray[np.float64], colour: tuple[float, ...]) -> None:
        m.set_colour(("block", block), colour)
        geo.append(LinkGeometry(link, block, T, colour))

    # link 0: a foot plate and the pedestal up to the trunk
    foot_h, trunk_h = _FOOT_H * s, min(_TRUNK_H * s, 0.5 * d1)
    solids.cylinder(m, "base.foot", radius=_FOOT_R * s, height=foot_h, n=_N_CYL)
    add(0, "base.foot", np.eye(4), BASE_COLOUR)
    solids.cylinder(m, "base.pedestal", radius=_PEDESTAL_R * s, height=d1 - trunk_h, n=_N_CYL)
    add(0, "base.pedestal", np.eye(4), BASE_COLOUR)

    # link 1 (frame 1: origin on the shoulder axis z1, y1 up): trunk and shoulder housing
    fore_w = _FORE_W * s
    upper_z0 = d3 + fore_w / 2  # inner face of the upper arm along z1 = z2
    solids.cylinder(m, "link1.trunk", radius=_TRUNK_R * s, height=trunk_h, n=_N_CYL)
    add(1, "link1.trunk", spatial.translation(0, -trunk_h, 0) @ _Rxm90, ARM_COLOUR)
    back = _SHOULDER_BACK * s
    solids.cylinder(m, "link1.shoulder", radius=_SHOULDER_R * s, height=back + upper_z0, n=_N_CYL)
    add(1, "link1.shoulder", spatial.translation(0, 0, -back), ARM_COLOUR)

    # link 2 (frame 2: origin on the elbow axis, shoulder at (-a2, 0, 0)): swept upper arm
    upper = capsule_profile((-a2, 0.0), _UPPER_R_SHOULDER * s, (0.0, 0.0), _UPPER_R_ELBOW * s)
    solids.extrude(
        m, "link2.upper_arm", Surface(upper, name="link2.upper_arm"), height=_UPPER_T * s
    )
    add(2, "link2.upper_arm", spatial.translation(0, 0, upper_z0), ARM_COLOUR)

    # link 3 (frame 3: z3 along the forearm to the wrist centre at z3 = d4; elbow axis
    # along y3 through x3 = -a3): swept forearm, profile in x3-z3, centred on y3 = 0
    fore = capsule_profile((-a3, 0.0), _FORE_R_ELBOW * s, (0.0, d4), _FORE_R_WRIST * s)
    solids.extrude(m, "link3.forearm", Surface(fore, name="link3.forearm"), height=fore_w)
    add(3, "link3.forearm", spatial.translation(0, fore_w / 2, 0) @ _PROFILE_XZ, ARM_COLOUR)

    # wrist: sphere on link 4 at the wrist centre, cylinder on link 5 along z5, flange on 6
    flange = flange_distance(robot, s)
    wrist_r = min(_WRIST_R * s, 0.8 * flange)
    cyl_r = min(_WRIST_CYL_R * s, 0.7 * wrist_r)
    flange_t = min(_FLANGE_T * s, 0.25 * flange)
    solids.sphere(m, "link4.wrist", radius=wrist_r, m=_SPHERE_M, n=_SPHERE_N)
    add(4, "link4.wrist", np.eye(4), WRIST_COLOUR)
    # starts inside the sphere (at -cyl_r) so it holds the wrist centre, ends at the flange
    solids.cylinder(m, "link5.wrist", radius=cyl_r, height=flange - flange_t + cyl_r, n=_N_CYL)
    add(5, "link5.wrist", spatial.translation(0, 0, -cyl_r), WRIST_COLOUR)
    solids.cylinder(m, "link6.flange", radius=_FLANGE_R * s, height=flange_t, n=_N_CYL)
    add(6, "link6.flange", spatial.translation(0, 0, flange - flange_t), FLANGE_COLOUR)
    return robot.with_(model=m, geometry=tuple(geo))


# ---------------------------------------------------------------------- copying blocks
def _dependencies(src: Model, block: str) -> tuple[list[str], list[str]]:
    """(surfaces, blocks) that ``block`` needs, blocks in build order (operands first)."""
    surfaces: dict[str, None] = {}
    blocks: dict[str, None] = {}

    def visit(name: str) -> None:
        if name in blocks:
            return
        for rel in src.relations(("block", name)):
            if rel.target_level == "surface":
                surfaces.setdefault(rel.target)
            else:
                visit(rel.target)
        blocks[name] = None

    visit(block)
    return list(surfaces), list(blocks)


def copy_blocks(
    src: Model, blocks: Iterable[str], dst: Model, *, prefix: str = ""
) -> dict[str, str]:
    """Rebuild ``blocks`` of ``src`` in ``dst`` named ``prefix + name``; return old -> new names.

    Surfaces, boolean operands, relation names and transforms, colours and movable flags
    are copied (the immutable Surface geometry is shared). Every new name is checked
    before anything is created, so a clash (ModelError) leaves ``dst`` unchanged.
    """
    surfaces: dict[str, None] = {}
    order: dict[str, None] = {}
    for b in blocks:
        src.info(("block", b))  # a ModelError naming the known blocks when unknown
        ss, bs = _dependencies(src, b)
        surfaces.update(dict.fromkeys(ss))
        order.update(dict.fromkeys(bs))
    for level, names in (("surface", surfaces), ("block", order)):
        for name in names:
            new = check_name(prefix + name)
            if dst.exists((level, new)):
                raise ModelError(f"cannot copy {level} '{name}': '{new}' already exists")
    for name in surfaces:
        colour = src.info(("surface", name)).colour
        dst.create("surface", prefix + name, src.surface(("surface", name)), colour=colour)
    for name in order:
        info = src.info(("block", name))
        rels = src.relations(("block", name))
        Ts = np.stack([r.transform for r in rels]) if rels else np.zeros((0, 4, 4))
        targets = [(r.target_level, prefix + r.target) for r in rels]
        if info.boolean:
            dst.create_boolean(prefix + name, info.boolean, targets, list(Ts), colour=info.colour)
        else:
            dst.create("block", prefix + name, colour=info.colour, movable=info.movable)
            if rels:
                dst.attach_many(prefix + name, targets, Ts, names=[r.name for r in rels])
    return {b: prefix + b for b in order}
