"""The command language, datamodel part: the thesis's data sublanguage (§2.2) and solids.

Each entry of :data:`BRANCHES` is a top-level keyword and its key tree; every leaf
builds a command of :mod:`workcell.program.commands` or
:mod:`workcell.program.solidcommands`. Transforms are written as SRT factors
(``scale``, ``rotate`` (deg), ``translate`` (m); the thesis's M = T Rz Ry Rx S) or as
``matrix`` and 16 numbers, row by row.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from workcell import spatial
from workcell.errors import ProgramError
from workcell.modeller.surface import Surface
from workcell.program import commands as cmd
from workcell.program import solidcommands as sol
from workcell.program.keytree import Keys, Leaf, Node, Options, Seq, Set
from workcell.program.params import LEVEL_WORDS, Choice, Name, Number, Ref, Text, Vector

__all__ = ["BRANCHES", "TRANSFORM_OPTIONS", "transform_of"]

Matrix = tuple[tuple[float, ...], ...]

TRANSFORM_OPTIONS: dict[str, Node] = {
    "scale": Vector("scale", None, None, what="1 or 3 scale factors"),
    "rotate": Vector("rotate", 3, "angle", what="rx ry rz (deg)"),
    "translate": Vector("translate", 3, "length", what="tx ty tz (m)"),
    "matrix": Vector("matrix", 16, None, what="16 numbers, row by row"),
}
TRANSFORM_SYNTAX = (
    "[scale S | scale SX SY SZ] [rotate RX RY RZ] [translate TX TY TZ] | [matrix M11 .. M44]"
)


def transform_of(v: dict[str, Any]) -> Matrix | None:
    """The transform the SRT or matrix options in ``v`` give (None when none was given)."""
    keys = [k for k in TRANSFORM_OPTIONS if k in v]
    if not keys:
        return None
    if "matrix" in v:
        if len(keys) > 1:
            raise ProgramError("give a transform as matrix or as scale/rotate/translate, not both")
        return tuple(tuple(v["matrix"][4 * i : 4 * i + 4]) for i in range(4))
    s = v.get("scale", (1.0,))
    if len(s) not in (1, 3):
        raise ProgramError(f"scale takes 1 or 3 factors, got {len(s)}")
    M = spatial.srt(
        s[0] if len(s) == 1 else s,
        v.get("rotate", (0.0, 0.0, 0.0)),
        v.get("translate", (0.0, 0.0, 0.0)),
    )
    return tuple(tuple(float(x) for x in row) for row in M)


def _colour(v: dict[str, Any]) -> tuple[float, ...] | None:
    return v.get("colour")


_COLOUR = {"colour": Vector("colour", None, None, what="R G B [A] in [0, 1]")}


class Holes(Node):
    """``points X Y X Y ...`` then any number of ``hole X Y X Y ...`` (m)."""

    def expects(self, cur: Any) -> list[str]:
        return ["<x y x y ... (m)>"]

    def match(self, cur: Any) -> None:
        Vector("points", None, "length", what="x y x y ... (m)").match(cur)
        holes = []
        while (tok := cur.peek()) is not None and tok.kind == "word" and tok.text == "hole":
            cur.take()
            Vector("hole", None, "length", what="x y x y ... (m)").match(cur)
            holes.append(cur.values.pop("hole"))
        if cur.completing and cur.peek() is None:
            cur.fail("", ["hole", "colour"])
        cur.values["holes"] = holes


def _pairs(flat: tuple[float, ...], what: str) -> tuple[tuple[float, float], ...]:
    if len(flat) % 2 or len(flat) < 6:
        raise ProgramError(f"{what}: give x y pairs, at least 3 points; got {len(flat)} numbers")
    return tuple((flat[i], flat[i + 1]) for i in range(0, len(flat), 2))


def _surface(v: dict[str, Any]) -> cmd.CreateSurface:
    shape = v["shape"]
    if shape == "rectangle":
        pts = Surface.rectangle(v["w"], v["h"], center=v.get("centered", False)).main
    elif shape in ("polygon", "circle"):
        pts = Surface.regular_polygon(v["n"], v["r"]).main
    else:
        return cmd.CreateSurface(
            v["name"],
            _pairs(v["points"], "points"),
            tuple(_pairs(h, "hole") for h in v["holes"]),
            _colour(v),
        )
    return cmd.CreateSurface(v["name"], tuple(map(tuple, np.asarray(pts).tolist())), (), _colour(v))


_SURFACE = Seq(
    Name("name", "surface", new=True),
    Keys(
        {
            "rectangle": Seq(
                Set("shape", "rectangle"),
                Number("w", "length", what="width (m)"),
                Number("h", "length", what="height (m)"),
                Options({"centered": Set("centered", True), **_COLOUR}),
            ),
            "polygon": Seq(
                Set("shape", "polygon"),
                Number("n", integer=True, what="number of sides"),
                Number("r", "length", what="radius (m)"),
                Options(_COLOUR),
            ),
            "circle": Seq(
                Set("shape", "circle"),
                Set("n", 32),
                Number("r", "length", what="radius (m)"),
                Options({"segments": Number("n", integer=True, what="segments"), **_COLOUR}),
            ),
            "points": Seq(Set("shape", "points"), Holes(), Options(_COLOUR)),
        }
    ),
    Leaf(
        _surface,
        "create surface NAME rectangle W H [centered] | polygon N R | circle R [segments N]"
        " | points X Y X Y ... [hole X Y ...]... ; [colour R G B]",
        "create a planar surface (m); holes are cut from the main contour",
        "create surface square1 rectangle 1 1",
    ),
)


def _entity(level: str) -> Node:
    return Seq(
        Name("name", level, new=True),
        Options({**_COLOUR, "movable": Set("movable", True)}),
        Leaf(
            lambda v: cmd.CreateEntity(level, v["name"], _colour(v), v.get("movable", False)),
            f"create {level} NAME [colour R G B [A]] [movable]",
            f"create an empty {level}; attach its parts with 'attach'",
            f"create {level} my_{level}",
        ),
    )


def _solid(kind: str, params: list[Node], options: dict[str, Node], build: Any, doc: str) -> Node:
    syntax, summary, example = doc.split(" | ")
    return Seq(
        Name("name", "block", new=True),
        *params,
        Options({**options, **_COLOUR}),
        Leaf(build, syntax, summary, example),
    )


_R = Number("radius", "length", what="radius (m)")
_H = Number("height", "length", what="height (m)")
_CREATE = Keys(
    {
        "surface": _SURFACE,
        "block": _entity("block"),
        "object": _entity("object"),
        "scene": _entity("scene"),
        "cube": _solid(
            "cube",
            [],
            {"size": Number("size", "length", what="edge (m)")},
            lambda v: sol.CreateCube(v["name"], v.get("size", 1.0), _colour(v)),
            "create cube NAME [size S] [colour R G B] | a cube of edge S (m, default 1), "
            "one square placed six times | create cube c1 size 0.04",
        ),
        "box": _solid(
            "box",
            [Keys({"size": Vector("size", 3, "length", what="x y z (m)")})],
            {},
            lambda v: sol.CreateBox(v["name"], v["size"], _colour(v)),
            "create box NAME size X Y Z [colour R G B] | a box, a corner at the origin "
            "| create box table size 0.6 0.6 0.4",
        ),
        "cylinder": _solid(
            "cylinder",
            [Keys({"radius": _R}), Keys({"height": _H})],
            {"facets": Number("n", integer=True, what="facets")},
            lambda v: sol.CreateCylinder(
                v["name"], v["radius"], v["height"], v.get("n", 32), _colour(v)
            ),
            "create cylinder NAME radius R height H [facets N] [colour R G B] "
            "| a cylinder about z from z = 0 | create cylinder shaft radius 0.02 height 0.3",
        ),
        "sphere": _solid(
            "sphere",
            [Keys({"radius": _R})],
            {
                "slices": Number("m", integer=True, what="slices"),
                "faces": Number("n", integer=True, what="faces per half slice"),
            },
            lambda v: sol.CreateSphere(
                v["name"], v["radius"], v.get("m", 16), v.get("n", 8), _colour(v)
            ),
            "create sphere NAME radius R [slices M] [faces N] [colour R G B] "
            "| a sphere at the origin | create sphere ball radius 0.03",
        ),
        "cone": _solid(
            "cone",
            [Keys({"radius": _R}), Keys({"height": _H})],
            {"facets": Number("n", integer=True, what="facets")},
            lambda v: sol.CreateCone(
                v["name"], v["radius"], v["height"], v.get("n", 32), _colour(v)
            ),
            "create cone NAME radius R height H [facets N] [colour R G B] "
            "| a cone about z, base at z = 0 | create cone tip radius 0.5 height 1",
        ),
        "torus": _solid(
            "torus",
            [
                Keys({"major": Number("R", "length", what="major radius (m)")}),
                Keys({"minor": Number("r", "length", what="minor radius (m)")}),
            ],
            {
                "slices": Number("m", integer=True, what="steps about z"),
                "faces": Number("n", integer=True, what="sides of the section"),
            },
            lambda v: sol.CreateTorus(
                v["name"], v["R"], v["r"], v.get("m", 32), v.get("n", 16), _colour(v)
            ),
            "create torus NAME major R minor R [slices M] [faces N] [colour R G B] "
            "| a torus about z | create torus ring major 1 minor 0.25",
        ),
        "extrusion": _solid(
            "extrusion",
            [Name("surface", "surface"), Keys({"height": _H})],
            {},
            lambda v: sol.CreateExtrusion(v["name"], v["surface"], v["height"], _colour(v)),
            "create extrusion NAME SURFACE height H [colour R G B] "
            "| sweep a surface along +z | create extrusion plate square1 height 0.01",
        ),
    }
)


def _modify_entity() -> Node:
    yes_no = Choice("movable", {"yes": True, "no": False, "true": True, "false": False})
    return Seq(
        Ref("ref"),
        Keys(
            {
                "name": Seq(
                    Name("new", new=True),
                    Leaf(
                        lambda v: cmd.Rename(v["ref"], v["new"]),
                        "modify [LEVEL] NAME name NEW",
                        "rename an entity",
                        "modify cube1 name cube2",
                    ),
                ),
                "colour": Seq(
                    Keys({"none": Set("colour", None)}, other=_COLOUR["colour"]),
                    Leaf(
                        lambda v: cmd.SetColour(v["ref"], v["colour"]),
                        "modify [LEVEL] NAME colour R G B [A] | none",
                        "set or clear an entity's colour (components in [0, 1])",
                        "modify cube1 colour 0.8 0.3 0.2",
                    ),
                ),
                "movable": Seq(
                    yes_no,
                    Leaf(
                        lambda v: cmd.SetMovable(v["ref"], v["movable"]),
                        "modify [LEVEL] NAME movable yes|no",
                        "flag an entity as a movable part (robots may grasp it)",
                        "modify cube1 movable yes",
                    ),
                ),
            }
        ),
    )


_MODIFY = Keys(
    {
        "relation": Seq(
            Ref("owner", "owner"),
            Name("relation", "relation:owner", what="relation"),
            Keys(
                {
                    "name": Seq(
                        Name("new", new=True),
                        Leaf(
                            lambda v: cmd.RenameRelation(v["owner"], v["relation"], v["new"]),
                            "modify relation OWNER RELATION name NEW",
                            "rename a relation",
                            "modify relation cube1 ts1 name bottom",
                        ),
                    ),
                    "transform": Seq(
                        Options(TRANSFORM_OPTIONS),
                        Leaf(
                            lambda v: cmd.SetTransform(
                                v["owner"], v["relation"], transform_of(v) or _identity()
                            ),
                            f"modify relation OWNER RELATION transform {TRANSFORM_SYNTAX}",
                            "replace a relation's transform",
                            "modify relation cube1 ts2 transform rotate 90 0 0 translate 0 1 0",
                        ),
                    ),
                }
            ),
        )
    },
    other=_modify_entity(),
)


def _identity() -> Matrix:
    return tuple(tuple(float(i == j) for j in range(4)) for i in range(4))


def _ref_leaf(build: Any, syntax: str, summary: str, example: str, **options: Node) -> Node:
    return Seq(Ref("ref"), Options(options), Leaf(build, syntax, summary, example))


BRANCHES: dict[str, Node] = {
    "create": _CREATE,
    "remove": _ref_leaf(
        lambda v: cmd.Remove(v["ref"], v.get("recursive", False)),
        "remove [LEVEL] NAME [recursive]",
        "remove an entity (refused while pointed to); recursive: also what only it used",
        "remove cube2",
        recursive=Set("recursive", True),
    ),
    "modify": _MODIFY,
    "copy": Seq(
        Ref("ref"),
        Keys({"to": Name("new", new=True, what="new name")}),
        Options(TRANSFORM_OPTIONS),
        Leaf(
            lambda v: cmd.Copy(v["ref"], v["new"], transform_of(v)),
            f"copy [LEVEL] NAME to NEW {TRANSFORM_SYNTAX}",
            "copy an entity, applying a transform to its relations (instancing)",
            "copy cube1 to para scale 2 3 1.5",
        ),
    ),
    "show": Keys(
        {"detail": Seq(Set("detail", True), Leaf(lambda v: cmd.Show(None, True), "", "", ""))},
        other=Seq(
            Ref("ref"),
            Options({"detail": Set("detail", True)}),
            Leaf(
                lambda v: cmd.Show(v["ref"], v.get("detail", False)),
                "show [[LEVEL] NAME] [detail]",
                "show the model or one entity (detail: its relations)",
                "show cube1 detail",
            ),
        ),
        empty=Leaf(lambda v: cmd.Show(None, False), "", "", ""),
    ),
    "list": Keys(
        {lv: Leaf(lambda v, lv=lv: cmd.ListEntities(lv), "", "", "") for lv in LEVEL_WORDS},
        empty=Leaf(lambda v: cmd.ListEntities(None), "list [LEVEL]", "entity names", "list block"),
    ),
    "attach": Seq(
        Ref("target"),
        Keys({"to": Ref("owner", "owner")}),
        Options({"as": Name("relation", new=True, what="relation name"), **TRANSFORM_OPTIONS}),
        Leaf(
            lambda v: cmd.Attach(v["owner"], v["target"], transform_of(v), v.get("relation")),
            f"attach [LEVEL] TARGET to [LEVEL] OWNER [as RELATION] {TRANSFORM_SYNTAX}",
            "attach TARGET to OWNER through a transform (a block's surfaces, an object's "
            "blocks, a scene's objects)",
            "attach square1 to cube1 rotate 90 0 0 translate 0 1 0",
        ),
    ),
    "detach": Seq(
        Ref("owner", "owner"),
        Name("relation", "relation:owner", what="relation"),
        Leaf(
            lambda v: cmd.Detach(v["owner"], v["relation"]),
            "detach [LEVEL] OWNER RELATION",
            "remove one relation of OWNER",
            "detach cube1 ts6",
        ),
    ),
    "save": Seq(
        Text("path"),
        Leaf(
            lambda v: cmd.SaveModel(v["path"]), "save FILE", "save the model (JSON)", "save m.json"
        ),
    ),
    "load": Seq(
        Text("path"),
        Leaf(lambda v: cmd.LoadModel(v["path"]), "load FILE", "load a saved model", "load m.json"),
    ),
    "mesh": _ref_leaf(
        lambda v: cmd.WorldMesh(v["ref"], v.get("path")),
        "mesh [LEVEL] NAME [export FILE.stl|.obj|.ply]",
        "the entity's world mesh: counts, bounds, volume; export writes it",
        "mesh cube1",
        export=Text("path"),
    ),
    "properties": _ref_leaf(
        lambda v: cmd.Properties(v["ref"]),
        "properties [LEVEL] NAME",
        "area (m^2), volume (m^3), centroid (m), inertia (m^5, unit density)",
        "properties cube1",
    ),
}
