"""Grasp poses of a part, generated from its box: the thesis's three grasp tests turned around.

``close_gripper`` grasps a part when (1) the tool's z axis is parallel to one of the
part's box axes, (2) the box's width across the grasp (along the tool's y axis, where the
fingers close) fits the gripper's opening and (3) the tool-centre point is near the
part's centroid (:mod:`workcell.sim.grasp`). Turned around, these give every grasp pose:
tool z along one of the six box directions, tool y along one of the two other box axes
(either sense) where the box is narrower than the opening, the tool-centre point at the
centroid or backed off along the tool's -z axis (``backoffs``, m, within the distance
test; for fingers that would reach below a thin part). So 6 x 4 orientations at most.

The grasp's height along the approach comes from the gripper and the part
(:func:`grip_depths`): with the palm's face ``palm`` (m) behind the tool-centre point
and the finger tips ``tips`` (m) ahead of it, the tool-centre point backs off from the
centroid at least as far as keeps the palm ``margin`` (m) off the part's near face (a
part taller than the fingers are long: 40 mm above its centroid against 37.5 mm of
finger would put the palm 2.5 mm into it) and the tips ``margin`` short of its far face
(the support below a thin part); each back-off of ``backoffs`` counts from there. The
fingers then hold the part over their length and nothing but them touches it.

:func:`grasp_poses` orders them by preference: approaching from above first (tool z
nearest to straight down), then from the side, from below last; narrower grasps first;
no back-off first. Units: metres, radians.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from workcell.robots.gripper import Gripper

__all__ = ["GraspPose", "grasp_poses", "grip_depths"]

Array = NDArray[np.float64]
_DOWN = np.array([0.0, 0.0, -1.0])


@dataclass(frozen=True)
class GraspPose:
    """One grasp: the world ``tool`` pose (4x4), the part's ``width`` across the fingers
    (m), the ``backoff`` of the tool-centre point from the centroid (m) and the box axis
    approached (``axis`` 0-2 of the part frame, ``sign`` +1/-1: tool z = sign x axis)."""

    tool: Array
    width: float
    backoff: float
    axis: int
    sign: int


def grasp_poses(
    part_pose: Array,
    lower: Array,
    upper: Array,
    centroid: Array,
    *,
    opening: float,
    backoffs: tuple[float, ...] = (0.0,),
    palm: float | None = None,
    tips: float | None = None,
    margin: float = 0.0,
) -> list[GraspPose]:
    """Grasp poses of a part at world pose ``part_pose`` (4x4) with box corners
    ``lower``/``upper`` and ``centroid`` (3,) in its own frame, for a gripper of
    ``opening`` (m); preferred first (module doc). Empty when no box width fits.
    ``palm``, ``tips`` (m, None: not known) and ``margin`` (m): the grasp height (module
    doc)."""
    R = part_pose[:3, :3]
    c = part_pose[:3, :3] @ centroid + part_pose[:3, 3]
    lower, upper = np.asarray(lower, dtype=np.float64), np.asarray(upper, dtype=np.float64)
    size = upper - lower
    out = []
    for a in range(3):
        for sign in (-1, 1):
            z = sign * R[:, a]
            # the box faces the palm and the tips meet, from the centroid (m)
            ahead, behind = upper[a] - centroid[a], centroid[a] - lower[a]
            near, far = (ahead, behind) if sign < 0 else (behind, ahead)
            least = 0.0
            if palm is not None:
                least = max(least, near + margin - palm)
            if tips is not None:
                least = max(least, tips - far + margin)
            for b in (k for k in range(3) if k != a):
                width = float(size[b])
                if width > opening:
                    continue
                for ysign in (1, -1):
                    y = ysign * R[:, b]
                    T = np.eye(4)
                    T[:3, 0], T[:3, 1], T[:3, 2] = np.cross(y, z), y, z
                    for back in (least + b for b in backoffs):
                        T2 = T.copy()
                        T2[:3, 3] = c - back * z
                        out.append(GraspPose(T2, width, back, a, sign))
    out.sort(key=lambda g: (-round(float(g.tool[:3, 2] @ _DOWN), 9), g.backoff, g.width))
    return out


def grip_depths(gripper: Gripper) -> tuple[float | None, float]:
    """(palm, tips) of a gripper (m, along its approach axis z): how far its palm's face
    is behind the tool-centre point (None when it has no palm) and how far its finger
    tips are ahead of it."""
    tcp = float(gripper.tcp[2, 3])
    tips = float(gripper.finger_tips()[0, 2]) - tcp
    roles = {p.role for p in gripper.geometry}
    if "palm" not in roles:
        return None, tips
    face = float(gripper.part("palm").vertices(gripper.model)[:, 2].max())
    return tcp - face, tips
