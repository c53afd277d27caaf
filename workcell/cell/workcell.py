"""The workcell: parts, robots and cameras placed in the world (thesis ch. 4.4).

A :class:`Workcell` holds one modeller :class:`~workcell.Model` (``cell.model``) for all
part geometry and, by name:

- static parts: a block or object of the model at a world pose (4x4 rigid, m), coloured
  (without a colour of its own or given, the next of :data:`STATIC_COLOURS`, muted
  tones; movable parts take the next of :data:`MOVABLE_COLOURS`, vivid ones; robots keep
  their links' colours: pale arms, dark bases, orange fingers);
- movable parts: the same plus a density (kg/m^3); mass, bounding box and centroid frame
  (the thesis's grasp data) are computed from the geometry, never stored;
- robots: a :class:`~workcell.robots.Robot` (a library robot by name,
  :func:`workcell.robots.library`, or any Robot; optionally with a
  :func:`~workcell.robots.parallel_gripper`) at a world base pose (composed with the
  robot's own ``base``) with initial joint values;
- cameras: a position, a look-at target and a vertical field of view (deg).

Names are unique across all four kinds and MJCF-safe: a letter or '_' followed by
letters, digits, '_' or '-' (no '.', which separates robot prefixes in the compiled
model, and no '/', which dm_control reserves). A failed ``add_*`` changes nothing.

Saved as versioned JSON (:mod:`workcell.cell.cell_json`): the model, the parts, robots
(as their built-in name, their robot file or their chain inline,
:mod:`workcell.cell.robot_json`) and cameras. The records a cell holds (parts, robot
placements, cameras), its name rule and default colours are in
:mod:`workcell.cell.items` and importable from here too.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from workcell import limits
from workcell.cell.cell_json import FORMAT, VERSION, cell_from_dict, cell_to_dict
from workcell.cell.devices import DeviceItems
from workcell.cell.items import (
    BUILTIN_ROBOTS,
    GRIPPER_PARAMETERS,
    MOVABLE_COLOURS,
    STATIC_COLOURS,
    Array,
    Camera,
    MovablePart,
    RobotPlacement,
    StaticPart,
    build_robot,
    check_cell_name,
)
from workcell.cell.items import look_at as look_at  # importable from here as before
from workcell.checks import is_finite_number
from workcell.errors import GeometryError, ModelError, WorkcellError
from workcell.files import atomic_write_text, load_json
from workcell.modeller.model import Model, check_colour
from workcell.robots import attach_gripper, parallel_gripper
from workcell.robots.robot import Robot
from workcell.spatial import as_transform, translation

__all__ = [
    "BUILTIN_ROBOTS",
    "FORMAT",
    "GRIPPER_PARAMETERS",
    "MOVABLE_COLOURS",
    "STATIC_COLOURS",
    "VERSION",
    "Camera",
    "MovablePart",
    "RobotPlacement",
    "StaticPart",
    "Workcell",
    "check_cell_name",
]

_ENTITY_LEVELS = ("block", "object")


def _vec3(value: object, what: str) -> Array:
    values = list(value) if isinstance(value, (list, tuple, np.ndarray)) else []
    if len(values) != 3 or not all(is_finite_number(x) for x in values):
        raise GeometryError(f"{what} must be 3 finite numbers (m), got {value!r}")
    v = np.array(values, dtype=np.float64)
    limits.check("max_coordinate", float(np.abs(v).max()), what)
    return v


class Workcell(DeviceItems):
    """A workcell: parts, robots and cameras by unique name (see the module doc), and
    logic devices: signals, sensors, conveyors, part sources and sinks
    (:mod:`workcell.cell.devices`)."""

    def __init__(self, name: str = "workcell", model: Model | None = None) -> None:
        self.name = check_cell_name(name, "cell")
        self.model = Model() if model is None else model
        self._static: dict[str, StaticPart] = {}
        self._movable: dict[str, MovablePart] = {}
        self._robots: dict[str, RobotPlacement] = {}
        self._cameras: dict[str, Camera] = {}
        self._init_devices()

    # ------------------------------------------------------------------ views
    @property
    def static_parts(self) -> Mapping[str, StaticPart]:
        """Static parts by name (read-only view, in insertion order)."""
        return MappingProxyType(self._static)

    @property
    def movable_parts(self) -> Mapping[str, MovablePart]:
        """Movable parts by name (read-only view)."""
        return MappingProxyType(self._movable)

    @property
    def robots(self) -> Mapping[str, RobotPlacement]:
        """Robots by name (read-only view)."""
        return MappingProxyType(self._robots)

    @property
    def cameras(self) -> Mapping[str, Camera]:
        """Cameras by name (read-only view)."""
        return MappingProxyType(self._cameras)

    def names(self) -> list[str]:
        """Every name in the cell (static, movable, robots, cameras, then the devices:
        signals, sensors, conveyors, sources, sinks)."""
        return [*self._static, *self._movable, *self._robots, *self._cameras, *self._device_names()]

    def kind_of(self, name: str) -> str:
        """``"static"``, ``"movable"``, ``"robot"``, ``"camera"`` or a device kind
        (``"signal"``, ``"sensor"``, ``"conveyor"``, ``"source"``, ``"sink"``); ModelError
        when unknown."""
        device = self._device_kind(name)
        if device is not None:
            return device
        for kind, d in (
            ("static", self._static),
            ("movable", self._movable),
            ("robot", self._robots),
            ("camera", self._cameras),
        ):
            if name in d:
                return kind
        raise ModelError(f"no part, robot or camera '{name}' in the cell; known: {self._known()}")

    def _known(self) -> str:
        return ", ".join(self.names()) or "none"

    def _new_name(self, name: object, kind: str) -> str:
        name = check_cell_name(name, kind)
        if name in self.names():
            raise ModelError(
                f"{kind} name '{name}' is taken (by a {self.kind_of(name)}); names are unique "
                f"across parts, robots, cameras and devices; taken: {self._known()}"
            )
        source = self._reserved().get(name)
        if source is not None:
            raise ModelError(
                f"{kind} name '{name}' is reserved for a copy made by source '{source}'"
            )
        return name

    def _entity(self, entity: object, what: str) -> tuple[str, str]:
        m = self.model
        known = ", ".join(f"{lv} '{n}'" for lv in _ENTITY_LEVELS for n in m.list(lv)) or "none"
        if isinstance(entity, (tuple, list)) and len(entity) == 2:
            ref: Any = (str(entity[0]), str(entity[1]))
        elif isinstance(entity, str):
            ref = entity
        else:
            raise ModelError(f"{what}: entity must be a name or (level, name), got {entity!r}")
        try:
            level = m.level_of(ref)
        except (ModelError, KeyError, ValueError) as exc:
            raise ModelError(
                f"{what}: unknown entity {entity!r}; blocks and objects: {known}"
            ) from exc
        if level not in _ENTITY_LEVELS:
            raise ModelError(
                f"{what}: entity {entity!r} is a {level}; a part is a block or an object ({known})"
            )
        name = ref if isinstance(ref, str) else ref[1]
        return level, name

    def _colour(
        self,
        colour: ArrayLike | None,
        entity: tuple[str, str],
        what: str,
        palette: tuple[tuple[float, ...], ...],
        index: int,
    ) -> tuple[float, ...]:
        """The given colour, else the entity's own, else ``palette[index]`` (cycled)."""
        if colour is None:
            own = self.model.info(entity).colour
            return tuple(own) if own is not None else palette[index % len(palette)]
        try:
            return check_colour(colour)
        except ModelError as exc:
            raise ModelError(f"{what}: {exc}") from exc

    # ------------------------------------------------------------------ adding
    def add_static(
        self,
        name: str,
        entity: str | tuple[str, str],
        pose: ArrayLike | None = None,
        *,
        colour: ArrayLike | None = None,
    ) -> StaticPart:
        """Add a static part: ``entity`` (block or object) at world ``pose`` (4x4 rigid, m)."""
        name = self._new_name(name, "static part")
        what = f"static part '{name}'"
        ent = self._entity(entity, what)
        T = as_transform(np.eye(4) if pose is None else pose, rigid=True, name=f"{what} pose")
        if len(self.model.world_mesh(ent).faces) == 0:
            raise GeometryError(f"{what}: entity {ent[0]} '{ent[1]}' is empty (no faces)")
        rgba = self._colour(colour, ent, what, STATIC_COLOURS, len(self._static))
        part = StaticPart(name, ent, T, rgba)
        self._static[name] = part
        return part

    def add_movable(
        self,
        name: str,
        entity: str | tuple[str, str],
        pose: ArrayLike | None = None,
        *,
        density: float,
        colour: ArrayLike | None = None,
    ) -> MovablePart:
        """Add a movable part of ``density`` (kg/m^3): a free body when compiled."""
        name = self._new_name(name, "movable part")
        what = f"movable part '{name}'"
        ent = self._entity(entity, what)
        T = as_transform(np.eye(4) if pose is None else pose, rigid=True, name=f"{what} pose")
        if not (is_finite_number(density) and density > 0):
            raise GeometryError(
                f"{what}: density must be a positive number (kg/m^3), got {density!r}"
            )
        volume = self.model.properties(ent).volume
        if not volume > 0:
            raise GeometryError(
                f"{what}: entity {ent[0]} '{ent[1]}' has volume {volume:.3g} m^3; a movable "
                "part needs a closed solid with positive volume"
            )
        rgba = self._colour(colour, ent, what, MOVABLE_COLOURS, len(self._movable))
        part = MovablePart(name, ent, T, rgba, float(density))
        self._movable[name] = part
        return part

    def add_robot(
        self,
        name: str,
        robot: str | Robot | RobotPlacement = "puma260",
        *,
        gripper: Mapping[str, Any] | bool | None = None,
        base: ArrayLike | None = None,
        q: ArrayLike | None = None,
    ) -> RobotPlacement:
        """Add a robot: a library name (``workcell.robots.library()``: "ur5e", "puma260",
        "kuka_kr6_r700", ...), a :class:`Robot`, or the :class:`RobotPlacement` of another
        cell (its robot as placed, saved as it was: library name, gripper, file; ``base``
        and ``q`` default to the placement's; ``gripper`` must be None).

        ``gripper``: True for the default :func:`parallel_gripper`, a mapping of its
        parameters, or None for none (a ``Robot`` may already carry one). ``base`` (4x4
        rigid) places the robot's base frame in the world. ``q`` (rad/m) defaults to the
        robot's "home" pose if it has one, else zeros; it must lie within the limits.
        Any Robot is saved with the cell (:mod:`workcell.cell.robot_json`: a robot read
        from a file as its file, others inline).
        """
        name = self._new_name(name, "robot")
        what = f"robot '{name}'"
        params: dict[str, Any] | None
        if gripper is True:
            params = {}
        elif gripper is None or gripper is False:
            params = None
        elif isinstance(gripper, Mapping):
            params = dict(gripper)
        else:
            raise ModelError(
                f"{what}: gripper must be True, None or a mapping of parallel_gripper parameters"
            )
        bare: Robot | None = None
        if isinstance(robot, RobotPlacement):
            if params is not None:
                raise ModelError(f"{what}: a placed robot keeps its gripper; give gripper=None")
            base = robot.base if base is None else base
            q = robot.q if q is None else q
            params, bare = robot.gripper_parameters, robot.bare
        try:
            if isinstance(robot, RobotPlacement):
                builtin, r = robot.builtin, robot.robot
            elif isinstance(robot, str):
                builtin: str | None = robot
                r = build_robot(robot, params)
            elif isinstance(robot, Robot):
                builtin = None
                r = (
                    attach_gripper(robot, parallel_gripper(**params))
                    if params is not None
                    else robot
                )
            else:
                raise ModelError(f"robot must be a built-in name or a Robot, got {robot!r}")
        except WorkcellError as exc:
            raise type(exc)(f"{what}: {exc}") from exc
        except TypeError as exc:  # a wrong gripper parameter value type
            raise ModelError(f"{what}: bad gripper parameters {params!r}: {exc}") from exc
        B = as_transform(np.eye(4) if base is None else base, rigid=True, name=f"{what} base")
        q0 = (r.pose("home") if "home" in r.poses else np.zeros(r.dof)) if q is None else q
        try:
            qv = r.check_limits(q0).copy()
        except WorkcellError as exc:
            raise ModelError(f"{what}: initial q: {exc}") from exc
        if isinstance(robot, Robot) and r is not robot:
            bare = robot
        placed = RobotPlacement(name, r, B, qv, builtin, params, bare)
        self._robots[name] = placed
        return placed

    def add_camera(
        self, name: str, position: ArrayLike, target: ArrayLike, fovy: float = 45.0
    ) -> Camera:
        """Add a camera at ``position`` looking at ``target`` (m), vertical field ``fovy`` (deg, (0, 180))."""
        name = self._new_name(name, "camera")
        what = f"camera '{name}'"
        p = _vec3(position, f"{what} position")
        t = _vec3(target, f"{what} target")
        if np.linalg.norm(p - t) < 1e-9:
            raise GeometryError(f"{what}: target must differ from position, both are {p.tolist()}")
        if not (is_finite_number(fovy) and 0 < fovy < 180):
            raise GeometryError(f"{what}: fovy must be in (0, 180) deg, got {fovy!r}")
        cam = Camera(name, p, t, float(fovy))
        self._cameras[name] = cam
        return cam

    def remove(self, name: str) -> None:
        """Remove the part, robot, camera or device ``name`` (the model's entities stay);
        refused for a part a source copies and a signal a device uses."""
        kind = self.kind_of(name)
        if self._device_kind(name) is not None:
            self._remove_device(name, kind)
            return
        users = [s.name for s in self._sources.values() if s.part == name]
        if users:
            raise ModelError(f"cannot remove part '{name}': source '{users[0]}' copies it")
        {
            "static": self._static,
            "movable": self._movable,
            "robot": self._robots,
            "camera": self._cameras,
        }[kind].pop(name)

    # ------------------------------------------------------------------ grasp data
    def _movable_part(self, name: str) -> MovablePart:
        if name not in self._movable:
            raise ModelError(
                f"no movable part '{name}'; movable parts: {', '.join(self._movable) or 'none'}"
            )
        return self._movable[name]

    def mass(self, name: str) -> float:
        """Mass (kg) of movable part ``name``: density x volume."""
        p = self._movable_part(name)
        return p.density * float(self.model.properties(p.entity).volume)

    def bounding_box(self, name: str) -> tuple[Array, Array]:
        """Axis-aligned box (lower, upper corners, m) of movable part ``name`` in its part frame."""
        p = self._movable_part(name)
        lo, hi = self.model.world_mesh(p.entity).bounds
        return np.array(lo, dtype=np.float64), np.array(hi, dtype=np.float64)

    def centroid_frame(self, name: str) -> Array:
        """The part's centroid frame in its part frame: axes of the part frame, origin at the centroid."""
        p = self._movable_part(name)
        return translation(*self.model.properties(p.entity).centroid)

    # ------------------------------------------------------------------ storage
    def to_dict(
        self, base_dir: str | os.PathLike | None = None, *, kinematics: bool = False
    ) -> dict:
        """The cell as JSON-able data. A robot is its library name, its robot file
        (path relative to ``base_dir`` when given, else absolute) or its chain inline
        (:mod:`workcell.cell.robot_json`); ModelError for one that cannot be saved.
        ``kinematics``: a robot file's entry also carries the robot's kinematics, for a
        reader without the file (what a server sends its clients)."""
        return cell_to_dict(self, base_dir, kinematics=kinematics)

    @classmethod
    def from_dict(
        cls,
        data: object,
        *,
        source: str = "cell data",
        base_dir: str | os.PathLike | None = None,
        root: str | os.PathLike | None = None,
    ) -> Workcell:
        """Rebuild a cell from :meth:`to_dict` data; ModelError naming the faulty place.

        Robot file paths are relative to ``base_dir`` (absolute when None); with ``root``
        (a server's folder) no robot file outside it is read.
        """
        return cell_from_dict(cls, data, source=source, base_dir=base_dir, root=root)

    def save(self, path: str | os.PathLike) -> None:
        """Write the cell as versioned JSON, atomically; a failed write raises ModelError.
        Robot files are named relative to the cell file's folder."""
        folder = Path(os.path.abspath(path)).parent
        text = json.dumps(self.to_dict(base_dir=folder), allow_nan=False)
        atomic_write_text(path, text, error=ModelError)

    @classmethod
    def load(cls, path: str | os.PathLike, *, root: str | os.PathLike | None = None) -> Workcell:
        """Read a cell saved by :meth:`save`; a damaged file raises ModelError naming the
        place (never quoting a file that is not a cell file); so do a robot file that is
        missing or changed. ``root``: robot files must lie inside this folder."""
        data = load_json(path, what="cell file", error=ModelError)
        folder = Path(os.path.abspath(path)).parent
        return cls.from_dict(data, source=f"cell file '{path}'", base_dir=folder, root=root)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Workcell) and self.to_dict() == other.to_dict()

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        devices = len(self._device_names())
        more = f", {devices} devices" if devices else ""
        return (
            f"Workcell({self.name!r}: {len(self._static)} static, {len(self._movable)} movable, "
            f"{len(self._robots)} robots, {len(self._cameras)} cameras{more})"
        )
