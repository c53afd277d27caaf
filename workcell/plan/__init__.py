"""Collision-free motion and the planners of task-level commands (the thesis's future
work, §6), on plain values: the simulator calls them, they never import it.

- :mod:`workcell.plan.scene`: collision checks of robots' configurations (planning
  scenes) in a copy of a simulator's state (:class:`~workcell.plan.scene.SceneSource`);
- :mod:`workcell.plan.rrt`: OMPL's RRT-Connect and shortening, motions checked densely;
- :mod:`workcell.plan.motion`: the planning settings and planned paths;
- :mod:`workcell.plan.grasps`, :mod:`workcell.plan.choices`: grasp poses and what
  task-level commands choose between;
- :mod:`workcell.plan.support`: what parts rest on.

The commands that use them are the simulator's: ``plan=True`` and ``set_planning``
(:mod:`workcell.sim.planned`), ``pick``, ``place``, ``handover``
(:mod:`workcell.sim.task_commands`), settling (:mod:`workcell.sim.resting`). Seeded
random planning problems: :mod:`workcell.examples.plan_problems`. The names below are
imported on first use.
"""

from __future__ import annotations

import importlib
from typing import Any

from workcell.moved import moved

__all__ = ["PlanningError", "PlanningOptions", "PlanningScene", "plan_path", "random_problem"]

_WHERE = {
    "PlanningError": "workcell.errors",
    "PlanningOptions": "workcell.plan.motion",
    "PlanningScene": "workcell.plan.scene",
    "plan_path": "workcell.plan.rrt",
}
_MOVED = moved(__name__, {"random_problem": "workcell.examples.plan_problems"})


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(importlib.import_module(_WHERE[name]), name)
    return _MOVED(name)


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
