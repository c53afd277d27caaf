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

Saved as versioned JSON (``format: "workcell-cell", version: 1``); the model through
:meth:`Model.to_dict`, robots as their built-in name plus gripper parameters.
"""

from __future__ import annotations

import functools
import json
import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell import limits
from workcell.checks import is_finite_number
from workcell.errors import GeometryError, ModelError, WorkcellError
from workcell.files import atomic_write_text, load_json
from workcell.modeller.model import MAX_NAME_LENGTH, Model, check_colour
from workcell.robots import attach_gripper, get, library, parallel_gripper
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

FORMAT = "workcell-cell"
VERSION = 1
# the default colours (RGBA), by kind, one after another per part: muted tones for what
# stands still, vivid ones for what robots carry, none close to the robots' pale arms,
# dark bases and orange fingers, nor to the blue-grey floor of the pictures
STATIC_COLOURS = (
    (0.55, 0.45, 0.35, 1.0),  # wood
    (0.36, 0.50, 0.72, 1.0),  # slate blue
    (0.42, 0.62, 0.45, 1.0),  # sage
    (0.72, 0.64, 0.46, 1.0),  # sand
    (0.56, 0.42, 0.58, 1.0),  # mauve
    (0.40, 0.62, 0.64, 1.0),  # teal
)
MOVABLE_COLOURS = (
    (0.86, 0.18, 0.14, 1.0),  # red
    (0.15, 0.62, 0.25, 1.0),  # green
    (0.96, 0.78, 0.10, 1.0),  # yellow
    (0.14, 0.42, 0.92, 1.0),  # blue
    (0.82, 0.22, 0.72, 1.0),  # magenta
    (0.10, 0.78, 0.82, 1.0),  # cyan
)
BUILTIN_ROBOTS: Mapping[str, Callable[[], Robot]] = MappingProxyType(
    {name: functools.partial(get, name) for name in library()}
)
"""The library robots by name (:func:`workcell.robots.get`), as the cell builds them."""
GRIPPER_PARAMETERS = (
    "name",
    "max_opening",
    "finger_length",
    "finger_width",
    "finger_thickness",
    "palm_height",
    "tcp_depth",
)
_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_\-]*")
_ENTITY_LEVELS = ("block", "object")

Array = NDArray[np.float64]


def check_cell_name(name: object, kind: str = "item") -> str:
    """Return ``name`` if it is a valid (MJCF-safe) cell name, else raise ModelError."""
    if not isinstance(name, str) or len(name) > MAX_NAME_LENGTH or not _NAME_RE.fullmatch(name):
        shown = repr(name) if len(repr(name)) <= 60 else repr(name)[:57] + "..."
        raise ModelError(
            f"invalid {kind} name {shown}: use a letter or '_' followed by letters, digits, "
            f"'_' or '-' (no '.', no '/'), at most {MAX_NAME_LENGTH} characters"
        )
    return name


@dataclass(frozen=True, eq=False)
class StaticPart:
    """A fixed part: ``entity`` (level, name) of the cell's model at world ``pose`` (4x4)."""

    name: str
    entity: tuple[str, str]
    pose: Array
    colour: tuple[float, ...]


@dataclass(frozen=True, eq=False)
class MovablePart:
    """A movable part (free body when compiled): as :class:`StaticPart` plus ``density`` (kg/m^3)."""

    name: str
    entity: tuple[str, str]
    pose: Array
    colour: tuple[float, ...]
    density: float


@dataclass(frozen=True, eq=False)
class RobotPlacement:
    """A robot in the cell.

    ``robot`` as built (gripper attached if any); ``base`` (4x4) the world pose of the
    robot's base frame, so the world pose of its tool is ``base @ robot.fk(q)``; ``q``
    the initial joint values (rad/m). ``builtin`` names the library robot it came from
    ("ur5e", "puma260", ...; None for a custom robot) and ``gripper_parameters`` the
    :func:`parallel_gripper` arguments (None: no gripper, or a custom one).
    """

    name: str
    robot: Robot
    base: Array
    q: Array
    builtin: str | None = None
    gripper_parameters: Mapping[str, Any] | None = field(default=None)

    @property
    def world_base(self) -> Array:
        """World pose of the robot's link 0 body: ``base @ robot.base``."""
        return self.base @ self.robot.base

    def tool_pose(self, q: ArrayLike | None = None) -> Array:
        """World pose of the tool at ``q`` (default: the initial q)."""
        return self.base @ self.robot.fk(self.q if q is None else q)


