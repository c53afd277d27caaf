"""The command language, cell part: ``cell new|load|save|example|show|remove`` and ``add
robot|static|movable|camera`` (thesis §4.4); :mod:`workcell.program.grammar_sim` puts
them in the tree. Lengths m, angles deg, densities kg/m^3.
"""

from __future__ import annotations

import math
from typing import Any

from workcell.errors import ProgramError
from workcell.program import cellcommands as cellc
from workcell.program.grammar_model import (
    _COLOUR,
    TRANSFORM_OPTIONS,
    TRANSFORM_SYNTAX,
    transform_of,
)
from workcell.program.keytree import Keys, Leaf, Options, Seq, Set
from workcell.program.params import Choice, Name, Number, Ref, Text, Vector
from workcell.robots.library import library

__all__ = ["ADD", "CELL"]

CELL = Keys(
    {
        "new": Seq(
            Name("name", new=True, what="cell name"),
            Leaf(
                lambda v: cellc.NewCell(v["name"]), "cell new NAME", "start a cell", "cell new c1"
            ),
        ),
        "load": Seq(
            Text("path"),
            Leaf(
                lambda v: cellc.LoadCell(v["path"]),
                "cell load FILE",
                "load a cell",
                "cell load c.json",
            ),
        ),
        "save": Seq(
            Text("path"),
            Leaf(
                lambda v: cellc.SaveCell(v["path"]),
                "cell save FILE",
                "save the cell",
                "cell save c.json",
            ),
        ),
        "example": Seq(
            Choice("name", {k: k for k in cellc.EXAMPLES}),
            Leaf(
                lambda v: cellc.ExampleCell(v["name"]),
                "cell example joints|pick-place|handoff|obstacle|conveyor",
                "load an example cell: the thesis's three (ch. 5), a wall between two stages, or "
                "a belt with a light beam and a UR5e (its programs: workcell.examples.conveyor)",
                "cell example joints",
            ),
        ),
        "show": Leaf(
            lambda v: cellc.ShowCell(), "cell show", "robots, parts and cameras", "cell show"
        ),
        "remove": Seq(
            Name("name", "cellitem", what="part, robot or camera"),
            Leaf(
                lambda v: cellc.RemoveFromCell(v["name"]),
                "cell remove NAME",
                "remove a part, robot or camera from the cell",
                "cell remove table_1",
            ),
        ),
    }
)

_FILE_ROBOT_OPTIONS = ("base_link", "tip_link", "base_body", "tip_body", "tool_site")


def _add_robot(v: dict[str, Any]) -> cellc.AddRobot | cellc.ImportRobot:
    files = [k for k in ("urdf", "mjcf") if k in v]
    extra = [k for k in (*_FILE_ROBOT_OPTIONS, "search") if k in v]
    if len(files) > 1 or (files and "model" in v):
        raise ProgramError("give one of a library MODEL, urdf FILE or mjcf FILE")
    if not files:
        if extra:
            raise ProgramError(f"{', '.join(extra)}: only for a robot read from urdf or mjcf FILE")
        return cellc.AddRobot(
            v["name"],
            v.get("model", "puma260"),
            v.get("gripper", False),
            transform_of(v),
            v.get("q"),
        )
    kind = files[0]
    return cellc.ImportRobot(
        v["name"],
        kind,
        v[kind],
        **{k: v[k] for k in _FILE_ROBOT_OPTIONS if k in v},
        search=(v["search"],) if "search" in v else (),
        gripper=v.get("gripper", False),
        base=transform_of(v),
        # parsed as angles (rad); the robot file says which joints are prismatic (m)
        q=tuple(math.degrees(x) for x in v["q"]) if "q" in v else None,
        q_degrees=True,
    )


ADD = Keys(
    {
        "robot": Seq(
            Name("name", new=True, what="robot name"),
            Options(
                {
                    **{name: Set("model", name) for name in library()},
                    "urdf": Text("urdf", "URDF file"),
                    "mjcf": Text("mjcf", "MJCF file"),
                    **{k: Name(k, what=k.replace("_", " ")) for k in _FILE_ROBOT_OPTIONS},
                    "search": Text("search", "folder"),
                    "gripper": Set("gripper", True),
                    "q": Vector("q", None, "angle", what="initial joint values (deg)"),
                    **TRANSFORM_OPTIONS,
                }
            ),
            Leaf(
                _add_robot,
                "add robot NAME [MODEL | urdf FILE | mjcf FILE] [base_link L] [tip_link L] "
                "[base_body B] [tip_body B] [tool_site S] [search DIR] [gripper] [q J1 .. Jn] "
                f"{TRANSFORM_SYNTAX}",
                "place a library robot (MODEL: puma260 (default), ur5e, kuka_kr6_r700, ... "
                "see 'workcell robots') or one read from a URDF or MJCF file (the chain from "
                "base_link/base_body to tip_link/tip_body/tool_site; search: a folder for "
                "package:// meshes); base pose by the transform; q in deg",
                "add robot puma puma260 q 0 0 -90 0 90 0",
            ),
        ),
        "static": Seq(
            Name("name", new=True, what="part name"),
            Ref("entity", "entity"),
            Options({**TRANSFORM_OPTIONS, **_COLOUR}),
            Leaf(
                lambda v: cellc.AddStatic(v["name"], v["entity"], transform_of(v), v.get("colour")),
                f"add static NAME [LEVEL] ENTITY {TRANSFORM_SYNTAX} [colour R G B]",
                "place a fixed part (a block or object of the model)",
                "add static table_1 table translate -0.3 -0.3 0",
            ),
        ),
        "movable": Seq(
            Name("name", new=True, what="part name"),
            Ref("entity", "entity"),
            Keys({"density": Number("density", what="density (kg/m^3)")}),
            Options({**TRANSFORM_OPTIONS, **_COLOUR}),
            Leaf(
                lambda v: cellc.AddMovable(
                    v["name"], v["entity"], v["density"], transform_of(v), v.get("colour")
                ),
                f"add movable NAME [LEVEL] ENTITY density D {TRANSFORM_SYNTAX} [colour R G B]",
                "place a movable part of density D (kg/m^3) that robots may grasp",
                "add movable part cube density 2700 translate 0.3 0 0.4",
            ),
        ),
        "camera": Seq(
            Name("name", new=True, what="camera name"),
            Keys({"at": Vector("position", 3, "length", what="x y z (m)")}),
            Keys({"looking": Vector("target", 3, "length", what="x y z (m)")}),
            Options({"fovy": Number("fovy", "angle", what="field of view (deg)")}),
            Leaf(
                lambda v: cellc.AddCamera(
                    v["name"], v["position"], v["target"], _deg(v.get("fovy"), 45.0)
                ),
                "add camera NAME at X Y Z looking X Y Z [fovy A]",
                "place a camera looking at a point",
                "add camera front at 1.5 0 1 looking 0 0 0.5",
            ),
        ),
    }
)


def _deg(rad: float | None, default: float) -> float:
    return default if rad is None else rad * 180.0 / 3.141592653589793
