"""Changes to :class:`~workcell.modeller.model.Model` entities: create, remove, rename, copy, set.

Each operation validates first and mutates after, so a failed one leaves the model
exactly as it was.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from workcell.errors import GeometryError, ModelError
from workcell.modeller.entities import (
    BOOLEAN_OPS,
    Ref,
    _Entity,
    _target_counts,
    check_colour,
    check_name,
)
from workcell.modeller.model_base import ModelBase
from workcell.modeller.surface import Surface
from workcell.spatial import as_transforms

__all__ = ["EditOps"]


class EditOps(ModelBase):
    """The entity operations of :class:`~workcell.modeller.model.Model`."""

    # ================================================================ create / remove
    def create(
        self,
        level: str,
        name: str,
        surface: Surface | None = None,
        *,
        colour: ArrayLike | None = None,
        movable: bool = False,
    ) -> str:
        """Create an empty entity (a surface takes its :class:`Surface`); return its name."""
        self._check_level(level)
        check_name(name)
        if name in self._levels[level]:
            raise ModelError(f"a {level} named '{name}' already exists")
        if level == "surface":
            if not isinstance(surface, Surface):
                raise ModelError(f"creating surface '{name}' needs a Surface, got {surface!r}")
        elif surface is not None:
            raise ModelError(f"only surfaces take a Surface; '{name}' is a {level}")
        if not isinstance(movable, (bool, np.bool_)):
            raise ModelError(f"movable must be True or False, got {movable!r}")
        if movable and level == "surface":
            raise ModelError("the movable flag applies to blocks, objects and scenes, not surfaces")
        c = None if colour is None else check_colour(colour)
        e = _Entity(level, name)
        e.surface, e.colour, e.movable = surface, c, bool(movable)
        self._levels[level][name] = e
        return name

    def create_boolean(
        self,
        name: str,
        op: str,
        operands: Sequence[Ref],
        transforms: Sequence[ArrayLike | None] | None = None,
        *,
        colour: ArrayLike | None = None,
    ) -> str:
        """Create a boolean (CSG) block ``op`` of operand blocks, each placed by a transform.

        ``difference`` subtracts the second and later operands from the first. The result
        is evaluated lazily (manifold3d) when its mesh is asked for (the solids'
        ``union``, ``difference`` and ``intersection`` evaluate it at once).
        """
        if op not in BOOLEAN_OPS:
            raise ModelError(
                f"unknown boolean operation {op!r}; use one of {', '.join(BOOLEAN_OPS)}"
            )
        ents = [self._get(r, "block") if isinstance(r, str) else self._get(r) for r in operands]
        if len(ents) < 2:
            raise ModelError(f"boolean block '{name}' needs at least 2 operand blocks")
        for t in ents:
            if t.level != "block":
                raise ModelError(f"boolean operands must be blocks; {t.label} is not")
        if transforms is None:
            transforms = [None] * len(ents)
        if len(transforms) != len(ents):
            raise ModelError(f"{len(ents)} operands but {len(transforms)} transforms")
        Ts = as_transforms(
            [np.eye(4) if T is None else T for T in transforms], rigid=False, what=f"block '{name}'"
        )
        check_name(name)
        if name in self._levels["block"]:
            raise ModelError(f"a block named '{name}' already exists")
        c = None if colour is None else check_colour(colour)
        self.create("block", name, colour=c)
        e = self._levels["block"][name]
        e.boolean = op
        self._add_relations(e, [f"op{i + 1}" for i in range(len(ents))], ents, Ts)
        e.serial = len(ents)
        return name

    def remove(self, ref: Ref, *, recursive: bool = False) -> list[str]:
        """Remove an entity; refused while anything points to it.

        With ``recursive`` the entities it pointed to are removed too when nothing else
        points to them any more (transitively). Returns the removed names.
        """
        e = self._get(ref)
        if e.pointed_by:
            users = ", ".join(
                f"{u.label} ({k} relation{'s' * (k > 1)})" for u, k in e.users.items()
            )
            raise ModelError(
                f"cannot remove {e.label}: it is pointed to by {users}; detach those first"
            )
        doomed = [e]
        if recursive:
            doomed_ids = {id(e)}
            remaining: dict[int, int] = {}
            stack = [e]
            while stack:
                cur = stack.pop()
                for t, k in _target_counts(cur).items():
                    left = remaining.get(id(t), t.pointed_by) - k
                    remaining[id(t)] = left
                    if left == 0 and id(t) not in doomed_ids:
                        doomed_ids.add(id(t))
                        doomed.append(t)
                        stack.append(t)
        for d in doomed:
            for t, k in _target_counts(d).items():
                left = t.users[d] - k
                if left:
                    t.users[d] = left
                else:
                    del t.users[d]
            del self._levels[d.level][d.name]
        return [d.name for d in doomed]

    # ================================================================ modify
    def rename(self, ref: Ref, new_name: str) -> None:
        """Give an entity a new name (unique within its level)."""
        e = self._get(ref)
        check_name(new_name)
        if new_name in self._levels[e.level]:
            raise ModelError(f"a {e.level} named '{new_name}' already exists")
        d = self._levels[e.level]
        self._levels[e.level] = {(new_name if k == e.name else k): v for k, v in d.items()}
        e.name = new_name

    def rename_relation(self, owner: Ref, relation_name: str, new_name: str) -> None:
        """Give a relation a new name (unique within its owner)."""
        o = self._get(owner)
        i = self._rel_index(o, relation_name)
        check_name(new_name)
        if o.rels.index(new_name) is not None:
            raise ModelError(f"{o.label} already has a relation named '{new_name}'")
        o.rels.names[i] = new_name
        o.rels._index = None
        o.rels.custom = True

    def set_transform(self, owner: Ref, relation_name: str, transform: ArrayLike) -> None:
        """Replace the transform of one relation."""
        o = self._get(owner)
        i = self._rel_index(o, relation_name)
        T = as_transforms(transform, rigid=(o.level == "scene"), what=f"relation '{relation_name}'")
        if T.shape != (4, 4):
            raise GeometryError(
                f"relation '{relation_name}': expected one 4x4 matrix, got {T.shape}"
            )
        o.rels.T[i] = T
        self._touch(o)

    def set_colour(self, ref: Ref, colour: ArrayLike | None) -> None:
        """Set an entity's RGB(A) colour (components in [0, 1]); None clears it."""
        e = self._get(ref)
        c = None if colour is None else check_colour(colour)
        e.colour = c
        self._touch(e)

    def set_movable(self, ref: Ref, movable: bool) -> None:
        """Flag a block, object or scene as movable (a part that robots may grasp)."""
        e = self._get(ref)
        if e.level == "surface":
            raise ModelError("the movable flag applies to blocks, objects and scenes, not surfaces")
        if not isinstance(movable, (bool, np.bool_)):
            raise ModelError(f"movable must be True or False, got {movable!r}")
        e.movable = bool(movable)
        self._touch(e)

    def set_surface(self, ref: Ref, surface: Surface) -> None:
        """Replace the geometry of a surface entity (every block using it changes)."""
        e = self._get(ref, "surface") if isinstance(ref, str) else self._get(ref)
        if e.level != "surface" or not isinstance(surface, Surface):
            raise ModelError(f"set_surface needs a surface entity and a Surface ({e.label})")
        e.surface = surface
        self._touch(e)

    def copy(self, ref: Ref, new_name: str, transform: ArrayLike | None = None) -> str:
        """Copy an entity under a new name, optionally applying ``transform`` (instancing).

        A copied block, object or scene points to the same targets (their pointed_by
        grows), each relation's transform premultiplied by ``transform``. A surface copy
        needs a transform that keeps the surface's plane (z = 0) in place.
        """
        e = self._get(ref)
        check_name(new_name)
        if new_name in self._levels[e.level]:
            raise ModelError(f"a {e.level} named '{new_name}' already exists")
        T = (
            None
            if transform is None
            else as_transforms(
                transform, rigid=(e.level == "scene"), what=f"copy transform for '{new_name}'"
            )
        )
        if e.level == "surface":
            surf = e.surface
            if T is not None:
                if (
                    np.abs(T[2, :2]).max() > 1e-12
                    or np.abs(T[:2, 2]).max() > 1e-12
                    or abs(T[2, 3]) > 1e-12
                ):
                    raise GeometryError(
                        f"copying surface '{e.name}': the transform must keep the plane z = 0 "
                        "(no rotation out of plane, no z translation)"
                    )
                surf = surf.transformed(T[np.ix_([0, 1], [0, 1, 3])], name=new_name)
            self.create("surface", new_name, surf, colour=e.colour)
            return new_name
        Ts = e.rels.T.copy() if T is None else T @ e.rels.T
        if T is not None:  # the products: finite, in range, and rigid in a scene
            as_transforms(Ts, rigid=e.level == "scene", what=f"copy of {e.label}")
        c = self._levels[e.level]
        new = _Entity(e.level, new_name)
        new.colour, new.movable, new.boolean, new.serial = e.colour, e.movable, e.boolean, e.serial
        c[new_name] = new
        self._add_relations(new, list(e.rels.names), list(e.rels.targets), Ts)
        new.rels.custom = e.rels.custom  # the copied names may clash with generated ones
        return new_name
