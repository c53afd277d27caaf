"""Save and load a :class:`~workcell.modeller.model.Model` as versioned JSON.

Format ``workcell-model`` version 1::

    {"format": "workcell-model", "version": 1,
     "surfaces": [{"name": "square1", "main": [[x, y], ...], "holes": [[[x, y], ...]],
                   "colour": null}],
     "blocks":   [{"name": "cube1", "colour": [r, g, b, a] | null, "movable": false,
                   "boolean": null | "union" | "difference" | "intersection", "serial": 6,
                   "relations": [{"name": "ts1", "target": "square1",
                                  "transform": [[4 numbers] x 4]}]}],
     "objects":  [... same keys, targets are blocks ...],
     "scenes":   [... same keys, targets are objects, transforms rigid ...]}

Coordinates in metres. Floats are written with Python's shortest round-trip repr, so a
save/load round trip is exact. Writes are atomic (temp file + rename). Loading validates
everything and builds a fresh model: a damaged file raises :class:`ModelError` naming the
place, and nothing is loaded partially.
"""

from __future__ import annotations

import json
import os
from typing import Any

import numpy as np

from workcell.errors import ModelError, WorkcellError
from workcell.files import atomic_write_text, load_json
from workcell.modeller.entities import BOOLEAN_OPS, CHILD, LEVELS, check_name
from workcell.modeller.model import Model
from workcell.modeller.surface import Surface

__all__ = [
    "FORMAT",
    "VERSION",
    "load",
    "model_from_dict",
    "model_to_dict",
    "save",
]

FORMAT = "workcell-model"
VERSION = 1
_MAX_SERIAL = 10**9  # relation names are generated from it (ts1, ts2, ...)
_SECTIONS = {"surface": "surfaces", "block": "blocks", "object": "objects", "scene": "scenes"}


def model_to_dict(model: Model) -> dict:
    """Plain JSON-able data of the whole model."""
    out: dict[str, Any] = {"format": FORMAT, "version": VERSION}
    for level, key in _SECTIONS.items():
        items = []
        for e in model._levels[level].values():
            d: dict[str, Any] = {
                "name": e.name,
                "colour": None if e.colour is None else list(e.colour),
            }
            if level == "surface":
                d.update(e.surface.to_dict())
            else:
                d["movable"] = e.movable
                d["boolean"] = e.boolean
                d["serial"] = e.serial
                d["relations"] = [
                    {"name": n, "target": t.name, "transform": T.tolist()}
                    for n, t, T in zip(e.rels.names, e.rels.targets, e.rels.T, strict=True)
                ]
            items.append(d)
        out[key] = items
    return out


def _field(d: Any, key: str, where: str, kinds: type | tuple[type, ...]) -> Any:
    if not isinstance(d, dict):
        raise ModelError(f"{where}: expected an object, got {type(d).__name__}")
    if key not in d:
        raise ModelError(f"{where}: missing field '{key}'")
    v = d[key]
    bool_ok = kinds is bool or (isinstance(kinds, tuple) and bool in kinds)
    if not isinstance(v, kinds) or (isinstance(v, bool) and not bool_ok):  # True is an int
        raise ModelError(f"{where}: field '{key}' has the wrong type ({type(v).__name__})")
    return v


def model_from_dict(data: Any) -> Model:
    """Build a new model from :func:`model_to_dict` data, validating every part first."""
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise ModelError(f"not a {FORMAT} document (missing or wrong 'format')")
    version = data.get("version")
    if type(version) is not int or version != VERSION:
        small = isinstance(version, (int, float)) and abs(version) < 10**9
        shown = repr(version) if version is None or small else f"(a {type(version).__name__})"
        raise ModelError(f"unsupported {FORMAT} version {shown}; this build reads {VERSION}")
    m = Model()
    sections = {lv: _field(data, key, "document", list) for lv, key in _SECTIONS.items()}
    # pass 1: every entity, so relations may point in any order within a level
    for level in LEVELS:
        for i, d in enumerate(sections[level]):
            where = f"{_SECTIONS[level]}[{i}]"
            try:
                name = check_name(_field(d, "name", where, str))
            except ModelError as exc:
                raise ModelError(f"{where}: {exc}") from None
            where = f"{where} '{name}'"
            try:
                colour = d.get("colour") if isinstance(d, dict) else None
                if level == "surface":
                    surf = Surface.from_dict(
                        {
                            "main": _field(d, "main", where, list),
                            "holes": _field(d, "holes", where, list),
                        },
                        name=name,
                    )
                    m.create("surface", name, surf, colour=colour)
                else:
                    m.create(
                        level, name, colour=colour, movable=bool(_field(d, "movable", where, bool))
                    )
                    op = d.get("boolean")
                    if op is not None:
                        if level != "block" or op not in BOOLEAN_OPS:
                            raise ModelError(f"invalid boolean {op!r}")
                        m._levels[level][name].boolean = op
            except WorkcellError as exc:
                raise ModelError(f"{where}: {exc}") from exc
    # pass 2: relations
    for level in LEVELS[1:]:
        for i, d in enumerate(sections[level]):
            where = f"{_SECTIONS[level]}[{i}] '{d['name']}'"
            rels = _field(d, "relations", where, list)
            serial = _field(d, "serial", where, int)
            if not 0 <= serial <= _MAX_SERIAL:
                raise ModelError(f"{where}: field 'serial' must be in 0 .. {_MAX_SERIAL}")
            e = m._levels[level][d["name"]]
            if rels:
                names, targets, Ts = [], [], []
                for j, r in enumerate(rels):
                    rw = f"{where} relation {j}"
                    names.append(_field(r, "name", rw, str))
                    tl = "block" if e.boolean else CHILD[level]
                    targets.append((tl, _field(r, "target", rw, str)))
                    Ts.append(_field(r, "transform", rw, list))
                try:
                    T = np.array(Ts, dtype=np.float64)
                    m.attach_many((level, d["name"]), targets, T, names=names)
                except (WorkcellError, ValueError, TypeError, OverflowError) as exc:
                    raise ModelError(f"{where}: {exc}") from exc
            if e.boolean and e.rels.n < 2:
                raise ModelError(f"{where}: a boolean block needs at least 2 operands")
            e.serial = serial
            e.rels.custom = True
    return m


def save(model: Model, path: str | os.PathLike) -> None:
    """Write ``model`` to ``path`` as JSON, atomically; a failed write raises ModelError."""
    text = json.dumps(model_to_dict(model), separators=(",", ":"))
    atomic_write_text(path, text, error=ModelError)


def load(path: str | os.PathLike) -> Model:
    """Read a model from ``path``; any fault raises ModelError naming the place (never
    quoting a file that is not a model file); a file over ``max_file_bytes`` LimitError."""
    data = load_json(path, what="model file", error=ModelError)
    try:
        return model_from_dict(data)
    except ModelError as exc:
        raise ModelError(f"model file '{path}': {exc}") from exc
