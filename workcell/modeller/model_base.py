"""The core of :class:`~workcell.modeller.model.Model`: its entity tables, lookup and queries.

:class:`ModelBase` holds the entities of each level, resolves references (a name, or
``(level, name)``) with messages that suggest close names, answers the read-only queries
(relations, ``made_of``, ``used_in``) and owns the two bookkeeping steps every change goes
through: adding relations (counting ``pointed_by``) and dropping cached geometry
(``_touch``). The operations that change a model are in :mod:`workcell.modeller.model_edit`
and :mod:`workcell.modeller.model_attach`.
"""

from __future__ import annotations

import difflib
from collections import Counter
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from workcell.errors import ModelError
from workcell.modeller.entities import (
    LEVELS,
    RELATION_KIND,
    EntityInfo,
    Ref,
    Relation,
    _Entity,
    _target_counts,
)

if TYPE_CHECKING:
    from workcell.modeller.surface import Surface

__all__ = ["ModelBase"]


class ModelBase:
    """Entity tables, lookup and queries of a :class:`~workcell.modeller.model.Model`."""

    def __init__(self) -> None:
        self._levels: dict[str, dict[str, _Entity]] = {lv: {} for lv in LEVELS}

    # ================================================================ lookup
    def _get(self, ref: Ref, level: str | None = None) -> _Entity:
        if isinstance(ref, tuple):
            if len(ref) != 2:
                raise ModelError(f"a reference is a name or (level, name), got {ref!r}")
            level, name = ref
            self._check_level(level)
            if not isinstance(name, str):
                raise ModelError(f"a reference is a name or (level, name), got {ref!r}")
            ent = self._levels[level].get(name)
            if ent is None:
                raise ModelError(self._unknown(name, level))
            return ent
        if not isinstance(ref, str):
            raise ModelError(f"a reference is a name or (level, name), got {ref!r}")
        if level is not None:
            return self._get((level, ref))
        found = [d[ref] for d in self._levels.values() if ref in d]
        if not found:
            raise ModelError(self._unknown(ref, None))
        if len(found) > 1:
            levels = " and ".join(e.level for e in found)
            raise ModelError(
                f"the name '{ref}' is used at levels {levels}; say which, e.g. ('{found[0].level}', '{ref}')"
            )
        return found[0]

    def _unknown(self, name: str, level: str | None) -> str:
        pool = list(self._levels[level]) if level else [n for d in self._levels.values() for n in d]
        where = f"{level} " if level else "entity "
        close = difflib.get_close_matches(str(name), pool, n=3)
        hint = f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""
        known = ", ".join(sorted(pool)[:20]) + (" ..." if len(pool) > 20 else "")
        return f"no {where}named '{name}'{hint} (known: {known or 'none'})"

    @staticmethod
    def _check_level(level: object) -> str:
        if level not in LEVELS:
            raise ModelError(f"unknown level {level!r}; levels are {', '.join(LEVELS)}")
        return level  # type: ignore[return-value]

    def exists(self, ref: Ref) -> bool:
        """True when ``ref`` names exactly one entity."""
        try:
            self._get(ref)
        except ModelError:
            return False
        return True

    def level_of(self, ref: Ref) -> str:
        """The level of the entity named by ``ref``."""
        return self._get(ref).level

    def list(self, level: str | None = None) -> list[str] | dict[str, list[str]]:
        """Names at ``level`` in creation order, or a dict of all levels."""
        if level is None:
            return {lv: list(d) for lv, d in self._levels.items()}
        return list(self._levels[self._check_level(level)])

    def info(self, ref: Ref) -> EntityInfo:
        """Level, name, pointed_by, relation count, colour, movable flag, boolean op."""
        e = self._get(ref)
        return EntityInfo(e.level, e.name, e.pointed_by, e.rels.n, e.colour, e.movable, e.boolean)

    def pointed_by(self, ref: Ref) -> int:
        """How many relations point to the entity."""
        return self._get(ref).pointed_by

    def surface(self, ref: Ref) -> Surface:
        """The :class:`Surface` of a surface entity."""
        e = self._get(ref, "surface") if isinstance(ref, str) else self._get(ref)
        if e.surface is None:
            raise ModelError(f"{e.label} is not a surface")
        return e.surface

    def relations(self, owner: Ref) -> list[Relation]:
        """The relations of ``owner`` in order."""
        e = self._get(owner)
        return [self._relation_view(e, i) for i in range(e.rels.n)]

    def relation(self, owner: Ref, name: str) -> Relation:
        """One relation of ``owner`` by name."""
        e = self._get(owner)
        return self._relation_view(e, self._rel_index(e, name))

    def _relation_view(self, e: _Entity, i: int) -> Relation:
        t = e.rels.targets[i]
        T = e.rels.T[i].copy()
        T.flags.writeable = False
        kind = "transform_block" if e.boolean else RELATION_KIND[e.level]
        return Relation(e.rels.names[i], kind, e.name, t.name, t.level, T)

    def _rel_index(self, e: _Entity, name: str) -> int:
        i = e.rels.index(name)
        if i is None:
            names = e.rels.names
            known = ", ".join(names[:20]) + (" ..." if len(names) > 20 else "")
            raise ModelError(
                f"{e.label} has no relation named '{name}' (its relations: {known or 'none'})"
            )
        return i

    # ================================================================ queries
    def _made_of(self, e: _Entity) -> list[_Entity]:
        seen: dict[int, _Entity] = {}
        stack = [e]
        while stack:
            for t in _target_counts(stack.pop()):
                if id(t) not in seen:
                    seen[id(t)] = t
                    stack.append(t)
        return list(seen.values())

    def made_of(self, ref: Ref) -> list[tuple[str, str]]:
        """Every entity ``ref`` is made of, transitively down to surfaces, as (level, name)."""
        ents = self._made_of(self._get(ref))
        return sorted(((t.level, t.name) for t in ents), key=lambda x: (-LEVELS.index(x[0]), x[1]))

    def used_in(self, ref: Ref) -> list[tuple[str, str]]:
        """Every entity that uses ``ref``, transitively up to scenes, as (level, name)."""
        seen: dict[int, _Entity] = {}
        stack = [self._get(ref)]
        while stack:
            for u in stack.pop().users:
                if id(u) not in seen:
                    seen[id(u)] = u
                    stack.append(u)
        return sorted(
            ((u.level, u.name) for u in seen.values()), key=lambda x: (LEVELS.index(x[0]), x[1])
        )

    # ================================================================ bookkeeping
    def _add_relations(
        self,
        o: _Entity,
        names: list[str] | tuple[str, int, int],
        targets: list[_Entity],
        Ts: NDArray[np.float64],
    ) -> None:
        o.rels.add(names, targets, Ts)
        for t, k in Counter(targets).items():
            t.users[o] = t.users.get(o, 0) + k
        self._touch(o)

    def _touch(self, e: _Entity) -> None:
        """Drop cached geometry of ``e`` and of everything that uses it."""
        stack = [e]
        seen: set[int] = set()
        while stack:
            cur = stack.pop()
            if id(cur) in seen:
                continue
            seen.add(id(cur))
            cur.cache.clear()
            stack.extend(cur.users)
