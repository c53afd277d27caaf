"""The datamodel of thesis ch. 2: surfaces, blocks, objects and scenes linked by named relations.

Levels and what each is made of:

========  ==============================================  ==================
level     made of                                         relation kind
========  ==============================================  ==================
surface   a :class:`~workcell.modeller.surface.Surface`   -
block     transformed surfaces (its boundary)             transform_surface
object    transformed blocks                              transform_block
scene     transformed objects (rigid placements)          transform_object
========  ==============================================  ==================

A block may instead be a *boolean* (CSG) block whose relations point to operand blocks.
Every relation has a name (unique within its owner), an owner, a target and a 4x4
transform. Each entity counts the relations that point to it (``pointed_by``); an entity
that is pointed to cannot be removed. Every operation validates first and mutates after,
so a failed operation leaves the model exactly as it was.

An entity is named by its name when that is unique across levels, else by
``(level, name)``.

The class is assembled from parts: records and checks in
:mod:`~workcell.modeller.entities`, tables, lookup and queries in
:mod:`~workcell.modeller.model_base`, entity changes in
:mod:`~workcell.modeller.model_edit` and relations in
:mod:`~workcell.modeller.model_attach`; geometry and storage delegate to
:mod:`~workcell.modeller.world` and :mod:`~workcell.modeller.storage`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from workcell.modeller.entities import (
    BOOLEAN_OPS,
    LEVELS,
    MAX_NAME_LENGTH,
    EntityInfo,
    Ref,
    Relation,
    check_colour,  # noqa: F401 - re-exported: other modules import it from here
    check_name,  # noqa: F401 - re-exported: other modules import it from here
)
from workcell.modeller.model_attach import AttachOps
from workcell.modeller.model_edit import EditOps

if TYPE_CHECKING:
    import trimesh

    from workcell.modeller.meshprops import MassProperties, ValidityReport
    from workcell.modeller.world import WorldPart

__all__ = ["BOOLEAN_OPS", "LEVELS", "MAX_NAME_LENGTH", "EntityInfo", "Model", "Ref", "Relation"]


class Model(EditOps, AttachOps):
    """The workcell datamodel: entities at four levels linked by named, transformed relations."""

    def show(self, ref: Ref | None = None, *, detail: bool = False) -> str:
        """A readable summary of the model, or of one entity (``detail`` lists its relations)."""
        from workcell.modeller.show import show_entity, show_model

        if ref is None:
            return show_model(self, detail=detail)
        return show_entity(self, self._get(ref), detail=detail)

    # ================================================================ geometry
    def world_mesh(self, ref: Ref) -> trimesh.Trimesh:
        """The entity as one mesh in world coordinates (m). Cached until the model changes."""
        from workcell.modeller.world import entity_mesh

        return entity_mesh(self._get(ref))

    def world_parts(self, ref: Ref) -> list[WorldPart]:
        """One world-coordinate mesh per block instance, with source names and colours."""
        from workcell.modeller.world import entity_parts

        return entity_parts(self._get(ref))

    def properties(self, ref: Ref) -> MassProperties:
        """Area, volume, centroid, first moments and inertia (unit density) of an entity."""
        from workcell.modeller.world import entity_properties

        return entity_properties(self._get(ref))

    def validity(self, ref: Ref, *, check_self_intersection: bool = True) -> ValidityReport:
        """Validity report of the entity's world mesh (watertight, wound, volume, intersections)."""
        from workcell.modeller.meshprops import validity_report

        m = self.world_mesh(ref)
        return validity_report(m.vertices, m.faces, check_self_intersection=check_self_intersection)

    # ================================================================ storage
    def to_dict(self) -> dict:
        """The whole model as plain JSON-able data (see :mod:`workcell.modeller.storage`)."""
        from workcell.modeller.storage import model_to_dict

        return model_to_dict(self)

    @classmethod
    def from_dict(cls, data: dict) -> Model:
        """Rebuild a model from :meth:`to_dict` data; raises ModelError naming any fault."""
        from workcell.modeller.storage import model_from_dict

        return model_from_dict(data)

    def save(self, path: str) -> None:
        """Write the model as versioned JSON, atomically (temp file + rename)."""
        from workcell.modeller.storage import save

        save(self, path)

    @classmethod
    def load(cls, path: str) -> Model:
        """Read a model saved by :meth:`save`; a damaged file raises ModelError, loading nothing."""
        from workcell.modeller.storage import load

        return load(path)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Model) and self.to_dict() == other.to_dict()

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        counts = ", ".join(f"{len(d)} {lv}s" for lv, d in self._levels.items())
        return f"Model({counts})"
