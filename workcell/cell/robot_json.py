"""How a cell file saves a robot that is not a library name, and rebuilds it.

A cell's robot entry holds exactly one of (:meth:`workcell.Workcell.to_dict`):

- ``"builtin"``: a library name (:func:`workcell.robots.get`);
- ``"file"``: a robot read from a URDF or MJCF file (``Robot.file``): ``format``,
  ``path`` (relative to the cell file's folder when the cell is saved to a file),
  ``sha256`` of the robot file's bytes and the import ``options``
  (:func:`workcell.robots.from_urdf`, :func:`workcell.robots.from_mjcf`; folders in
  ``packages`` and ``search`` relative like the path). Loading re-imports the file; a
  robot file that is missing or whose bytes changed since the cell was saved is a
  ModelError, so a cell never silently runs another robot. A server's ``cell_data``
  reply adds ``"kinematics"`` (:func:`kinematics_json`) beside ``"file"``: a client on
  another machine, without the file, rebuilds the robot from it (with a warning), without
  link geometry;
- ``"chain"``: any other robot, inline: its joints (each by its DH row when it was built
  from one, else by origin, axis and axis point), limits, speeds, accelerations and jerks
  (null: none), base, tool, named poses, nominal speed, source, and its link solids (the
  robot's modeller model and the placements of its blocks). A robot with meshes not read
  from a file, or carrying a gripper attached outside the cell, cannot be saved
  (ModelError saying what to do instead).

Numbers are written as JSON floats, which Python reads back bit for bit: a rebuilt robot
has the same FK to the last bit. Units: metres, radians, seconds.
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from workcell.errors import ModelError
from workcell.files import read_bytes, resolve_inside
from workcell.modeller.model import Model
from workcell.robots.chain import Joint
from workcell.robots.meshfile import sha256
from workcell.robots.robot import LinkGeometry, Robot

__all__ = ["kinematics_json", "robot_from_json", "robot_json"]

_LIMITS = ("max_speed", "max_acceleration", "max_jerk")


def _num(v: float) -> float | None:
    return None if math.isinf(v) else float(v)


def _rel(path: str, base_dir: Path | None) -> str:
    return path if base_dir is None else os.path.relpath(path, base_dir)


def _abs(path: str, base_dir: Path | None) -> str:
    return str(path) if base_dir is None else os.path.normpath(base_dir / path)


def _joint_json(j: Joint) -> dict[str, Any]:
    out: dict[str, Any] = {"name": j.name, "kind": j.kind, "limits": list(j.limits)}
    out.update({k: _num(getattr(j, k)) for k in _LIMITS})
    if j.dh is not None:
        d = j.dh
        out["dh"] = {
            "convention": d.convention,
            "a": d.a,
            "alpha": d.alpha,
            "d": d.d,
            "theta": d.theta,
            "offset": d.offset,
        }
    else:
        out.update(origin=j.origin.tolist(), axis=j.axis.tolist(), axis_point=j.axis_point.tolist())
    return out


def _joint(e: Mapping[str, Any]) -> Joint:
    lims = {k: math.inf if e[k] is None else float(e[k]) for k in _LIMITS}
    lims["limits"] = tuple(e["limits"])
    if "dh" in e:
        d = e["dh"]
        return Joint.from_dh(
            e["name"],
            a=d["a"],
            alpha=d["alpha"],
            d=d["d"],
            theta=d["theta"],
            offset=d["offset"],
            kind=e["kind"],
            convention=d["convention"],
            **lims,
        )
    return Joint(
        e["name"], np.array(e["origin"]), e["axis"], e["kind"], axis_point=e["axis_point"], **lims
    )  # type: ignore[arg-type]


def robot_json(robot: Robot, base_dir: Path | None = None) -> dict[str, Any]:
    """``{"file": ...}`` or ``{"chain": ...}`` for ``robot`` (module doc); paths relative
    to ``base_dir`` when given. ModelError for a robot that cannot be saved."""
    if robot.file is not None:
        f = robot.file
        opts = dict(f.options)
        if "packages" in opts:
            opts["packages"] = {k: _rel(v, base_dir) for k, v in opts["packages"].items()}
        if "search" in opts:
            opts["search"] = [_rel(s, base_dir) for s in opts["search"]]
        opts["name"] = robot.name
        file = {"format": f.format, "path": _rel(f.path, base_dir), "sha256": f.sha256}
        return {"file": {**file, "options": opts}}
    if robot.gripper is not None:
        raise ModelError(
            f"robot '{robot.name}' carries gripper '{robot.gripper.name}' attached outside the "
            "cell; add the robot without it and give add_robot(..., gripper=...) instead, so "
            "the cell can save it"
        )
    if any(g.mesh is not None for g in robot.geometry):
        raise ModelError(
            f"robot '{robot.name}' has mesh geometry that was not read from a robot file; "
            "import it with from_urdf or from_mjcf (the cell saves the file), or give it "
            "modeller solids"
        )
    chain = kinematics_json(robot)
    chain["model"] = None if robot.model is None else robot.model.to_dict()
    chain["geometry"] = [
        {
            "link": g.link,
            "block": g.block,
            "transform": g.transform.tolist(),
            "colour": None if g.colour is None else list(g.colour),
        }
        for g in robot.geometry
    ]
    return {"chain": chain}


def kinematics_json(robot: Robot) -> dict[str, Any]:
    """A ``"chain"`` entry of ``robot`` without its link geometry and gripper: joints,
    limits, base, tool, named poses, nominal speed, source (module doc)."""
    return {
        "name": robot.name,
        "source": robot.source,
        "nominal_speed": robot.nominal_speed,
        "base": robot.base.tolist(),
        "tool": robot.tool.tolist(),
        "poses": {k: v.tolist() for k, v in robot.poses.items()},
        "joints": [_joint_json(j) for j in robot.joints],
    }


def _file_robot(f: Mapping[str, Any], base_dir: Path | None, root: Path | None) -> Robot:
    from workcell.robots import from_mjcf, from_urdf

    fmt = f["format"]
    if fmt not in ("urdf", "mjcf"):
        raise ModelError(f"robot file format must be urdf or mjcf, got {fmt!r}")
    path = Path(_abs(f["path"], base_dir))
    if root is not None:
        path = resolve_inside(root, os.path.relpath(path, root), error=ModelError)
    data = read_bytes(path, what=f"robot file ({fmt})", error=ModelError)
    if sha256(data) != f["sha256"]:
        raise ModelError(
            f"robot file '{path}' changed since the cell was saved (its sha256 differs); "
            "import the robot again and save the cell, or restore the file"
        )
    opts = dict(f.get("options") or {})
    if "packages" in opts:
        opts["packages"] = {k: _abs(v, base_dir) for k, v in opts["packages"].items()}
    if "search" in opts:
        opts["search"] = [_abs(s, base_dir) for s in opts["search"]]
    allowed = {
        "urdf": {
            "packages",
            "search",
            "base_link",
            "tip_link",
            "name",
            "gripper",
            "geometry",
            "concavity",
            "link_seconds",
            "strict",
        },
        "mjcf": {"base_body", "tip_body", "tool_site", "name", "gripper", "geometry", "strict"},
    }[fmt]
    bad = sorted(set(opts) - allowed)
    if bad:
        raise ModelError(
            f"unknown {fmt} import option(s) {bad}; valid: {', '.join(sorted(allowed))}"
        )
    load = from_urdf if fmt == "urdf" else from_mjcf
    return load(path, root=root, **opts)


def robot_from_json(
    entry: Mapping[str, Any], base_dir: Path | None = None, root: Path | None = None
) -> Robot:
    """The robot of a ``"file"`` or ``"chain"`` entry (module doc); ``root`` confines the
    files a file robot reads. ModelError (or KeyError/TypeError/ValueError for malformed
    data, which the cell loader reports with the entry's place)."""
    if "file" in entry:
        try:
            return _file_robot(entry["file"], base_dir, root)
        except ModelError as exc:
            if "kinematics" not in entry:
                raise
            warnings.warn(
                f"{exc}; robot '{entry['kinematics'].get('name')}' is rebuilt from the "
                "kinematics sent with it (joints, limits, base, tool, poses), without its "
                "link geometry and its file's gripper",
                stacklevel=2,
            )
            return _chain_robot(entry["kinematics"])
    return _chain_robot(entry["chain"])


def _chain_robot(c: Mapping[str, Any]) -> Robot:
    model = None if c.get("model") is None else Model.from_dict(c["model"])
    geometry = tuple(
        LinkGeometry(
            int(g["link"]),
            str(g["block"]),
            np.array(g["transform"], dtype=float),
            None if g["colour"] is None else tuple(g["colour"]),
        )
        for g in c.get("geometry", [])
    )
    if geometry and model is None:
        raise ModelError("a robot's link solids need its model")
    for g in geometry:
        model.info(("block", g.block))  # a ModelError naming the known blocks
    return Robot(
        name=str(c["name"]),
        joints=tuple(_joint(j) for j in c["joints"]),
        base=np.array(c["base"], dtype=float),
        tool=np.array(c["tool"], dtype=float),
        poses={k: np.array(v, dtype=float) for k, v in c.get("poses", {}).items()},
        nominal_speed=float(c.get("nominal_speed", 0.3)),
        model=model,
        geometry=geometry,
        source=str(c.get("source", "")),
    )
