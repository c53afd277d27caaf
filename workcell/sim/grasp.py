"""The thesis's grasp tests (§4.5): which movable part a closing gripper takes.

Every movable part carries a bounding box and a frame at its centroid, both in the part's
own frame. ``close_gripper(robot, max_distance, max_angle)`` tests each movable part:

1. **angle**: the tool's z axis (the approach direction) is parallel, within
   ``max_angle`` (rad), to one of the box's axes (either sense);
2. **width**: the box's width across the grasp, measured along the tool's y axis (the
   direction the fingers close along), fits the gripper's opening;
3. **distance**: the tool-centre point lies within ``max_distance`` (m) of the grasp
   point, the part's centroid.

The parts are tried nearest first (by the distance of test 3); the first that passes
all three is grasped. When none passes, :func:`describe_failure` names the nearest
candidate, the first test it failed and by how much.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["GraspCandidate", "PartBox", "describe_failure", "grasp_candidates", "tool_down"]

Array = NDArray[np.float64]
TESTS = ("angle", "width", "distance")


@dataclass(frozen=True)
class PartBox:
    """A movable part as the grasp tests see it, in world coordinates.

    ``axes`` (3, 3): the box axes as columns (the part frame's rotation); ``half`` (3,):
    the box's half extents along them (m); ``centroid`` (3,): the grasp point (m).
    """

    name: str
    axes: Array
    half: Array
    centroid: Array


@dataclass(frozen=True)
class GraspCandidate:
    """The three tests of one part: ``angle`` (rad) between the tool's z axis and the
    nearest box axis, ``width`` (m) of the box across the grasp, ``distance`` (m) from the
    tool-centre point to the centroid, and ``failed``: the first failed test ("angle",
    "width" or "distance") or None when the part can be grasped."""

    part: str
    angle: float
    width: float
    distance: float
    failed: str | None


def grasp_candidates(
    tcp: Array,
    parts: list[PartBox],
    *,
    opening: float,
    max_distance: float,
    max_angle: float,
) -> list[GraspCandidate]:
    """The grasp tests of every part, nearest first (see the module doc).

    ``tcp`` is the tool-centre pose in the world (4x4); ``opening`` the gripper's widest
    opening (m).
    """
    z, y, p = tcp[:3, 2], tcp[:3, 1], tcp[:3, 3]
    out = []
    for part in parts:
        cosines = np.abs(part.axes.T @ z)
        angle = math.acos(min(1.0, float(cosines.max())))
        width = 2.0 * float(np.abs(part.axes.T @ y) @ part.half)
        distance = float(np.linalg.norm(part.centroid - p))
        checks = (angle <= max_angle, width <= opening, distance <= max_distance)
        failed = next((t for t, ok in zip(TESTS, checks, strict=True) if not ok), None)
        out.append(GraspCandidate(part.name, angle, width, distance, failed))
    out.sort(key=lambda c: c.distance)
    return out


def describe_failure(
    robot: str,
    candidates: list[GraspCandidate],
    *,
    opening: float,
    max_distance: float,
    max_angle: float,
) -> str:
    """Why no part was grasped: the nearest candidate and the test it failed, with numbers."""
    if not candidates:
        return f"close_gripper '{robot}': the cell has no movable part to grasp"
    c = candidates[0]
    why = {
        "angle": (
            f"tool z axis is {math.degrees(c.angle):.3g} deg from the nearest box axis "
            f"(max_angle {math.degrees(max_angle):.3g} deg)"
        ),
        "width": (
            f"its width across the grasp is {c.width * 1e3:.4g} mm, wider than the "
            f"gripper's {opening * 1e3:.4g} mm opening"
        ),
        "distance": (
            f"the tool-centre point is {c.distance * 1e3:.4g} mm from its centroid "
            f"(max_distance {max_distance * 1e3:.4g} mm)"
        ),
    }[c.failed or "distance"]
    return (
        f"close_gripper '{robot}': no part passes the grasp tests; nearest candidate "
        f"'{c.part}' fails the {c.failed} test: {why}"
    )


def tool_down(position: ArrayLike, yaw: float = 0.0) -> Array:
    """World tool pose (4x4) at ``position`` (m) with the tool's z axis pointing down
    (a top grasp): ``Rz(yaw) Rx(pi)``, so its x axis is the world's x axis turned by
    ``yaw`` (rad) about the vertical; the fingers close along its y axis."""
    c, s = math.cos(yaw), math.sin(yaw)
    T = np.eye(4)
    T[:3, :3] = [[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]]
    T[:3, 3] = np.asarray(position, dtype=np.float64)
    return T