@dataclass(frozen=True, eq=False)
class Camera:
    """A named camera at ``position`` looking at ``target`` (m) with vertical field ``fovy`` (deg)."""

    name: str
    position: Array
    target: Array
    fovy: float

    def pose(self) -> Array:
        """World pose of the camera frame (MuJoCo convention: looks along -z, y up)."""
        return look_at(self.position, self.target)


def look_at(position: ArrayLike, target: ArrayLike) -> Array:
    """Camera frame at ``position`` whose -z axis points to ``target``; x horizontal.

    When the view is vertical the world y axis serves as the up hint instead of z.
    """
    p = np.asarray(position, dtype=np.float64)
    z = p - np.asarray(target, dtype=np.float64)
    z = z / np.linalg.norm(z)
    up = np.array([0.0, 0.0, 1.0])
    if abs(z @ up) > 1 - 1e-9:
        up = np.array([0.0, 1.0, 0.0])
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, y, z, p
    return T


def _vec3(value: object, what: str) -> Array:
    values = list(value) if isinstance(value, (list, tuple, np.ndarray)) else []
    if len(values) != 3 or not all(is_finite_number(x) for x in values):
        raise GeometryError(f"{what} must be 3 finite numbers (m), got {value!r}")
    v = np.array(values, dtype=np.float64)
    limits.check("max_coordinate", float(np.abs(v).max()), what)
    return v


def build_robot(builtin: str, gripper: Mapping[str, Any] | None) -> Robot:
    """The library robot ``builtin`` with a parallel gripper of ``gripper`` parameters (or none)."""
    if builtin not in BUILTIN_ROBOTS:
        raise ModelError(f"unknown built-in robot {builtin!r}; known: {', '.join(BUILTIN_ROBOTS)}")
    robot = get(builtin)
    if gripper is None:
        return robot
    if not isinstance(gripper, Mapping):
        raise ModelError(f"gripper parameters must be a mapping, got {gripper!r}")
    bad = sorted(set(gripper) - set(GRIPPER_PARAMETERS))
    if bad:
        raise ModelError(
            f"unknown gripper parameter(s) {bad}; valid: {', '.join(GRIPPER_PARAMETERS)}"
        )
    return attach_gripper(robot, parallel_gripper(**gripper))


