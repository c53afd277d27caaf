"""MJCF files whose mesh or texture files are missing, or not wanted: still a robot.

A MuJoCo Menagerie arm copied without its ``assets/`` folder names every mesh and MuJoCo
refuses to compile it; its kinematics are all in the XML. :func:`workcell.robots.mjcf_files.read_mjcf`
looks for each file where MuJoCo 3.17 does (``meshdir``/``assetdir`` of any
``<compiler>``, relative to the main file's folder: so a ``scene.xml`` including
``panda.xml`` looks in ``assets/``, where MuJoCo's own error names a path without it) and
lists a mesh or texture file found nowhere in the import's
:class:`~workcell.robots.standin.Missing` (a ModelError with ``strict``), leaving it
unread. Before the model is compiled, :func:`stand_in_missing` turns the geoms of such a
mesh into small placeholder spheres (so the model compiles with the file's own
inertias; the importer replaces them by the body's capsule stand-in) and such a texture
into a plain grey one. With ``geometry=False`` no mesh or texture file is read at all:
every mesh geom is a placeholder and nothing is reported (only the kinematics are
wanted).
"""

from __future__ import annotations

from collections.abc import Collection

import mujoco

__all__ = ["PLACEHOLDER", "stand_in_missing"]

PLACEHOLDER = "workcell_standin"  # name prefix of the placeholder geoms
_SIZE = 0.005  # m: a placeholder sphere's radius


def stand_in_missing(spec: mujoco.MjSpec, absent: Collection[str]) -> tuple[set[str], set[str]]:
    """Stand in for the meshes and textures of ``spec`` whose files (asset names, as
    :func:`~workcell.robots.mjcf_files.read_mjcf` gave them) are ``absent`` (module doc);
    (the names of the placeholder geoms, the names of the bodies whose inertia the file
    states: the stand-ins' sizes may come from it)."""
    gone = {m.name for m in spec.meshes if m.file in absent}
    for tex in spec.textures:
        if tex.file in absent:
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
