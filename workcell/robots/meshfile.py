"""Reading robot files safely: XML without entities, meshes within the work limits, primitives.

- :func:`parse_xml`: a robot file's XML through expat, with every entity declaration and
  external entity refused (no "billion laughs", no file or network reads behind the
  reader's back) and each element's line number kept for messages;
- :func:`load_mesh`: an STL, OBJ, PLY or COLLADA (DAE) file as meshes in metres, each with
  its own colour when the file gives one (a DAE scene keeps one mesh per part, parts
  of fewer than 4 distinct vertices left out: MuJoCo takes no such mesh; its ``<unit meter>`` is
  applied; its ``<up_axis>`` is not, as ROS-Industrial's files are Z-up), read through :func:`workcell.files.read_bytes` (``max_file_bytes``) and refused
  beyond ``max_facets`` (:mod:`workcell.limits`); a DAE with entity declarations is
  refused as the XML is;
- :func:`primitive`: a box, cylinder, sphere, capsule or ellipsoid as a closed mesh
  (vertices on the surface: 32 sides, a 2-times subdivided icosphere);
- :func:`joint_speeds`: the speed, acceleration and jerk limits of an imported joint:
  the file's speed, else :data:`DEFAULT_SPEED` (1 rad/s) or :data:`DEFAULT_SLIDE_SPEED`
  (0.25 m/s); accelerations and jerks, which URDF and MJCF do not state, derived from
  the speed as for the library's robots
  (:func:`workcell.robots.library.derived_limits`: full speed in 0.25 s, full
  acceleration in 0.05 s).

Units: metres, radians, seconds.
"""

from __future__ import annotations

import hashlib
import io
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any
from xml.parsers import expat

import numpy as np
import trimesh

from workcell import limits
from workcell.checks import check_size
from workcell.errors import ModelError
from workcell.files import read_bytes

__all__ = [
    "DEFAULT_SLIDE_SPEED",
    "DEFAULT_SPEED",
    "MESH_TYPES",
    "count_facets",
    "joint_speeds",
    "load_mesh",
    "parse_xml",
    "primitive",
    "sha256",
]

DEFAULT_SPEED = 1.0  # rad/s: a revolute joint whose file gives no speed
DEFAULT_SLIDE_SPEED = 0.25  # m/s: a prismatic joint whose file gives no speed
MESH_TYPES = ("stl", "obj", "ply", "dae")
_SIDES = 32
_UNIT = re.compile(r"^\s*([0-9.eE+-]+)\s*\*\s*meters\s*$")

Colour = tuple[float, float, float, float]


def sha256(data: bytes) -> str:
    """Hex SHA-256 of ``data``."""
    return hashlib.sha256(data).hexdigest()


def parse_xml(data: bytes, what: str) -> tuple[ET.Element, dict[ET.Element, int]]:
    """The root element of XML ``data`` and each element's line number.

    ModelError naming ``what`` for XML that does not parse (with line and column) or
    that declares entities (refused, see the module doc).
    """
    lines: dict[ET.Element, int] = {}
    builder = ET.TreeBuilder()
    parser = expat.ParserCreate()
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)

    def refuse(*_: Any) -> None:
        raise ModelError(
            f"{what}: line {parser.CurrentLineNumber}: entity declarations and external "
            "entities are refused (a robot file does not need them)"
        )

    def start(tag: str, attrs: dict[str, str]) -> None:
        lines[builder.start(tag, attrs)] = parser.CurrentLineNumber

    parser.EntityDeclHandler = refuse
    parser.ExternalEntityRefHandler = refuse
    parser.StartElementHandler = start
    parser.EndElementHandler = builder.end
    parser.CharacterDataHandler = builder.data
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise ModelError(
            f"{what} is not well-formed XML: line {exc.lineno}, column {exc.offset}: "
            f"{expat.ErrorString(exc.code)}"
        ) from None
    return builder.close(), lines


