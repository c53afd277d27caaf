"""What task-level commands choose between, as plain values: reaches, failures, turns.

:class:`Reach` is a reachable tool pose with its approach; :class:`Failures` counts why
candidates were turned down, for the error message; :func:`turns` lists the tool
rotations to try for a held part; :data:`BACKOFFS` are the grasp depths tried. The
choosing itself is the simulator's (:mod:`workcell.sim.choosing`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from workcell.moved import moved
from workcell.plan.scene import Violation
from workcell.spatial import rot_z

__all__ = [
    "BACKOFFS",
    "ChoiceHelpers",  # noqa: F822 (moved; found by __getattr__)
    "Failures",
    "Reach",
    "turns",
]

Array = NDArray[np.float64]
BACKOFFS = (0.0, 0.005, 0.01, 0.015)  # m: tool-centre point back from the centroid


@dataclass(frozen=True)
class Reach:
    """A reachable tool pose: the ``tool`` pose, its joints ``q``, the ``above`` pose and
    its joints ``q_above`` (the approach, consistent with ``q`` along a straight line)."""

    tool: Array
    q: Array
    above: Array
    q_above: Array


class Failures:
    """Why candidates were turned down, for the error message."""

    def __init__(self) -> None:
        self.unreachable = 0
        self.reason = ""
        self.collisions = 0
        self.nearest: Violation | None = None
        self.other = ""

    def collide(self, v: Violation | None) -> None:
        self.collisions += 1
        if v is not None and (self.nearest is None or v[2] < self.nearest[2]):
            self.nearest = v


def turns(R: Array) -> list[Array]:
    """Tool rotations to try for a part held with tool rotation R: turned about the
    vertical by 0, 90, -90, 180 deg when the tool points down; else pointing down at the
    yaw of its x axis (then the same turns), R itself last."""
    yaws = (0.0, math.pi / 2, -math.pi / 2, math.pi)
    if R[2, 2] < -1 + 1e-6:
        return [rot_z(a)[:3, :3] @ R for a in yaws]
    x = R[:3, 0] if abs(R[2, 0]) < 0.9 else R[:3, 1]
    psi = math.atan2(x[1], x[0])
    down = np.diag([1.0, -1.0, -1.0])  # tool_down at yaw 0: z down, x along world x
    return [rot_z(psi + a)[:3, :3] @ down for a in yaws] + [R]


# the simulator's choosing lives with the simulator (workcell.sim.choosing)
__getattr__ = moved(__name__, {"ChoiceHelpers": "workcell.sim.choosing"})
