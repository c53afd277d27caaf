"""The cell's logic devices: signals, sensors, conveyors, part sources and sinks.

A :class:`~workcell.cell.workcell.Workcell` holds them by name beside its parts, robots
and cameras (:class:`DeviceItems` is the mixin that adds them); the simulator evaluates
them on every frame (:mod:`workcell.sim.devices`). Lengths m, speeds m/s, times s,
positions in world coordinates.

- **signal** (:class:`Signal`): a named bool, int or float value with its initial value;
  its kind is the initial value's type (``add_signal("go", False)`` is a bool signal).
- **sensor** (:class:`Sensor`): drives a bool signal of its own name, initially false.
  ``kind="beam"``: ``start``, ``end`` points: true while a movable part crosses the
  segment; ``kind="presence"``: ``center``, ``size`` (full edge lengths of a box on the
  world axes): true while a part's centroid is inside; ``kind="proximity"``: ``origin``,
  ``direction``, ``range``, ``threshold``: the distance to the first surface along the
  ray (inf beyond ``range``), true while it is <= ``threshold``. Robots are ignored
  unless ``robots=True`` (then a beam or ray is broken by robot links too, and a
  presence box is entered by a robot's tool point).
- **conveyor** (:class:`Conveyor`): a horizontal belt whose top surface runs from
  ``start`` to ``end`` (its centre line), ``width`` across, at ``speed`` along start ->
  end, while its ``run_signal`` (a bool signal) is true (always without one); an end stop
  at ``end`` holds the parts it carries. Compiled as a belt slab
  (:data:`BELT_THICKNESS` thick, top face at the given height), a frame under it down to
  the floor, and an end stop plate (:data:`STOP_THICKNESS` thick, :data:`STOP_HEIGHT`
  above the belt) just past ``end``.
- **source** (:class:`Source`): makes copies of a movable part (its *pattern*, which
  itself stays out of the simulation) at pose ``at`` (the part frame's world pose; three
  numbers: its position, unturned), every ``every`` seconds from t = 0 or on each rising
  edge of the bool signal ``on_signal``, up to ``count`` copies (without a count, the
  limit ``max_part_copies`` of :mod:`workcell.limits`). Copies are named
  ``<part>_1``, ``<part>_2``, ... in the order they are made; these names are reserved
  from the moment the source is added. The compiled model is fixed, so each copy is a
  body of it from the start, *parked* out of the world until it is made
  (:mod:`workcell.cell.compile_devices`).
- **sink** (:class:`Sink`): a box (``center``, full edge ``size``) that removes every
  part whose centroid enters it (a part no gripper holds) and counts them; removed parts
  are parked again.

Names are cell names, unique across everything the cell holds (a sensor's signal has the
sensor's name). A failed ``add_*`` changes nothing. :func:`devices_to_dict` and
:func:`device_sections` are the JSON form (:mod:`workcell.cell.cell_json`). The devices as
values: :mod:`workcell.cell.device_types`; their JSON: :mod:`workcell.cell.device_json`
(both importable from here).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell import limits
from workcell.cell.device_json import device_sections, devices_to_dict
from workcell.cell.device_types import (
    BELT_THICKNESS,
    DEVICE_KINDS,
    MAX_SPEED,
    SENSOR_KINDS,
    SENSOR_PARAMETERS,
    STOP_HEIGHT,
    STOP_THICKNESS,
    TIME_EPS,
    Conveyor,
    Sensor,
    Signal,
    SignalValue,
    Sink,
    Source,
    check_signal_value,
    copy_names,
    format_value,
    same_value,
)
from workcell.checks import is_finite_number, shown
from workcell.errors import GeometryError, ModelError
from workcell.spatial import as_transform, translation

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
    "DeviceItems",
    "Sensor",
    "Signal",
    "SignalValue",
    "Sink",
    "Source",
    "check_signal_value",
    "copy_names",
    "device_sections",
    "devices_to_dict",
    "format_value",
    "same_value",
]

Array = NDArray[np.float64]


def _vec3(value: object, what: str) -> Array:
    values = list(value) if isinstance(value, (list, tuple, np.ndarray)) else []
    if len(values) != 3 or not all(is_finite_number(x) for x in values):
        raise GeometryError(f"{what} must be 3 finite numbers (m), got {shown(value)}")
    v = np.array(values, dtype=np.float64)
    limits.check("max_coordinate", float(np.abs(v).max()), what)
    return v


def _length(value: object, what: str, *, zero: bool = False) -> float:
    ok = is_finite_number(value) and (float(value) >= 0 if zero else float(value) > 0)  # type: ignore[arg-type]
    if not ok:
        bound = ">= 0" if zero else "> 0"
        raise GeometryError(f"{what} must be a finite number of metres {bound}, got {shown(value)}")
    v = float(value)  # type: ignore[arg-type]
    limits.check("max_coordinate", v, what)
    return v


def _sizes(value: object, what: str) -> Array:
    v = _vec3(value, what)
    if np.any(v <= 0):
        raise GeometryError(f"{what} must be 3 edge lengths > 0 (m), got {v.tolist()}")
    return v


def _read_only(a: Array) -> Array:
    a = np.array(a, dtype=np.float64)
    a.flags.writeable = False
    return a


class DeviceItems:
    """Signals, sensors, conveyors, sources and sinks of a Workcell (a mixin; module doc).

    The Workcell supplies ``_new_name(name, kind)`` (a valid, unused name or ModelError)
    and ``movable_parts``.
    """

    _signals: dict[str, Signal]
    _sensors: dict[str, Sensor]
    _conveyors: dict[str, Conveyor]
    _sources: dict[str, Source]
    _sinks: dict[str, Sink]
    _new_name: Callable[[object, str], str]
    movable_parts: Mapping[str, Any]

    def _init_devices(self) -> None:
        self._signals, self._sensors, self._conveyors = {}, {}, {}
        self._sources, self._sinks = {}, {}

    # ------------------------------------------------------------------ views
    @property
    def signals(self) -> Mapping[str, Signal]:
        """Declared signals by name (read-only view; sensors' signals are in :attr:`sensors`)."""
        return MappingProxyType(self._signals)

    @property
    def sensors(self) -> Mapping[str, Sensor]:
        """Sensors by name (read-only view)."""
        return MappingProxyType(self._sensors)

    @property
    def conveyors(self) -> Mapping[str, Conveyor]:
        """Conveyors by name (read-only view)."""
        return MappingProxyType(self._conveyors)

    @property
    def sources(self) -> Mapping[str, Source]:
        """Part sources by name (read-only view)."""
        return MappingProxyType(self._sources)

    @property
    def sinks(self) -> Mapping[str, Sink]:
        """Sinks by name (read-only view)."""
        return MappingProxyType(self._sinks)

    def _device_names(self) -> list[str]:
        return [*self._signals, *self._sensors, *self._conveyors, *self._sources, *self._sinks]

    def _device_kind(self, name: str) -> str | None:
        for kind, d in zip(
            DEVICE_KINDS,
            (self._signals, self._sensors, self._conveyors, self._sources, self._sinks),
            strict=True,
        ):
            if name in d:
                return kind
        return None

    def _reserved(self) -> dict[str, str]:
        """Copy names reserved by sources: copy name -> source name."""
        return {c: s.name for s in self._sources.values() for c in s.copies}

    def pattern_of(self, name: str) -> str:
        """The movable part whose geometry ``name`` has: a source's copy's pattern, else
        ``name`` itself."""
        for s in self._sources.values():
            if name.startswith(f"{s.part}_") and name in s.copies:
                return s.part
        return name

    def signal_kind(self, name: str) -> str:
        """The kind of signal ``name`` (a declared signal or a sensor's): ``"bool"``,
        ``"int"`` or ``"float"``; ModelError listing the signals when unknown."""
        if name in self._sensors:
            return "bool"
        if name in self._signals:
            return self._signals[name].kind
        known = ", ".join([*self._signals, *self._sensors]) or "none"
        raise ModelError(f"no signal {shown(name)} in the cell; signals: {known}")

    def _bool_signal(self, name: object, what: str) -> str:
        if not isinstance(name, str):
            raise ModelError(f"{what} must be a signal name, got {shown(name)}")
        if self.signal_kind(name) != "bool":
            raise ModelError(
                f"{what}: signal '{name}' is a {self.signal_kind(name)} signal; a bool one is "
                "needed (add_signal(name, False) declares one)"
            )
        return name

    # ------------------------------------------------------------------ adding
    def add_signal(self, name: str, initial: SignalValue) -> Signal:
        """Declare a signal with its ``initial`` value (bool, int or float: its kind)."""
        name = self._new_name(name, "signal")
        sig = Signal(name, check_signal_value(initial, f"signal '{name}': initial value"))
        self._signals[name] = sig
        return sig

    def add_sensor(self, name: str, kind: str, *, robots: bool = False, **params: Any) -> Sensor:
        """Add a sensor driving the bool signal ``name`` (module doc): ``kind`` "beam"
        (``start``, ``end``), "presence" (``center``, ``size``) or "proximity"
        (``origin``, ``direction``, ``range``, ``threshold``); m, world coordinates."""
        name = self._new_name(name, "sensor")
        what = f"sensor '{name}'"
        if kind not in SENSOR_KINDS:
            raise ModelError(
                f"{what}: unknown kind {shown(kind)}; kinds: {', '.join(SENSOR_KINDS)}"
            )
        wanted = SENSOR_PARAMETERS[kind]
        if set(params) != set(wanted):
            missing = [p for p in wanted if p not in params]
            extra = sorted(set(params) - set(wanted))
            say = "; ".join(
                x
                for x in (
                    f"missing {', '.join(missing)}" if missing else "",
                    f"unknown {', '.join(extra)}" if extra else "",
                )
                if x
            )
            raise ModelError(
                f"{what}: a {kind} sensor takes {', '.join(wanted)} (and robots); {say}"
            )
        p: dict[str, Any] = {}
        if kind == "beam":
            p["start"] = _vec3(params["start"], f"{what} start")
            p["end"] = _vec3(params["end"], f"{what} end")
            if np.linalg.norm(p["end"] - p["start"]) < 1e-6:
                raise GeometryError(f"{what}: start and end must be at least 1 um apart")
        elif kind == "presence":
            p["center"] = _vec3(params["center"], f"{what} center")
            p["size"] = _sizes(params["size"], f"{what} size")
        else:
            p["origin"] = _vec3(params["origin"], f"{what} origin")
            d = _vec3(params["direction"], f"{what} direction")
            n = float(np.linalg.norm(d))
            if n < 1e-9:
                raise GeometryError(f"{what}: direction must not be zero")
            p["direction"] = d / n
            p["range"] = _length(params["range"], f"{what} range")
            p["threshold"] = _length(params["threshold"], f"{what} threshold", zero=True)
            if p["threshold"] > p["range"]:
                raise GeometryError(
                    f"{what}: threshold {p['threshold']:.6g} m is beyond the range "
                    f"{p['range']:.6g} m"
                )
        if not isinstance(robots, (bool, np.bool_)):
            raise ModelError(f"{what}: robots must be True or False, got {shown(robots)}")
        frozen = {k: _read_only(v) if isinstance(v, np.ndarray) else v for k, v in p.items()}
        sensor = Sensor(name, kind, MappingProxyType(frozen), bool(robots))
        self._sensors[name] = sensor
        return sensor

    def add_conveyor(
        self,
        name: str,
        *,
        start: ArrayLike,
        end: ArrayLike,
        width: float,
        speed: float,
        run_signal: str | None = None,
    ) -> Conveyor:
        """Add a belt (module doc): top surface centre line ``start`` -> ``end`` (m, one
        height), ``width`` (m), ``speed`` (m/s, at most :data:`MAX_SPEED`), running while
        the bool signal ``run_signal`` is true (None: always)."""
        name = self._new_name(name, "conveyor")
        what = f"conveyor '{name}'"
        a, b = _vec3(start, f"{what} start"), _vec3(end, f"{what} end")
        if abs(a[2] - b[2]) > 1e-9:
            raise GeometryError(
                f"{what}: start and end must be at one height (a horizontal belt), got z = "
                f"{a[2]:.6g} and {b[2]:.6g} m"
            )
        if np.linalg.norm(b - a) < 1e-3:
            raise GeometryError(f"{what}: start and end must be at least 1 mm apart")
        w = _length(width, f"{what} width")
        if not (is_finite_number(speed) and 0 < float(speed) <= MAX_SPEED):
            raise GeometryError(
                f"{what}: speed must be a number of m/s in (0, {MAX_SPEED:g}], got {shown(speed)}"
            )
        sig = None if run_signal is None else self._bool_signal(run_signal, f"{what} run_signal")
        b[2] = a[2]
        belt = Conveyor(name, _read_only(a), _read_only(b), w, float(speed), sig)
        self._conveyors[name] = belt
        return belt

    def add_source(
        self,
        name: str,
        part: str,
        *,
        at: ArrayLike,
        every: float | None = None,
        count: int | None = None,
        on_signal: str | None = None,
    ) -> Source:
        """Add a source of copies of movable part ``part`` (module doc) at pose ``at`` (4x4
        of the part frame, or its position (3,)), every ``every`` s from t = 0 or on each
        rising edge of the bool signal ``on_signal`` (give one of the two), at most
        ``count`` copies (None: ``max_part_copies``)."""
        name = self._new_name(name, "source")
        what = f"source '{name}'"
        if not isinstance(part, str) or part not in self.movable_parts:
            known = ", ".join(self.movable_parts) or "none"
            raise ModelError(f"{what}: {shown(part)} is no movable part; movable parts: {known}")
        for other in self._sources.values():
            if other.part == part:
                raise ModelError(
                    f"{what}: part '{part}' is the pattern of source '{other.name}' already; "
                    "give a second source its own movable part"
                )
        try:
            shape = np.shape(at)
        except ValueError:  # ragged nested lists
            shape = None
        pose = (
            translation(*_vec3(at, f"{what} at"))
            if shape == (3,)
            else as_transform(at, rigid=True, name=f"{what} at")
        )
        if (every is None) == (on_signal is None):
            raise ModelError(f"{what}: give one of every (s) or on_signal (a bool signal)")
        if every is not None and not (is_finite_number(every) and float(every) > 0):
            raise ModelError(f"{what}: every must be a number of seconds > 0, got {shown(every)}")
        sig = None if on_signal is None else self._bool_signal(on_signal, f"{what} on_signal")
        most = int(limits.current().max_part_copies)
        if count is not None:
            if not (isinstance(count, (int, np.integer)) and not isinstance(count, bool)):
                raise ModelError(f"{what}: count must be a whole number >= 1, got {shown(count)}")
            if count < 1:
                raise ModelError(f"{what}: count must be a whole number >= 1, got {count}")
            limits.check("max_part_copies", int(count), f"{what}: count")
        pool = most if count is None else int(count)
        taken = set(self.names())  # type: ignore[attr-defined]
        clash = [c for c in copy_names(part, pool) if c in taken]
        if clash:
            raise ModelError(
                f"{what}: its copies are named {part}_1 ... {part}_{pool}, and '{clash[0]}' is "
                "taken; rename that item or the part"
            )
        src = Source(
            name,
            part,
            _read_only(pose),
            None if every is None else float(every),
            None if count is None else int(count),
            sig,
            pool,
        )
        self._sources[name] = src
        return src

    def add_sink(self, name: str, *, center: ArrayLike, size: ArrayLike) -> Sink:
        """Add a sink: a box (``center``, full edge ``size``, m) that removes and counts
        the parts whose centroid enters it."""
        name = self._new_name(name, "sink")
        what = f"sink '{name}'"
        sink = Sink(
            name,
            _read_only(_vec3(center, f"{what} center")),
            _read_only(_sizes(size, f"{what} size")),
        )
        self._sinks[name] = sink
        return sink

    def _remove_device(self, name: str, kind: str) -> None:
        """Remove device ``name`` of ``kind``; refused while another device uses it."""
        if kind in ("signal", "sensor"):
            users = [
                *(f"conveyor '{c.name}'" for c in self._conveyors.values() if c.run_signal == name),
                *(f"source '{s.name}'" for s in self._sources.values() if s.on_signal == name),
            ]
            if users:
                raise ModelError(f"cannot remove {kind} '{name}': {', '.join(users)} uses it")
        {
            "signal": self._signals,
            "sensor": self._sensors,
            "conveyor": self._conveyors,
            "source": self._sources,
            "sink": self._sinks,
        }[kind].pop(name)