_OBJ_FACE = re.compile(rb"(?m)^[ \t]*f[ \t][^\n]*")
_PLY_FACES = re.compile(rb"(?m)^element[ \t]+face[ \t]+(\d{1,15})")
_DAE_COUNT = re.compile(
    rb"<(?:triangles|polylist|polygons|tristrips|trifans)\b[^>]*?\bcount=\"(\d{1,15})\""
)


def count_facets(data: bytes, suffix: str) -> int:
    """The triangles a mesh file's bytes hold, counted without parsing it (to refuse a
    file over ``max_facets`` before a reader spends seconds and gigabytes on it).

    Binary STL: the header's count (when the size agrees); ASCII STL: its ``endfacet``
    lines; OBJ: each face line's vertices less 2; PLY: the header's face count; COLLADA:
    the ``count`` of its triangle and polygon lists; MuJoCo's MSH: its header's face
    count. 0 for other types (their readers bound themselves)."""
    ext = suffix.lower().lstrip(".")
    if ext == "stl":
        if len(data) >= 84:
            n = int.from_bytes(data[80:84], "little")
            if len(data) == 84 + 50 * n:
                return n
        return data.count(b"endfacet") + data.count(b"ENDFACET")
    if ext == "obj":
        lines = data.count(b"\nf ") + data.count(b"\nf\t") + int(data.startswith(b"f"))
        if lines > limits.current().max_facets:
            return lines  # each face line is at least one triangle: over already
        return sum(max(len(m.group().split()) - 3, 1) for m in _OBJ_FACE.finditer(data))
    if ext == "ply":
        m = _PLY_FACES.search(data[:65536])
        return int(m.group(1)) if m else 0
    if ext == "dae":
        return sum(int(m.group(1)) for m in _DAE_COUNT.finditer(data))
    if ext == "msh" and len(data) >= 16:
        return int.from_bytes(data[12:16], "little", signed=True)
    return 0


def _colour(visual: Any) -> Colour | None:
    """The main RGBA colour (0..1) of a trimesh visual, None when it has none."""
    try:
        if visual.kind == "texture":
            c = visual.material.main_color
        elif visual.kind is not None:
            c = visual.main_color
        else:
            return None
    except (AttributeError, ValueError, IndexError):
        return None
    rgba = np.asarray(c, dtype=np.float64).reshape(-1)[:4] / 255.0
    return tuple(float(v) for v in rgba) if rgba.size == 4 else None  # type: ignore[return-value]


def _solid_enough(mesh: trimesh.Trimesh) -> bool:
    """At least 4 distinct vertices (as float32, as MuJoCo reads an STL): a mesh MuJoCo takes."""
    return len(mesh.faces) > 0 and len(np.unique(mesh.vertices.astype(np.float32), axis=0)) >= 4


def _check_dae(data: bytes, what: str) -> None:
    head = data[:4]
    if head.startswith((b"\xff\xfe", b"\xfe\xff")) or b"<!ENTITY" in data or b"<!DOCTYPE" in data:
        raise ModelError(
            f"{what}: a COLLADA file with a DOCTYPE, entities or UTF-16 text is refused"
        )


