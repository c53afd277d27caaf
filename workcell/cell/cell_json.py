"""A cell as versioned JSON-able data and back (``format: "workcell-cell", version: 1``):
the model through :meth:`Model.to_dict`; static and movable parts (entity, pose, colour,
density); robots as their library name, their robot file (path relative to the cell
file, sha256, import options) or their chain inline (:mod:`workcell.cell.robot_json`),
plus gripper parameters, base pose and initial joint values; cameras; the logic devices
(signals, sensors, conveyors, sources, sinks: :mod:`workcell.cell.devices`). Lengths m,
angles rad, densities kg/m^3, fields of view deg.

:meth:`Workcell.to_dict <workcell.cell.workcell.Workcell.to_dict>` and
:meth:`Workcell.from_dict <workcell.cell.workcell.Workcell.from_dict>` call
:func:`cell_to_dict` and :func:`cell_from_dict`.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from workcell.cell.devices import device_sections, devices_to_dict
from workcell.cell.items import _NAME_RE
from workcell.cell.robot_json import kinematics_json, robot_from_json, robot_json
from workcell.errors import ModelError, WorkcellError
from workcell.modeller.model import MAX_NAME_LENGTH, Model

if TYPE_CHECKING:
    from workcell.cell.workcell import Workcell

__all__ = ["FORMAT", "VERSION", "cell_from_dict", "cell_to_dict"]

FORMAT = "workcell-cell"
VERSION = 1


def cell_to_dict(
    cell: Workcell, base_dir: str | os.PathLike | None = None, *, kinematics: bool = False
) -> dict:
    """The cell as JSON-able data. A robot is its library name, its robot file
    (path relative to ``base_dir`` when given, else absolute) or its chain inline
    (:mod:`workcell.cell.robot_json`); ModelError for one that cannot be saved.
    ``kinematics``: a robot file's entry also carries the robot's kinematics, for a
    reader without the file (a server's reply to a client on another machine)."""
    robots = []
    folder = None if base_dir is None else Path(os.path.abspath(base_dir))
    for r in cell.robots.values():
        entry: dict[str, Any] = {"name": r.name}
        if r.builtin is not None:
            entry["builtin"] = r.builtin
        else:
            try:
                entry.update(robot_json(r.bare or r.robot, folder))
                if kinematics and "file" in entry:
                    entry["kinematics"] = kinematics_json(r.bare or r.robot)
            except ModelError as exc:
                raise ModelError(f"robot '{r.name}' cannot be saved: {exc}") from exc
        entry["gripper"] = None if r.gripper_parameters is None else dict(r.gripper_parameters)
        entry["base"], entry["q"] = r.base.tolist(), r.q.tolist()
        robots.append(entry)
    return {
        "format": FORMAT,
        "version": VERSION,
        "name": cell.name,
        "model": cell.model.to_dict(),
        "static": [
            {
                "name": p.name,
                "entity": list(p.entity),
                "pose": p.pose.tolist(),
                "colour": list(p.colour),
            }
            for p in cell.static_parts.values()
        ],
        "movable": [
            {
                "name": p.name,
                "entity": list(p.entity),
                "pose": p.pose.tolist(),
                "colour": list(p.colour),
                "density": p.density,
            }
            for p in cell.movable_parts.values()
        ],
        "robots": robots,
        "cameras": [
            {
                "name": c.name,
                "position": c.position.tolist(),
                "target": c.target.tolist(),
                "fovy": c.fovy,
            }
            for c in cell.cameras.values()
        ],
        **devices_to_dict(cell),
    }


def cell_from_dict(
    cls: type[Workcell],
    data: object,
    *,
    source: str = "cell data",
    base_dir: str | os.PathLike | None = None,
    root: str | os.PathLike | None = None,
) -> Workcell:
    """Rebuild a cell (a ``cls``) from :func:`cell_to_dict` data; ModelError naming the
    faulty place.

    Robot file paths are relative to ``base_dir`` (absolute when None); with ``root``
    (a server's folder) no robot file outside it is read.
    """
    folder = None if base_dir is None else Path(os.path.abspath(base_dir))

    def fail(where: str, exc: BaseException | str) -> ModelError:
        return ModelError(f"{source}: {where}: {exc}")

    if not isinstance(data, dict):
        raise fail("top level", "expected a JSON object")
    if data.get("format") != FORMAT:
        # never quote the field: the file may be anything (a server reads files by name)
        hint = (
            " (a model file: load it as a model)" if data.get("format") == "workcell-model" else ""
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
            lambda e: cell.add_static(e["name"], tuple(e["entity"]), e["pose"], colour=e["colour"]),
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
                e["name"],
                e["builtin"] if "builtin" in e else robot_from_json(e, folder, root),
                gripper=e.get("gripper"),
                base=e["base"],
                q=e["q"],
            ),
        ),
        (
            "cameras",
            lambda e: cell.add_camera(e["name"], e["position"], e["target"], e["fovy"]),
        ),
        *device_sections(cell),
    ]
    for key, add in sections:
        entries = data.get(key, [])
        if not isinstance(entries, list):
            raise fail(key, "expected a list")
        for i, e in enumerate(entries):
            where = f"{key}[{i}]"
            name = e.get("name") if isinstance(e, dict) else None
            if isinstance(name, str) and len(name) <= MAX_NAME_LENGTH and _NAME_RE.fullmatch(name):
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
