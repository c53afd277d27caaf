"""Collision-free motion and task-level commands (the thesis's future work, §6).

- :mod:`workcell.plan.scene`: collision checks of robots' configurations (planning scenes);
- :mod:`workcell.plan.rrt`: OMPL's RRT-Connect and shortening, motions checked densely;
- :mod:`workcell.plan.motion`: ``plan=True`` on the simulator's moves, ``set_planning``;
- :mod:`workcell.plan.grasps`, :mod:`workcell.plan.choices`, :mod:`workcell.plan.tasks`:
  ``pick``, ``place``, ``handover``;
- :mod:`workcell.plan.support`, :mod:`workcell.plan.resting`: what parts rest on;
- :mod:`workcell.plan.scenes`: seeded random planning problems and an independent re-check.

The simulator mixes these in, and they use the simulator's modules: the simulator is
imported first (below), so that whichever module is imported first, ``workcell.sim``
finishes loading these mixins before they are used. The names below are imported on
first use.
"""

from __future__ import annotations

import importlib
from typing import Any

import workcell.sim  # noqa: F401  (first: see the module doc)

__all__ = ["PlanningError", "PlanningOptions", "PlanningScene", "plan_path", "random_problem"]

_WHERE = {
    "PlanningError": "workcell.errors",
    "PlanningOptions": "workcell.plan.motion",
    "PlanningScene": "workcell.plan.scene",
    "plan_path": "workcell.plan.rrt",
    "random_problem": "workcell.plan.scenes",
}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(importlib.import_module(_WHERE[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
