"""The command vocabulary, datamodel part: the thesis's data sublanguage (§2.2) as commands.

Each command is a frozen dataclass with SI values (metres, radians) whose
``execute(session)`` calls the :class:`~workcell.Model` (which validates first and mutates
after, so a failed command changes nothing) and returns a plain result. The wire name
(the protocol's ``command``) follows the Model method it calls. The cell and simulation
commands are in :mod:`workcell.program.simcommands`; both register in
:data:`workcell.program.base.COMMANDS`.

An entity reference (``ref``) is a name, or ``(level, name)`` when the name is used at
several levels. Transforms are 4x4 matrices (rows).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from workcell.errors import ModelError
from workcell.modeller.surface import Surface
from workcell.program import args as a
from workcell.program.args import arg
from workcell.program.base import Command

if TYPE_CHECKING:
    from workcell.program.session import Session

__all__ = [
    "Attach",
    "Copy",
    "CreateEntity",
    "CreateSurface",
    "Detach",
    "ListEntities",
    "LoadModel",
    "Properties",
    "Remove",
    "Rename",
    "RenameRelation",
    "SaveModel",
    "SetColour",
    "SetMovable",
    "SetTransform",
    "Show",
    "WorldMesh",
]

_opt_colour = a.optional(a.colour)
_opt_matrix = a.optional(a.matrix)


def _T(m: tuple[tuple[float, ...], ...] | None) -> np.ndarray | None:
    return None if m is None else np.array(m, dtype=np.float64)


def _in_cell(session: Session, ref: str | tuple[str, str], doing: str) -> None:
    """Refuse ``doing`` to an entity that a part of the session's cell is made of."""
    cell = session.cell
    if cell is None:
        return
    m = session.model
    e = m.info(ref)
    for part in (*cell.static_parts.values(), *cell.movable_parts.values()):
        if part.entity == (e.level, e.name) or (e.level, e.name) in m.made_of(part.entity):
            raise ModelError(
                f"cannot {doing} {e.level} '{e.name}': part '{part.name}' of cell "
                f"'{cell.name}' is made of it"
            )


# ---------------------------------------------------------------- create
@dataclass(frozen=True)
class CreateEntity(Command, wire="create"):
    """Create an empty block, object or scene (relations are attached to it later)."""

    level: str = arg(a.choice("block", "object", "scene"))
    name: str = arg(a.name)
    colour: tuple[float, ...] | None = arg(_opt_colour, None, "RGB(A) in [0, 1]")
    movable: bool = arg(a.boolean, False)

    def execute(self, session: Session) -> str:
        return session.model.create(self.level, self.name, colour=self.colour, movable=self.movable)


@dataclass(frozen=True)
class CreateSurface(Command, wire="create_surface"):
    """Create a planar surface: a main contour and hole contours, [x, y] points (m)."""

    name: str = arg(a.name)
    points: tuple[tuple[float, float], ...] = arg(a.points)
    holes: tuple[tuple[tuple[float, float], ...], ...] = arg(a.list_of(a.points), ())
    colour: tuple[float, ...] | None = arg(_opt_colour, None)

    def execute(self, session: Session) -> str:
        surface = Surface(self.points, self.holes, name=self.name)
        return session.model.create("surface", self.name, surface, colour=self.colour)


# ---------------------------------------------------------------- remove / modify / copy
@dataclass(frozen=True)
class Remove(Command, wire="remove"):
    """Remove an entity (refused while pointed to); ``recursive`` also removes what it used."""

    ref: str | tuple[str, str] = arg(a.ref)
    recursive: bool = arg(a.boolean, False)

    def execute(self, session: Session) -> list[str]:
        _in_cell(session, self.ref, "remove")
        return session.model.remove(self.ref, recursive=self.recursive)


@dataclass(frozen=True)
class Rename(Command, wire="rename"):
    """Give an entity a new name (unique within its level)."""

    ref: str | tuple[str, str] = arg(a.ref)
    new_name: str = arg(a.name)

    def execute(self, session: Session) -> str:
        _in_cell(session, self.ref, "rename")
        session.model.rename(self.ref, self.new_name)
        return self.new_name


@dataclass(frozen=True)
class RenameRelation(Command, wire="rename_relation"):
    """Give relation ``relation`` of ``owner`` a new name."""

    owner: str | tuple[str, str] = arg(a.ref)
    relation: str = arg(a.name)
    new_name: str = arg(a.name)

    def execute(self, session: Session) -> str:
        session.model.rename_relation(self.owner, self.relation, self.new_name)
        return self.new_name


@dataclass(frozen=True)
class SetTransform(Command, wire="set_transform"):
    """Replace the transform (4x4) of relation ``relation`` of ``owner``."""

    owner: str | tuple[str, str] = arg(a.ref)
    relation: str = arg(a.name)
    transform: tuple[tuple[float, ...], ...] = arg(a.matrix)

    def execute(self, session: Session) -> None:
        session.model.set_transform(self.owner, self.relation, _T(self.transform))


@dataclass(frozen=True)
class SetColour(Command, wire="set_colour"):
    """Set an entity's RGB(A) colour (components in [0, 1]); null clears it."""

    ref: str | tuple[str, str] = arg(a.ref)
    colour: tuple[float, ...] | None = arg(_opt_colour)

    def execute(self, session: Session) -> None:
        session.model.set_colour(self.ref, self.colour)


