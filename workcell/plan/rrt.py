"""A collision-free joint-space path with OMPL: RRT-Connect, then simplification.

:func:`plan_path` searches the robot's joint box (its limits) with OMPL's RRTConnect
(bidirectional rapidly-exploring random trees), states checked by a validity function
(a :class:`~workcell.plan.scene.PlanningScene`) and motions checked at joint-space
intervals of at most ``step`` (OMPL's default, about 1 % of the space's extent, misses
narrow obstacles). The path found is then shortened: vertices that can be joined directly
are removed (``reduceVertices``), then three times the path is spread over 20 states and
random shortcuts are taken between them (``partialShortcutPath``, then
``reduceVertices`` again), which pulls far-flung RRT vertices in (about 2.5x shorter
paths than one round, for ~0.1 s here); vertices closer than OMPL's collapse distance
are merged. Every new segment is checked at the same resolution. No B-spline smoothing: the result is a few straight joint-space
segments, which the simulator's motion profiles then time.

A straight segment from start to goal that is valid at that resolution is returned as
it is, without a search.

Reproducible: OMPL's random generator is re-seeded with ``seed`` before every search and
the simplification runs by iteration counts, not by time, so the same scene and seed give
the same path. ``time_limit`` (s) bounds only the search; a search that runs out of time
returns None.

OMPL objects are kept local to the call (OMPL 2.x's bindings print "leaked instances" at
exit when they are held in globals). Units: radians and metres.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

__all__ = ["plan_path", "segment_valid"]

Array = NDArray[np.float64]
_ROUNDS = 3  # shortening rounds
_SPREAD = 20  # states the path is spread over before each round of shortcuts


def segment_valid(valid: Callable[[Array], bool], a: Array, b: Array, step: float) -> bool:
    """Whether ``valid`` holds at points of the straight segment a-b at most ``step``
    apart (Euclidean, rad/m), the ends excluded; coarse to fine (halving strides), so a
    collision in the middle is found early."""
    n = max(1, math.ceil(float(np.linalg.norm(b - a)) / step))
    stride = 1 << max(0, (n - 1).bit_length() - 1)
    seen = set()
    while stride >= 1:
        for i in range(stride, n, stride):
            if i in seen:
                continue
            seen.add(i)
            if not valid(a + (b - a) * (i / n)):
                return False
        stride //= 2
    return True


def plan_path(
    valid: Callable[[Array], bool],
    q_start: Array,
    q_goal: Array,
    lower: Array,
    upper: Array,
    *,
    step: float,
    time_limit: float,
    seed: int,
) -> Array | None:
    """Waypoints (k, dof) from ``q_start`` to ``q_goal`` (both included) whose straight
    segments keep ``valid`` true at every ``step`` (rad/m), or None when the search ran
    out of ``time_limit`` (s). ``lower``/``upper``: the joint box searched."""
    q_start, q_goal = np.asarray(q_start, dtype=np.float64), np.asarray(q_goal, dtype=np.float64)
    if segment_valid(valid, q_start, q_goal, step):
        return np.array([q_start, q_goal])
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    n = len(q_start)
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    try:
        ou.RNG.setSeed(int(seed) + 1)  # 0 would ask OMPL for a random seed
        space = ob.RealVectorStateSpace(n)
        bounds = ob.RealVectorBounds(n)
        for i in range(n):
            bounds.setLow(i, float(lower[i]))
            bounds.setHigh(i, float(upper[i]))
        space.setBounds(bounds)
        si = ob.SpaceInformation(space)
        buf = np.empty(n)

        def check(state: object) -> bool:
            for i in range(n):
                buf[i] = state[i]  # type: ignore[index]
            return valid(buf)

        si.setStateValidityChecker(check)
        si.setStateValidityCheckingResolution(min(1.0, step / space.getMaximumExtent()))
        si.setup()
        start, goal = space.allocState(), space.allocState()
        start[0:n] = [float(v) for v in q_start]
        goal[0:n] = [float(v) for v in q_goal]
        pdef = ob.ProblemDefinition(si)
        pdef.setStartAndGoalStates(start, goal)
        planner = og.RRTConnect(si)
        planner.setProblemDefinition(pdef)
        planner.setup()
        status = planner.solve(ob.timedPlannerTerminationCondition(float(time_limit)))
        if not pdef.hasExactSolution() or "Exact" not in str(status):
            return None
        path = pdef.getSolutionPath()
        simplifier = og.PathSimplifier(si)
        simplifier.reduceVertices(path)
        for _ in range(_ROUNDS):
            path.interpolate(_SPREAD)
            simplifier.partialShortcutPath(path)
            simplifier.reduceVertices(path)
        simplifier.collapseCloseVertices(path)
        out = np.array(
            [[path.getState(k)[i] for i in range(n)] for k in range(path.getStateCount())]
        )
        out[0], out[-1] = q_start, q_goal  # exactly, not through OMPL's doubles round trip
        return out
    finally:
        ou.setLogLevel(level)
