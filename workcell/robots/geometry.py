"""Link solids of the built-in robots (placeholder until the geometry lands: no solids)."""

from __future__ import annotations

from workcell.robots.robot import Robot

__all__ = ["puma_geometry"]


def puma_geometry(robot: Robot, *, scale: float) -> Robot:
    """Return ``robot`` (link solids are added by the geometry builder)."""
    return robot
