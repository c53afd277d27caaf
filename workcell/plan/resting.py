"""Moved: parts resting on something (released parts, settling, resting poses) are the
simulator's commands, in :mod:`workcell.sim.resting`; what a part rests on is found by
:mod:`workcell.plan.support`."""

from __future__ import annotations

from workcell.moved import moved

__all__ = ["RestingCommands"]  # noqa: F822 (moved; found by __getattr__)

__getattr__ = moved(__name__, {"RestingCommands": "workcell.sim.resting"})