def load_mesh(
    path: Path, *, scale: tuple[float, float, float] = (1.0, 1.0, 1.0), what: str = "mesh"
) -> list[tuple[trimesh.Trimesh, Colour | None]]:
    """The meshes of mesh file ``path`` (module doc), scaled by ``scale`` (3 factors).

    ModelError for an unknown type, an unreadable or empty file; LimitError beyond the
    work limits.
    """
    ext = path.suffix.lower().lstrip(".")
    if ext not in MESH_TYPES:
        raise ModelError(
            f"{what}: cannot read mesh file '{path}': type '.{ext}' is not one of "
            f"{', '.join('.' + t for t in MESH_TYPES)}"
        )
    data = read_bytes(path, what="mesh file", error=ModelError)
    if ext == "dae":
        _check_dae(data, f"mesh file '{path}'")
    limits.check("max_facets", count_facets(data, ext), f"mesh file '{path}' (before reading it)")
    try:
        loaded = trimesh.load(io.BytesIO(data), file_type=ext)
    except Exception as exc:  # every reader's own failure means a bad file here
        raise ModelError(f"{what}: cannot read mesh file '{path}': {exc}") from None
    parts: list[tuple[trimesh.Trimesh, Colour | None]] = []
    if isinstance(loaded, trimesh.Scene):
        unit = 1.0
        m = _UNIT.match(str(loaded.metadata.get("units") or loaded.units or ""))
        if m:
            unit = float(m.group(1))
        for node in loaded.graph.nodes_geometry:
            T, gname = loaded.graph[node]
            g = loaded.geometry[gname]
            if isinstance(g, trimesh.Trimesh) and _solid_enough(g):
                mesh = g.copy().apply_transform(T)
                if unit != 1.0:
                    mesh.apply_scale(unit)
                parts.append((mesh, _colour(g.visual)))
    elif isinstance(loaded, trimesh.Trimesh) and _solid_enough(loaded):
        parts.append((loaded, _colour(loaded.visual)))
    if not parts:
        raise ModelError(f"{what}: mesh file '{path}' holds no triangles")
    limits.check("max_facets", sum(len(p.faces) for p, _ in parts), f"mesh file '{path}'")
    s = np.asarray(scale, dtype=np.float64)
    if not np.allclose(s, 1.0):
        S = np.diag([*s, 1.0])
        parts = [(p.apply_transform(S), c) for p, c in parts]  # trimesh re-winds a mirror
    return parts


def primitive(kind: str, *, size: tuple[float, ...] = (), what: str = "shape") -> trimesh.Trimesh:
    """A closed mesh centred on the origin (m): ``box`` (size = full x, y, z extents),
    ``cylinder`` (radius, full length along z), ``sphere`` (radius), ``capsule`` (radius,
    distance between the caps' centres, along z), ``ellipsoid`` (three radii).
    ModelError naming ``what`` for sizes that are not positive, DegenerateError (also a
    ModelError) for sizes under :data:`~workcell.checks.MIN_LENGTH`."""
    s = tuple(float(v) for v in size)
    need = {"box": 3, "cylinder": 2, "sphere": 1, "capsule": 2, "ellipsoid": 3}
    if kind not in need:
        raise ModelError(f"{what}: unknown shape '{kind}'; known: {', '.join(need)}")
    ok = len(s) == need[kind] and all(np.isfinite(v) and v > 0 for v in s)
    if kind == "capsule" and len(s) == 2 and s[0] > 0 and s[1] == 0:
        ok = True  # a capsule of length 0 is a sphere
    if not ok:
        raise ModelError(f"{what}: a {kind} needs {need[kind]} positive size(s), got {list(s)}")
    for k, v in enumerate(s):
        if not (kind == "capsule" and k == 1 and v == 0):
            check_size(f"{what}: a {kind}", f"size {k + 1}", v)
    limits.check("max_coordinate", max(s), what)
    if kind == "box":
        return trimesh.creation.box(extents=s)
    if kind == "cylinder":
        return trimesh.creation.cylinder(radius=s[0], height=s[1], sections=_SIDES)
    if kind == "capsule":
        return trimesh.creation.capsule(height=s[1], radius=s[0], count=[_SIDES, _SIDES // 2])
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
    radii = (s[0],) * 3 if kind == "sphere" else s
    return sphere.apply_transform(np.diag([*radii, 1.0]))


def joint_speeds(kind: str, speed: float | None) -> dict[str, float]:
    """``max_speed``, ``max_acceleration``, ``max_jerk`` of an imported joint (module doc);
    ``speed`` (rad/s or m/s) None or <= 0 when the file gives none."""
    from workcell.robots.library import derived_limits

    if speed is None or not np.isfinite(speed) or speed <= 0:
        speed = DEFAULT_SLIDE_SPEED if kind == "prismatic" else DEFAULT_SPEED
    (a,), (j,) = derived_limits([speed])
    return {"max_speed": float(speed), "max_acceleration": a, "max_jerk": j}
