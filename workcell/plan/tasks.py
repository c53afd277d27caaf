"""Moved: the task-level commands ``pick``, ``place`` and ``handover`` are the
simulator's, in :mod:`workcell.sim.task_commands`; the values they choose between are in
:mod:`workcell.plan.choices`, :mod:`workcell.plan.grasps` and :mod:`workcell.plan.support`."""

from __future__ import annotations

from workcell.moved import moved

__all__ = ["TaskCommands"]  # noqa: F822 (moved; found by __getattr__)

__getattr__ = moved(__name__, {"TaskCommands": "workcell.sim.task_commands"})
