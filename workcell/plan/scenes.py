"""Moved: the seeded random planning problems and the independent re-check of a run
build simulators, so they live above the simulator, in
:mod:`workcell.examples.plan_problems`."""

from __future__ import annotations

from workcell.moved import moved

__all__ = ["ROBOT", "Problem", "penetrations", "random_problem"]  # noqa: F822 (moved)

__getattr__ = moved(
    __name__,
    dict.fromkeys(__all__, "workcell.examples.plan_problems"),
)
