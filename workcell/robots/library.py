"""The library of built-in robots: ``library()`` names them, ``get(name)`` builds one.

Every model is built from published numbers and cites them in its docstring and in
``Robot.source`` (:mod:`workcell.robots.puma`, :mod:`workcell.robots.models`). Each has
link solids from the modeller (the Pumas' own, :mod:`workcell.robots.geometry`; the
others generated from their axes, :mod:`workcell.robots.arm_geometry`), so it is visible
and collides, and finite joint limits, speeds, accelerations and jerks.

Accelerations and jerks are not published by the manufacturers (UR's own ROS
description says so); :func:`derived_limits` derives plausible values from each
joint's published maximum speed v: a joint reaches full speed in ``RAMP_TIME`` (0.25 s)
and full acceleration in ``JERK_TIME`` (0.05 s), so a = v / 0.25 s and j = a / 0.05 s,
typical of servo-driven arms. Reach (m) is the manufacturer's figure (the Pumas': the
wrist centre's from the shoulder, computed from their DH tables).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from workcell.errors import ModelError
from workcell.robots.robot import Robot

__all__ = ["JERK_TIME", "RAMP_TIME", "Entry", "derived_limits", "entries", "get", "library"]

RAMP_TIME = 0.25  # s: from rest to a joint's maximum speed at its maximum acceleration
JERK_TIME = 0.05  # s: from zero to a joint's maximum acceleration at its maximum jerk


def derived_limits(speeds: Sequence[float]) -> tuple[list[float], list[float]]:
    """Accelerations (rad/s^2) and jerks (rad/s^3) derived from maximum speeds (rad/s)
    as the module doc says: ``a = v / RAMP_TIME``, ``j = a / JERK_TIME``."""
    acc = [float(v) / RAMP_TIME for v in speeds]
    return acc, [a / JERK_TIME for a in acc]


@dataclass(frozen=True)
class Entry:
    """A library robot: ``name``, its ``build`` (geometry: bool) -> Robot, the
    manufacturer's ``reach`` (m) and a one-line ``maker`` / model description."""

    name: str
    build: Callable[..., Robot]
    reach: float
    maker: str


def _puma(which: str) -> Callable[..., Robot]:
    def build(*, geometry: bool = True) -> Robot:
        from workcell.robots import puma

        return getattr(puma, which)(geometry=geometry)

    return build


_DARK = (0.2, 0.2, 0.22, 1.0)
_COLOURS = {  # links, drums, base and flange (RGBA): the makers' usual paint
    "abb": ((0.93, 0.93, 0.92, 1.0), (0.80, 0.80, 0.80, 1.0), _DARK),
    "fanuc": ((0.98, 0.80, 0.10, 1.0), (0.92, 0.72, 0.05, 1.0), _DARK),
    "kuka": ((0.98, 0.45, 0.05, 1.0), (0.90, 0.40, 0.05, 1.0), _DARK),
    "ur": ((0.86, 0.86, 0.84, 1.0), (0.35, 0.45, 0.60, 1.0), _DARK),
}


def _model(which: str) -> Callable[..., Robot]:
    def build(*, geometry: bool = True) -> Robot:
        from workcell.robots import models
        from workcell.robots.arm_geometry import chain_geometry

        robot = getattr(models, which)()
        colours = _COLOURS[which.split("_")[0] if "_" in which else "ur"]
        return chain_geometry(robot, colours=colours) if geometry else robot

    return build


_ENTRIES = {
    e.name: e
    for e in (
        Entry("abb_irb120", _model("abb_irb120"), 0.580, "ABB IRB 120-3/0.6"),
        Entry("abb_irb140", _model("abb_irb140"), 0.810, "ABB IRB 140"),
        Entry("abb_irb2400", _model("abb_irb2400"), 1.550, "ABB IRB 2400/10"),
        Entry("fanuc_lrmate200id", _model("fanuc_lrmate200id"), 0.717, "FANUC LR Mate 200iD"),
        Entry("kuka_kr16", _model("kuka_kr16"), 1.611, "KUKA KR 16-2"),
        Entry("kuka_kr6_r700", _model("kuka_kr6_r700"), 0.7067, "KUKA KR 6 R700 sixx"),
        # Pumas: no manufacturer figure in the sources; the wrist centre's reach from the
        # shoulder, a2 + sqrt(a3^2 + d4^2), from the DH tables
        Entry("puma260", _puma("puma260"), 0.4022, "Unimation Puma 260"),
        Entry("puma560", _puma("puma560"), 0.8641, "Unimation Puma 560"),
        Entry("ur10e", _model("ur10e"), 1.300, "Universal Robots UR10e"),
        Entry("ur3e", _model("ur3e"), 0.500, "Universal Robots UR3e"),
        Entry("ur5e", _model("ur5e"), 0.850, "Universal Robots UR5e"),
    )
}


def library() -> list[str]:
    """The built-in robot names, sorted."""
    return sorted(_ENTRIES)


def entries() -> list[Entry]:
    """The library's entries, sorted by name."""
    return [_ENTRIES[n] for n in library()]


def get(name: str, *, geometry: bool = True) -> Robot:
    """The library robot ``name`` (with its link solids unless ``geometry=False``).

    ModelError listing the names for an unknown one.
    """
    if not isinstance(name, str) or name not in _ENTRIES:
        raise ModelError(f"unknown robot {name!r}; the library has: {', '.join(library())}")
    return _ENTRIES[name].build(geometry=geometry)
