"""Solids as MuJoCo mesh geoms: STL assets, convex collision pieces, geoms in an MjSpec.

Cells (:mod:`workcell.cell.compile`) and robots (:mod:`workcell.robots.mjcf`) put modeller
solids into MuJoCo the same way, through this module:

- every solid is one *visual* mesh geom (the exact mesh, ``inertia="exact"``, carrying the
  mass at its density, no contacts, group :data:`VISUAL_GROUP`) plus massless *collision*
  geoms on convex pieces (group :data:`COLLISION_GROUP`, stiff contacts
  :data:`CONTACT_SOLREF`, :data:`CONTACT_SOLIMP`): :func:`add_mesh_geoms`;
- mesh assets are binary STL bytes (:func:`stl_bytes`) registered under unique names by a
  :class:`MeshAssets` (``spec.assets`` at compile time; written to :data:`MESHDIR` beside
  an exported XML);
- MuJoCo collides a mesh geom through its convex hull, so a non-convex solid needs convex
  pieces. The rule (:func:`convex_pieces`):

  1. a convex solid (hull volume equals its volume within 1e-7 relative) is its own
     piece: the visual mesh asset is reused for collisions;
  2. an object, or a boolean *union* block: the pieces of each block or object it is made
     of, placed by its relation (recursively), so a union of convex primitives collides
     exactly;
  3. anything else (a non-convex sweep, a difference or intersection, an imported
     mesh): an approximate convex decomposition by CoACD within the error bound
     ``concavity`` (:mod:`workcell.decompose`; cached on disk by mesh hash), so holes,
     slots and cavities stay open: a bin holds a part;
  4. a solid CoACD cannot split (degenerate) collides as its convex hull.

:func:`collision_pieces` also says which rule applied (for ``workcell info``).

Units: metres, kg/m^3.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import mujoco
import trimesh
from scipy.spatial import ConvexHull, QhullError

from workcell.decompose import DEFAULT_CONCAVITY, decompose, decompose_many
from workcell.modeller.model import Model

__all__ = [
    "COLLISION_GROUP",
    "CONTACT_SOLIMP",
    "CONTACT_SOLREF",
    "MESHDIR",
    "VISUAL_GROUP",
    "CollisionPieces",
    "MeshAssets",
    "add_mesh_geoms",
    "collision_meshes",
    "collision_pieces",
    "convex_pieces",
    "decompose_ahead",
    "is_convex",
    "mass_inertia",
    "stl_bytes",
]

VISUAL_GROUP = 2
COLLISION_GROUP = 3
MESHDIR = "meshes"
CONTACT_SOLREF = (0.004, 1.0)  # s, damping ratio: stiff contacts (MuJoCo clamps to >= 2 dt)
CONTACT_SOLIMP = (0.95, 0.99, 0.001, 0.5, 2.0)  # MuJoCo's default is (0.9, 0.95, 0.001, ...)
_CONVEX_REL_TOL = 1e-7
_EXACT = mujoco.mjtMeshInertia.mjMESH_INERTIA_EXACT
_CONVEX = mujoco.mjtMeshInertia.mjMESH_INERTIA_CONVEX
_MIN_VOLUME = 1e-12  # m^3
_MESH = mujoco.mjtGeom.mjGEOM_MESH
_COMPOSED = ("block", "object")


def stl_bytes(mesh: trimesh.Trimesh) -> bytes:
    """Binary STL of ``mesh`` (float32 vertices: 84 + 50 x faces bytes)."""
    return mesh.export(file_type="stl")


def is_convex(mesh: trimesh.Trimesh, rel_tol: float = _CONVEX_REL_TOL) -> bool:
    """True when the closed mesh fills its convex hull (volumes equal within ``rel_tol``)."""
    v = float(mesh.volume)
    try:
        hull = float(ConvexHull(mesh.vertices).volume)
    except QhullError:  # flat or degenerate: no volume to fill
        return False
    return v > 0 and hull - v <= rel_tol * hull


@dataclass(frozen=True)
class CollisionPieces:
    """The convex collision pieces of a solid (in its own frame, m) and how they were
    made: ``method`` "convex" (the solid itself), "exact" (exact convex pieces of the
    blocks it is made of), "coacd" (CoACD's decomposition somewhere in it, within
    ``concavity``) or "hull" (the convex hull of a solid that could not be split)."""

    pieces: list[trimesh.Trimesh]
    method: str

    @property
    def convex(self) -> bool:
        """The solid is convex: its one piece is itself."""
        return self.method == "convex"


Decomposer = Callable[..., list[trimesh.Trimesh]]


def collision_pieces(
    model: Model,
    ref: str | tuple[str, str],
    concavity: float = DEFAULT_CONCAVITY,
    *,
    decomposer: Decomposer = decompose,
) -> CollisionPieces:
    """Convex collision pieces of a block or object (module doc, rules 1-4). ``ref``: a
    block name or ``(level, name)``; ``concavity``: CoACD's error bound; ``decomposer``:
    rule 3's ``f(mesh, concavity, label=...)`` (:func:`workcell.decompose.decompose`)."""
    level, name = ref if isinstance(ref, tuple) else ("block", ref)
    mesh = model.world_mesh((level, name))
    if is_convex(mesh):
        return CollisionPieces([mesh], "convex")
    if level == "object" or model.info((level, name)).boolean == "union":
        pieces: list[trimesh.Trimesh] = []
        methods = set()
        for rel in model.relations((level, name)):
            if rel.target_level not in _COMPOSED:
                return CollisionPieces([mesh.convex_hull], "hull")
            sub = collision_pieces(
                model, (rel.target_level, rel.target), concavity, decomposer=decomposer
            )
            pieces.extend(p.copy().apply_transform(rel.transform) for p in sub.pieces)
            methods.add(sub.method)
        if pieces:
            worst = next((m for m in ("hull", "coacd") if m in methods), "exact")
            return CollisionPieces(pieces, worst)
    pieces = decomposer(mesh, concavity, label=f"{level} '{name}'")
    return CollisionPieces(pieces, "coacd" if len(pieces) > 1 else "hull")


