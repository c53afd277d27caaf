"""How planned moves search, and what they find: plain values of the planners.

:class:`PlanningOptions` are the settings of planned moves (``sim.set_planning(...)``;
what ``plan=True`` does: :mod:`workcell.sim.planned`): ``clearance`` (m, default 5 mm;
never below the contact tolerance), ``time_limit`` (s per search, default 5) and
``seed`` (default 0): the same cell, program and seed give the same paths;
``near_clearance`` (m, default 1 mm) for the close work of task-level commands.
:class:`PlannedPath` is a path found; :func:`describe` puts a pair that breaks the
clearance in words.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from workcell.checks import is_finite_number
from workcell.errors import ProgramError
from workcell.moved import moved
from workcell.plan.scene import Violation

__all__ = [
    "MAX_TIME",
    "PlannedPath",
    "PlanningCommands",  # noqa: F822 (moved; found by __getattr__)
    "PlanningOptions",
    "describe",
]

Array = NDArray[np.float64]
MAX_TIME = 600.0  # s: the longest search a planned move may be given


@dataclass(frozen=True)
class PlanningOptions:
    """How planned moves search (module doc): ``clearance`` (m, at most 1), ``time_limit``
    (s per search, at most :data:`MAX_TIME`), ``seed`` (int); ``near_clearance`` (m): the clearance of the close work of
    task-level commands (grasp, meeting and placing poses, the straight lines in and out),
    where grippers work around parts and each other."""

    clearance: float = 0.005
    time_limit: float = 5.0
    seed: int = 0
    near_clearance: float = 0.001

    def __post_init__(self) -> None:
        for what, top in (("clearance", 1.0), ("near_clearance", 1.0), ("time_limit", MAX_TIME)):
            v = getattr(self, what)
            if not (is_finite_number(v) and 0 < v <= top):
                raise ProgramError(f"planning {what} must be a number in (0, {top:g}], got {v!r}")
        if not isinstance(self.seed, int) or isinstance(self.seed, bool) or self.seed < 0:
            raise ProgramError(f"planning seed must be an integer >= 0, got {self.seed!r}")


@dataclass(frozen=True)
class PlannedPath:
    """A planned path: ``waypoints`` (k, dof) from the start to the goal (row k-1), the
    search time ``seconds`` (wall clock) and the ``radii`` its motions were checked with
    (m per unit of each joint; see :meth:`PlanningScene.radii`)."""

    waypoints: Array
    seconds: float
    radii: Array


def describe(v: Violation, clearance: float) -> str:
    """A pair that breaks the clearance, in words."""
    a, b, dist = v
    if dist < 0:
        return f"{a} overlaps {b} by {-dist * 1e3:.3g} mm"
    return f"{a} is {dist * 1e3:.3g} mm from {b} (clearance {clearance * 1e3:.3g} mm)"


# the simulator's planned moves live with the simulator (workcell.sim.planned)
__getattr__ = moved(__name__, {"PlanningCommands": "workcell.sim.planned"})
