"""The cell's devices as values (:mod:`workcell.cell.devices` says what each one does and
adds them to a cell): signal values and how they compare and read, the five kinds of
device (:class:`Signal`, :class:`Sensor`, :class:`Conveyor`, :class:`Source`,
:class:`Sink`) and the constants of their geometry. Lengths m, speeds m/s, times s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell.checks import shown
from workcell.errors import ModelError

__all__ = [
    "BELT_THICKNESS",
    "DEVICE_KINDS",
    "MAX_SPEED",
    "SENSOR_KINDS",
    "SENSOR_PARAMETERS",
    "STOP_HEIGHT",
    "STOP_THICKNESS",
    "TIME_EPS",
    "Conveyor",
    "Sensor",
    "Signal",
    "SignalValue",
    "Sink",
    "Source",
    "check_signal_value",
    "copy_names",
    "format_value",
    "same_value",
]

Array = NDArray[np.float64]
SignalValue = bool | int | float
SENSOR_KINDS = ("beam", "presence", "proximity")
SENSOR_PARAMETERS: Mapping[str, tuple[str, ...]] = MappingProxyType(
    {
        "beam": ("start", "end"),
        "presence": ("center", "size"),
        "proximity": ("origin", "direction", "range", "threshold"),
    }
)
DEVICE_KINDS = ("signal", "sensor", "conveyor", "source", "sink")
BELT_THICKNESS = 0.02  # m: the belt slab under the top surface
STOP_THICKNESS = 0.01  # m: the end stop plate, along the belt
STOP_HEIGHT = 0.03  # m: how far the end stop rises above the belt
MAX_SPEED = 10.0  # m/s: the fastest belt
TIME_EPS = 1e-9  # s: simulated times closer than this are one time


def check_signal_value(value: object, what: str) -> SignalValue:
    """``value`` as a signal value (a bool, an int or a finite float; numpy scalars become
    Python ones), else ModelError."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)) and math.isfinite(float(value)):
        return float(value)
    raise ModelError(f"{what} must be a bool, an int or a finite float, got {shown(value)}")


def format_value(v: object) -> str:
    """A signal value as people read it: true/false, 3, 0.25."""
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def same_value(a: object, b: object) -> bool:
    """Whether two signal values are equal (a bool equals only a bool)."""
    return a == b and isinstance(a, bool) == isinstance(b, bool)


@dataclass(frozen=True)
class Signal:
    """A named value of the cell: ``initial`` is a bool, an int or a float, and its type is
    the signal's kind (:attr:`kind`)."""

    name: str
    initial: SignalValue

    @property
    def kind(self) -> str:
        """``"bool"``, ``"int"`` or ``"float"``."""
        return type(self.initial).__name__


@dataclass(frozen=True, eq=False)
class Sensor:
    """A sensor (module doc): ``kind`` one of :data:`SENSOR_KINDS`, its ``params`` by name
    (points and vectors as read-only (3,) arrays, m; ``direction`` a unit vector), and
    ``robots``: robot links break its beam or ray, a robot's tool point enters its box."""

    name: str
    kind: str
    params: Mapping[str, Any]
    robots: bool = False


@dataclass(frozen=True, eq=False)
class Conveyor:
    """A belt (module doc): top surface centre line ``start`` -> ``end`` (m, world, at one
    height), ``width`` (m), ``speed`` (m/s) and the bool ``run_signal`` (None: always
    running). :attr:`direction` is the unit vector start -> end, :attr:`length` (m) and
    :attr:`top` (m, the belt's height) follow."""

    name: str
    start: Array
    end: Array
    width: float
    speed: float
    run_signal: str | None = None

    @property
    def direction(self) -> Array:
        d = self.end - self.start
        return d / np.linalg.norm(d)

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.end - self.start))

    @property
    def top(self) -> float:
        return float(self.start[2])


@dataclass(frozen=True, eq=False)
class Source:
    """A part source (module doc): copies of movable part ``part`` at world pose ``at``
    (4x4 of the part frame), every ``every`` s or on rising edges of ``on_signal``, at most
    ``count`` (None: the pool limit); ``pool``: how many copies it can make (``count``, or
    ``max_part_copies`` when it was added). :attr:`copies` are their names."""

    name: str
    part: str
    at: Array
    every: float | None = None
    count: int | None = None
    on_signal: str | None = None
    pool: int = field(default=1)

    @property
    def copies(self) -> tuple[str, ...]:
        return copy_names(self.part, self.pool)


@dataclass(frozen=True, eq=False)
class Sink:
    """A sink: a box on the world axes (``center``, full edge ``size``, m) that removes and
    counts the parts whose centroid enters it."""

    name: str
    center: Array
    size: Array


def copy_names(part: str, n: int) -> tuple[str, ...]:
    """The names of a source's first ``n`` copies of ``part``: ``part_1`` ... ``part_n``."""
    return tuple(f"{part}_{k}" for k in range(1, n + 1))