class Workcell:
    """A workcell: parts, robots and cameras by unique name (see the module doc)."""

    def __init__(self, name: str = "workcell", model: Model | None = None) -> None:
        self.name = check_cell_name(name, "cell")
        self.model = Model() if model is None else model
        self._static: dict[str, StaticPart] = {}
        self._movable: dict[str, MovablePart] = {}
        self._robots: dict[str, RobotPlacement] = {}
        self._cameras: dict[str, Camera] = {}

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
        """Every name in the cell (static, movable, robots, cameras)."""
        return [*self._static, *self._movable, *self._robots, *self._cameras]

    def kind_of(self, name: str) -> str:
        """``"static"``, ``"movable"``, ``"robot"`` or ``"camera"``; ModelError when unknown."""
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
                f"across parts, robots and cameras; taken: {self._known()}"
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
        robot: str | Robot = "puma260",
        *,
        gripper: Mapping[str, Any] | bool | None = None,
        base: ArrayLike | None = None,
        q: ArrayLike | None = None,
    ) -> RobotPlacement:
        """Add a robot: a library name (``workcell.robots.library()``: "ur5e", "puma260",
        "kuka_kr6_r700", ...) or a :class:`Robot`.

        ``gripper``: True for the default :func:`parallel_gripper`, a mapping of its
        parameters, or None for none (a ``Robot`` may already carry one). ``base`` (4x4
        rigid) places the robot's base frame in the world. ``q`` (rad/m) defaults to the
        robot's "home" pose if it has one, else zeros; it must lie within the limits.
        A custom ``Robot`` works in memory but cannot be saved yet.
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
        try:
            if isinstance(robot, str):
                builtin: str | None = robot
                r = build_robot(robot, params)
            elif isinstance(robot, Robot):
                builtin = None
                r = (
                    attach_gripper(robot, parallel_gripper(**params))
                    if params is not None
                    else robot
                )
                params = None
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
        placed = RobotPlacement(name, r, B, qv, builtin, params)
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
        """Remove the part, robot or camera ``name`` (the model's entities stay)."""
        kind = self.kind_of(name)
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
    def to_dict(self) -> dict:
        """The cell as JSON-able data; ModelError for a custom (non built-in) robot."""
        robots = []
        for r in self._robots.values():
            if r.builtin is None:
                raise ModelError(
                    f"robot '{r.name}' is a custom Robot; only built-in robots "
                    f"({', '.join(BUILTIN_ROBOTS)}) with parallel grippers can be saved for now"
                )
            robots.append(
                {
                    "name": r.name,
                    "builtin": r.builtin,
                    "gripper": None if r.gripper_parameters is None else dict(r.gripper_parameters),
                    "base": r.base.tolist(),
                    "q": r.q.tolist(),
                }
            )
        return {
            "format": FORMAT,
            "version": VERSION,
            "name": self.name,
            "model": self.model.to_dict(),
            "static": [
                {
                    "name": p.name,
                    "entity": list(p.entity),
                    "pose": p.pose.tolist(),
                    "colour": list(p.colour),
                }
                for p in self._static.values()
            ],
            "movable": [
                {
                    "name": p.name,
                    "entity": list(p.entity),
                    "pose": p.pose.tolist(),
                    "colour": list(p.colour),
                    "density": p.density,
                }
                for p in self._movable.values()
            ],
            "robots": robots,
            "cameras": [
                {
                    "name": c.name,
                    "position": c.position.tolist(),
                    "target": c.target.tolist(),
                    "fovy": c.fovy,
                }
                for c in self._cameras.values()
            ],
        }

    @classmethod
    def from_dict(cls, data: object, *, source: str = "cell data") -> Workcell:
        """Rebuild a cell from :meth:`to_dict` data; ModelError naming the faulty place."""

        def fail(where: str, exc: BaseException | str) -> ModelError:
            return ModelError(f"{source}: {where}: {exc}")

        if not isinstance(data, dict):
            raise fail("top level", "expected a JSON object")
        if data.get("format") != FORMAT:
            # never quote the field: the file may be anything (a server reads files by name)
            hint = (
                " (a model file: load it as a model)"
                if data.get("format") == "workcell-model"
                else ""
            )
            raise fail("format", f"not a {FORMAT} document (missing or wrong 'format'){hint}")
        version = data.get("version")
        if type(version) is not int or version != VERSION:
            small = isinstance(version, (int, float)) and abs(version) < 10**9
            shown = repr(version) if version is None or small else f"(a {type(version).__name__})"
            raise fail("version", f"supported: {VERSION}, got {shown}")
        try:
            model = Model.from_dict(data["model"])
        except (WorkcellError, KeyError, TypeError, ValueError, OverflowError) as exc:
            raise fail("model", exc) from exc
        try:
            cell = cls(data.get("name", "workcell"), model)
        except WorkcellError as exc:
            raise fail("name", exc) from exc
        sections: list[tuple[str, Callable[[dict], object]]] = [
            (
                "static",
                lambda e: cell.add_static(
                    e["name"], tuple(e["entity"]), e["pose"], colour=e["colour"]
                ),
            ),
            (
                "movable",
                lambda e: cell.add_movable(
                    e["name"],
                    tuple(e["entity"]),
                    e["pose"],
                    density=e["density"],
                    colour=e["colour"],
                ),
            ),
            (
                "robots",
                lambda e: cell.add_robot(
                    e["name"], e["builtin"], gripper=e.get("gripper"), base=e["base"], q=e["q"]
                ),
            ),
            (
                "cameras",
                lambda e: cell.add_camera(e["name"], e["position"], e["target"], e["fovy"]),
            ),
        ]
        for key, add in sections:
            entries = data.get(key, [])
            if not isinstance(entries, list):
                raise fail(key, "expected a list")
            for i, e in enumerate(entries):
                where = f"{key}[{i}]"
                name = e.get("name") if isinstance(e, dict) else None
                if (
                    isinstance(name, str)
                    and len(name) <= MAX_NAME_LENGTH
                    and _NAME_RE.fullmatch(name)
                ):
                    where += f" ('{name}')"
                try:
                    if not isinstance(e, dict):
                        raise ModelError("expected a JSON object")
                    add(e)
                except KeyError as exc:
                    raise fail(where, f"missing field {exc}") from exc
                except (WorkcellError, TypeError, ValueError, OverflowError) as exc:
                    raise fail(where, exc) from exc
        return cell

    def save(self, path: str | os.PathLike) -> None:
        """Write the cell as versioned JSON, atomically; a failed write raises ModelError."""
        text = json.dumps(self.to_dict(), allow_nan=False)
        atomic_write_text(path, text, error=ModelError)

    @classmethod
    def load(cls, path: str | os.PathLike) -> Workcell:
        """Read a cell saved by :meth:`save`; a damaged file raises ModelError naming the
        place (never quoting a file that is not a cell file)."""
        data = load_json(path, what="cell file", error=ModelError)
        return cls.from_dict(data, source=f"cell file '{path}'")

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Workcell) and self.to_dict() == other.to_dict()

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return (
            f"Workcell({self.name!r}: {len(self._static)} static, {len(self._movable)} movable, "
            f"{len(self._robots)} robots, {len(self._cameras)} cameras)"
        )