@dataclass(frozen=True)
class SetMovable(Command, wire="set_movable"):
    """Flag a block, object or scene as movable (a part robots may grasp) or not."""

    ref: str | tuple[str, str] = arg(a.ref)
    movable: bool = arg(a.boolean)

    def execute(self, session: Session) -> None:
        session.model.set_movable(self.ref, self.movable)


@dataclass(frozen=True)
class Copy(Command, wire="copy"):
    """Copy an entity under ``new_name``, optionally applying ``transform`` (instancing)."""

    ref: str | tuple[str, str] = arg(a.ref)
    new_name: str = arg(a.name)
    transform: tuple[tuple[float, ...], ...] | None = arg(_opt_matrix, None)

    def execute(self, session: Session) -> str:
        return session.model.copy(self.ref, self.new_name, _T(self.transform))


# ---------------------------------------------------------------- relations
@dataclass(frozen=True)
class Attach(Command, wire="attach"):
    """Attach ``target`` to ``owner`` through ``transform`` (identity when null); returns
    the relation's name (``relation``, or generated: ts1, tb1, to1 ...)."""

    owner: str | tuple[str, str] = arg(a.ref)
    target: str | tuple[str, str] = arg(a.ref)
    transform: tuple[tuple[float, ...], ...] | None = arg(_opt_matrix, None)
    relation: str | None = arg(a.optional(a.name), None)

    def execute(self, session: Session) -> str:
        return session.model.attach(self.owner, self.target, _T(self.transform), name=self.relation)


@dataclass(frozen=True)
class Detach(Command, wire="detach"):
    """Remove relation ``relation`` of ``owner``."""

    owner: str | tuple[str, str] = arg(a.ref)
    relation: str = arg(a.name)

    def execute(self, session: Session) -> None:
        session.model.detach(self.owner, self.relation)


# ---------------------------------------------------------------- queries
@dataclass(frozen=True)
class Show(Command, wire="show"):
    """A readable summary of the model, or of one entity (``detail``: its relations)."""

    ref: str | tuple[str, str] | None = arg(a.optional(a.ref), None)
    detail: bool = arg(a.boolean, False)

    def execute(self, session: Session) -> str:
        return session.model.show(self.ref, detail=self.detail)


@dataclass(frozen=True)
class ListEntities(Command, wire="list"):
    """Entity names at ``level`` in creation order, or of every level."""

    level: str | None = arg(a.optional(a.choice(*a.LEVELS)), None)

    def execute(self, session: Session) -> list[str] | dict[str, list[str]]:
        return session.model.list(self.level)


@dataclass(frozen=True)
class Properties(Command, wire="properties"):
    """Area (m^2), volume (m^3), centroid (m), first moments (m^4) and inertia about the
    centroid (m^5, unit density) of an entity."""

    ref: str | tuple[str, str] = arg(a.ref)

    def execute(self, session: Session) -> dict[str, Any]:
        p = session.model.properties(self.ref)
        return {
            "area": float(p.area),
            "volume": float(p.volume),
            "centroid": p.centroid.copy(),
            "first_moments": p.first_moments.copy(),
            "inertia": p.inertia.copy(),
        }


@dataclass(frozen=True)
class WorldMesh(Command, wire="world_mesh"):
    """The entity's mesh in world coordinates: counts, bounds (m), volume (m^3),
    watertightness; with ``path`` also written there (STL, OBJ or PLY by extension)."""

    ref: str | tuple[str, str] = arg(a.ref)
    path: str | None = arg(a.optional(a.file_name), None)

    def execute(self, session: Session) -> dict[str, Any]:
        from workcell.files import check_writable

        path = None if self.path is None else session.path(self.path)
        if path is not None:
            if path.suffix.lower() not in _MESH_KINDS:
                raise ModelError(f"cannot write mesh '{path}': use a .stl, .obj or .ply file name")
            check_writable(path, error=ModelError)  # before the meshing
        mesh = session.model.world_mesh(self.ref)
        out: dict[str, Any] = {
            "vertices": len(mesh.vertices),
            "faces": len(mesh.faces),
            "bounds": np.asarray(mesh.bounds, dtype=np.float64),
            "volume": float(mesh.volume),
            "watertight": bool(mesh.is_watertight),
            "path": None,
        }
        if path is not None:
            out["path"] = str(_export_mesh(mesh, path))
        return out


_MESH_KINDS = {".stl": "stl", ".obj": "obj", ".ply": "ply"}


def _export_mesh(mesh: Any, path: Any) -> Any:
    from workcell.files import atomic_write_bytes

    data = mesh.export(file_type=_MESH_KINDS[path.suffix.lower()])
    data = data if isinstance(data, bytes) else data.encode("utf-8")
    atomic_write_bytes(path, data, error=ModelError)
    return path


# ---------------------------------------------------------------- files
@dataclass(frozen=True)
class SaveModel(Command, wire="save"):
    """Write the model to ``path`` as versioned JSON (atomic)."""

    path: str = arg(a.file_name)

    def execute(self, session: Session) -> str:
        p = session.path(self.path)
        session.model.save(str(p))
        return str(p)


@dataclass(frozen=True)
class LoadModel(Command, wire="load"):
    """Replace the model by the one saved in ``path`` (refused while a cell is loaded)."""

    path: str = arg(a.file_name)

    def execute(self, session: Session) -> dict[str, list[str]]:
        from workcell.modeller.model import Model

        if session.cell is not None:
            session.set_model(session.model)  # raises: explains why
        model = Model.load(str(session.path(self.path)))
        session.set_model(model)
        return model.list()  # type: ignore[return-value]