def decompose_ahead(
    model: Model, refs: Sequence[str | tuple[str, str]], concavity: float = DEFAULT_CONCAVITY
) -> None:
    """Decompose at once, on all cores, every mesh that :func:`collision_pieces` of
    ``refs`` will ask CoACD for (:func:`workcell.decompose.decompose_many`), so the calls
    that follow come from the cache: one batch of child processes instead of one per part."""
    wanted: list[tuple[trimesh.Trimesh, str]] = []

    def note(mesh: trimesh.Trimesh, concavity: float, *, label: str) -> list[trimesh.Trimesh]:
        wanted.append((mesh, label))
        return [mesh]

    for ref in refs:
        if len(model.world_mesh(ref).faces):  # an empty part: the caller's error to give
            collision_pieces(model, ref, concavity, decomposer=note)
    if wanted:
        decompose_many([m for m, _ in wanted], concavity, labels=[lb for _, lb in wanted])


def convex_pieces(
    model: Model, ref: str | tuple[str, str], concavity: float = DEFAULT_CONCAVITY
) -> tuple[list[trimesh.Trimesh], bool]:
    """Convex collision pieces of a block or object in its own frame, and whether it is
    convex (one piece: its own cached world mesh); see :func:`collision_pieces`."""
    c = collision_pieces(model, ref, concavity)
    return c.pieces, c.convex


@dataclass
class MeshAssets:
    """Mesh assets and unique geom/mesh names while one MjSpec is built.

    ``assets`` maps file names (``{mesh name}.stl``) to STL bytes; ``prefix`` is prepended
    by callers that namespace their names (a robot's ``"puma_1."``).
    """

    spec: mujoco.MjSpec
    prefix: str = ""
    assets: dict[str, bytes] = field(default_factory=dict)
    names: dict[str, set[str]] = field(default_factory=lambda: {"mesh": set(), "geom": set()})

    def unique(self, name: str, kind: str = "geom") -> str:
        """``name``, or ``name.2``, ``name.3`` ... when a ``kind`` of that name exists."""
        taken = self.names[kind]
        out, k = name, 1
        while out in taken:
            k += 1
            out = f"{name}.{k}"
        taken.add(out)
        return out

    def add(self, name: str, mesh: trimesh.Trimesh, inertia: mujoco.mjtMeshInertia = _EXACT) -> str:
        """Register ``mesh`` as asset ``name`` (made unique; exact inertia unless
        ``inertia`` says otherwise, see :func:`mass_inertia`); return the mesh name."""
        mname = self.unique(name, "mesh")
        file = f"{mname}.stl"
        self.assets[file] = stl_bytes(mesh)
        self.spec.add_mesh(name=mname, file=file, inertia=inertia)
        return mname


def mass_inertia(mesh: trimesh.Trimesh) -> mujoco.mjtMeshInertia | None:
    """How MuJoCo should take the mass of ``mesh`` (e.g. a visual mesh read from a robot
    file): exactly when it is closed with a positive volume (MuJoCo's exact inertia needs
    a closed surface), from its convex hull when it is open (a DAE surface), None when
    even its hull is flat (it can carry no mass)."""
    if mesh.is_watertight and mesh.volume > _MIN_VOLUME:
        return _EXACT
    try:
        hull = float(ConvexHull(mesh.vertices).volume)
    except (QhullError, ValueError):
        return None
    return _CONVEX if hull > _MIN_VOLUME else None


def collision_meshes(
    reg: MeshAssets, name: str, pieces: list[trimesh.Trimesh], convex: bool, visual: str
) -> list[str]:
    """Mesh names of a solid's collision pieces: its ``visual`` mesh when it is convex,
    else one asset ``{name}.hull{i}`` per piece."""
    if convex:
        return [visual]
    return [reg.add(f"{name}.hull{i}", p) for i, p in enumerate(pieces)]


def add_mesh_geoms(
    body: mujoco.MjsBody,
    visuals: list[tuple[str, str]],
    collisions: list[str],
    *,
    collision_prefix: str,
    pos: list[float],
    quat: list[float],
    density: float,
    rgba: list[float],
) -> None:
    """The geoms of one solid in ``body``: visual mesh geoms that carry the mass and no
    contacts (``visuals`` = (geom name, mesh name) pairs, group 2) and massless collision
    geoms named ``{collision_prefix}.col{i}`` on the ``collisions`` meshes (group 3, stiff
    contacts: :data:`CONTACT_SOLREF`, :data:`CONTACT_SOLIMP`). ``density`` in kg/m^3;
    ``pos``/``quat`` place the meshes in the body (m, wxyz)."""
    for geom, mesh in visuals:
        body.add_geom(
            name=geom,
            type=_MESH,
            meshname=mesh,
            pos=pos,
            quat=quat,
            density=density,
            contype=0,
            conaffinity=0,
            group=VISUAL_GROUP,
            rgba=rgba,
        )
    for i, mesh in enumerate(collisions):
        body.add_geom(
            name=f"{collision_prefix}.col{i}",
            type=_MESH,
            meshname=mesh,
            pos=pos,
            quat=quat,
            density=0.0,
            contype=1,
            conaffinity=1,
            group=COLLISION_GROUP,
            rgba=[*rgba[:3], 0.5],
            solref=list(CONTACT_SOLREF),
            solimp=list(CONTACT_SOLIMP),
        )
