"""MJCF files whose mesh or texture files are missing, or not wanted: still a robot.

A MuJoCo Menagerie arm copied without its ``assets/`` folder names every mesh and MuJoCo
refuses to compile it; its kinematics are all in the XML. Before the model is compiled,
:func:`stand_in_missing` looks for each mesh and texture file where MuJoCo 3.17 looks:

- ``meshdir`` (or ``assetdir``) of the model's ``<compiler>``, wherever it stands (in an
  included file too), relative to the main model file's folder, then the name;
  ``texturedir`` likewise for textures; an absolute name as it is;
- a mesh named in an included file that MuJoCo did not find there comes back from its
  parser prefixed with the include's folder (so MuJoCo's own error for ``scene.xml``
  names a path without ``assets/``); the name as the file wrote it is that path relative
  to the main file's folder, and both places are tried and listed.

A file found is given to MuJoCo by its full path. A mesh file found nowhere is listed in
the import's :class:`~workcell.robots.standin.Missing` (a ModelError with ``strict``),
its geoms become small placeholder spheres (so the model compiles with the file's own
inertias) that the importer replaces by the body's capsule stand-in; a missing texture
becomes a plain grey one. With ``geometry=False`` no mesh or texture file is looked at:
every mesh geom is a placeholder and nothing is reported (only the kinematics are wanted).
"""

from __future__ import annotations

import os
from pathlib import Path

import mujoco

from workcell.robots.standin import Missing

__all__ = ["PLACEHOLDER", "stand_in_missing"]

PLACEHOLDER = "workcell_standin"  # name prefix of the placeholder geoms
_SIZE = 0.005  # m: a placeholder sphere's radius


def _places(spec: mujoco.MjSpec, base: Path, folder: str, file: str) -> tuple[str, list[Path]]:
    """(the name as the file wrote it, where MuJoCo 3.17 looks for it) (module doc)."""
    written, places = file, []
    if os.path.isabs(file):
        try:  # the include's folder that MuJoCo put in front of an unfound name
            written = os.path.relpath(file, base)
        except ValueError:
            written = file
        if written.startswith(".."):
            written = file
    if not os.path.isabs(written):
        places.append(base / folder / written)
    places.append(Path(file) if os.path.isabs(file) else base / file)
    return written, list(dict.fromkeys(places))


def stand_in_missing(
    spec: mujoco.MjSpec, path: Path, missing: Missing, *, geometry: bool = True
) -> tuple[set[str], set[str]]:
    """Resolve the mesh and texture files of ``spec`` (parsed from ``path``) and stand in
    for the missing ones (module doc); (the names of the placeholder geoms, the names of
    the bodies whose inertia the file states: the stand-ins' sizes may come from it)."""
    base = Path(spec.modelfiledir or path.parent)
    gone: dict[str, str] = {}  # mesh name -> why (for the geoms that use it)
    for mesh in list(spec.meshes):
        if not mesh.file:
            continue
        mesh.name = mesh.name or Path(mesh.file).stem  # MuJoCo's name for an unnamed one
        written, places = _places(spec, base, spec.meshdir, mesh.file)
        found = next((p for p in places if p.is_file()), None) if geometry else None
        if found is not None:
            mesh.file = str(found)
            continue
        if geometry:
            missing.add(written, f"mesh '{mesh.name}'", [str(p) for p in places],
                        "a capsule between its body's joints stands in")  # fmt: skip
        gone[mesh.name] = written
    for tex in spec.textures:
        if not tex.file:
            continue
        written, places = _places(spec, base, spec.texturedir, tex.file)
        found = next((p for p in places if p.is_file()), None) if geometry else None
        if found is not None:
            tex.file = str(found)
            continue
        tex.file = ""
        tex.builtin = mujoco.mjtBuiltin.mjBUILTIN_FLAT
        tex.width = tex.height = 8
        tex.rgb1 = tex.rgb2 = [0.6, 0.6, 0.6]
    names: set[str] = set()
    for k, geom in enumerate(spec.geoms):
        if geom.type != mujoco.mjtGeom.mjGEOM_MESH or geom.meshname not in gone:
            continue
        geom.type = mujoco.mjtGeom.mjGEOM_SPHERE
        geom.size = [_SIZE, 0.0, 0.0]
        geom.meshname = ""
        if not geom.name:
            geom.name = f"{PLACEHOLDER}{k}"
        names.add(geom.name)
    for mesh in list(spec.meshes):
        if mesh.name in gone:
            spec.delete(mesh)
    return names, {b.name for b in spec.bodies if b.explicitinertial}
