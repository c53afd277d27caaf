"""Relations of :class:`~workcell.modeller.model.Model`: attach (one, many, groups) and detach.

Every attach validates all names, targets (level, no cycle) and transforms first and
changes the model after, so a failed call leaves it exactly as it was.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.errors import GeometryError, ModelError
from workcell.modeller.entities import _PREFIX, CHILD, RELATION_KIND, Ref, _Entity, check_name
from workcell.modeller.model_base import ModelBase
from workcell.spatial import as_transforms

__all__ = ["AttachOps"]


class AttachOps(ModelBase):
    """The relation operations of :class:`~workcell.modeller.model.Model`."""

    def attach(
        self,
        owner: Ref,
        target: Ref,
        transform: ArrayLike | None = None,
        *,
        name: str | None = None,
    ) -> str:
        """Attach ``target`` to ``owner`` through ``transform`` (4x4; identity when None).

        Returns the relation's name (given, or generated: ts1, tb1, to1 ...).
        """
        T = np.eye(4) if transform is None else transform
        return self.attach_many(owner, target, [T], names=None if name is None else [name])[0]

    def attach_many(
        self,
        owner: Ref,
        target: Ref | Sequence[Ref],
        transforms: ArrayLike,
        *,
        names: Sequence[str] | None = None,
    ) -> list[str]:
        """Attach one target (or one target per transform) through each of ``transforms`` (N, 4, 4).

        All-or-nothing: every name, target and transform is validated before anything changes.
        """
        o = self._owner(owner)
        # validate the transforms first: their count (one (4, 4) or a stack) sets n
        Ts = as_transforms(
            transforms, rigid=(o.level == "scene"), what=f"{RELATION_KIND[o.level]} of {o.label}"
        )
        if Ts.ndim == 2:
            Ts = Ts[None]
        n = len(Ts)
        if isinstance(target, (str, tuple)):
            return self._attach(o, [(self._target(o, target), n)], Ts, names)
        if len(target) != n:
            raise ModelError(f"{len(target)} targets but {n} transforms")
        runs: list[tuple[_Entity, int]] = []
        cache: dict[Any, _Entity] = {}
        for r in target:
            if r not in cache:
                cache[r] = self._target(o, r)
            t = cache[r]
            if runs and runs[-1][0] is t:
                runs[-1] = (t, runs[-1][1] + 1)
            else:
                runs.append((t, 1))
        return self._attach(o, runs, Ts, names)

    def attach_groups(
        self,
        owner: Ref,
        groups: Sequence[tuple[Ref, ArrayLike]],
        *,
        names: Sequence[str] | None = None,
        return_names: bool = True,
    ) -> list[str] | None:
        """Attach several targets at once: ``groups`` lists (target, transforms (k, 4, 4) or (4, 4)).

        The same as one :meth:`attach_many` call per group, validated and applied as one
        all-or-nothing operation (and much cheaper for many groups). With
        ``return_names=False`` the generated names are not spelled out now (None is
        returned): cheaper for solids of many thousand relations.
        """
        o = self._owner(owner)
        runs, stacks = [], []
        for target, transforms in groups:
            try:
                T = np.asarray(transforms, dtype=np.float64)
                stacks.append(T.reshape(-1, 4, 4))
            except (TypeError, ValueError, OverflowError) as exc:
                raise GeometryError(
                    f"{RELATION_KIND[o.level]} of {o.label}: transforms must be (k, 4, 4) or (4, 4), "
                    f"got {np.shape(transforms)}"
                ) from exc
            runs.append((self._target(o, target), len(stacks[-1])))
        Ts = as_transforms(
            np.concatenate(stacks) if stacks else np.zeros((0, 4, 4)),
            rigid=(o.level == "scene"),
            what=f"{RELATION_KIND[o.level]} of {o.label}",
        )
        return self._attach(o, runs, Ts, names, return_names=return_names)

    def _owner(self, ref: Ref) -> _Entity:
        o = self._get(ref)
        if o.level == "surface":
            raise ModelError(
                f"{o.label} cannot own relations; owners are blocks, objects and scenes"
            )
        return o

    def _target(self, o: _Entity, ref: object) -> _Entity:
        """Resolve a target reference for owner ``o`` and check its level and acyclicity."""
        want = "block" if o.boolean else CHILD[o.level]
        if not isinstance(ref, str) and not (
            isinstance(ref, tuple) and all(isinstance(x, str) for x in ref)
        ):
            raise ModelError(f"a reference is a name or (level, name), got {ref!r}")
        t = self._get(ref, want) if isinstance(ref, str) else self._get(ref)
        if t.level != want:
            raise ModelError(f"{o.label} points to {want}s; {t.label} is a {t.level}")
        if t is o or o in self._made_of(t):
            raise ModelError(f"attaching {t.label} to {o.label} would make a cycle")
        return t

    def _attach(
        self,
        o: _Entity,
        runs: list[tuple[_Entity, int]],
        Ts: NDArray[np.float64],
        names: Sequence[str] | None,
        *,
        return_names: bool = True,
    ) -> list[str] | None:
        """Name and add validated relations: ``runs`` of (target, count) in order, Ts (n, 4, 4)."""
        n = len(Ts)
        new_names: list[str] | tuple[str, int, int]
        if names is None:
            start, prefix = o.serial, _PREFIX[o.level]

            def spelled(first: int) -> list[str]:
                return list(map(f"{prefix}{{}}".format, range(first, first + n)))

            while o.rels.custom and any(o.rels.index(nm) is not None for nm in spelled(start + 1)):
                start += n
            new_names = (prefix, start + 1, n)
            serial = start + n
        else:
            new_names = [check_name(nm) for nm in names]
            if len(new_names) != n:
                raise ModelError(f"{len(new_names)} names but {n} transforms")
            if len(set(new_names)) != n:
                twice = sorted({nm for nm in new_names if new_names.count(nm) > 1})
                raise ModelError(f"relation names given twice in one attach: {', '.join(twice)}")
            for nm in new_names:
                if o.rels.index(nm) is not None:
                    raise ModelError(f"{o.label} already has a relation named '{nm}'")
            serial = o.serial
            o.rels.custom = True
        targets: list[_Entity] = []
        for t, k in runs:
            targets.extend([t] * k)
        self._add_relations(o, new_names, targets, Ts)
        o.serial = serial
        if not return_names:
            return None
        return spelled(new_names[1]) if isinstance(new_names, tuple) else new_names

    def detach(self, owner: Ref, relation_name: str) -> None:
        """Remove one relation of ``owner``; its target's pointed_by goes down by one."""
        o = self._get(owner)
        i = self._rel_index(o, relation_name)
        if o.boolean and o.rels.n <= 2:
            raise ModelError(f"{o.label} is a boolean block and keeps at least 2 operands")
        t = o.rels.targets[i]
        o.rels.delete(i)
        if t.users[o] == 1:
            del t.users[o]
        else:
            t.users[o] -= 1
        self._touch(o)
