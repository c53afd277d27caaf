"""The command language, cell and simulation part (thesis §4.4-4.6).

Each entry of :data:`BRANCHES` is a top-level keyword and its key tree; every leaf
builds a command of :mod:`workcell.program.cellcommands` or
:mod:`workcell.program.simcommands`. Joint values are degrees (metres for prismatic
joints) unless a unit says otherwise; speeds deg/s; times s; lengths m.

A tool pose (``move end_effector``, ``move straight``) is written with options:
``at X Y Z`` (m) or ``at PART`` (the part's centroid, the thesis's grasp point) or
``on PART`` (the centre of the top of its bounding box); ``offset DX DY DZ`` (m, world
axes); ``rpy RX RY RZ`` (deg, fixed axes x, y, z: R = Rz Ry Rx) or ``down`` (tool z
pointing down: rpy 180 0 0); or ``matrix`` and 16 numbers. Without a position or an
orientation, the tool keeps its current one.
"""

from __future__ import annotations

from typing import Any

from workcell import spatial
from workcell.errors import ProgramError
from workcell.program import cellcommands as cellc
from workcell.program import simcommands as simc
from workcell.program.grammar_model import (
    _COLOUR,
    TRANSFORM_OPTIONS,
    TRANSFORM_SYNTAX,
    transform_of,
)
from workcell.program.keytree import Cursor, Keys, Leaf, Node, Options, Seq, Set
from workcell.program.params import Choice, Name, Number, Ref, Text, Vector
from workcell.program.targets import Target
from workcell.robots.library import library

__all__ = ["ALIASES", "BRANCHES"]


class PointOrPart(Node):
    """After ``at``: three numbers (a position, m) or a part name (its centroid)."""

    def expects(self, cur: Cursor) -> list[str]:
        return ["<x y z (m)>", *(cur.names("part") or ["<part>"])]

    def match(self, cur: Cursor) -> None:
        tok = cur.peek()
        if tok is None and cur.completing:
            cur.fail("", self.expects(cur))
        if tok is not None and tok.kind == "number":
            Vector("position", 3, "length", what="x y z (m)").match(cur)
        else:
            Name("part", "part").match(cur)
            cur.values["anchor"] = "centroid"


_POSE: dict[str, Node] = {
    "at": PointOrPart(),
    "on": Seq(Name("on", "part"), Set("anchor", "top")),
    "offset": Vector("offset", 3, "length", what="dx dy dz (m)"),
    "rpy": Vector("rpy", 3, "angle", what="rx ry rz (deg)"),
    "down": Set("down", True),
    "matrix": Vector("matrix", 16, None, what="16 numbers, row by row"),
}
POSE_SYNTAX = (
    "[at X Y Z | at PART | on PART] [offset DX DY DZ] [rpy RX RY RZ | down] | matrix M11 .. M44"
)


def _target(v: dict[str, Any]) -> Target:
    if "on" in v:
        if "part" in v or "position" in v:
            raise ProgramError("give the position with 'at' or with 'on', not both")
        v = {**v, "part": v["on"]}
    if "matrix" in v:
        if any(k in v for k in ("part", "position", "rpy", "down", "offset")):
            raise ProgramError("give a pose as matrix, or with at/on/offset/rpy, not both")
        return Target(matrix=transform_of({"matrix": v["matrix"]}))
    if "rpy" in v and "down" in v:
        raise ProgramError("give the orientation with 'rpy' or 'down', not both")
    rpy = (3.141592653589793, 0.0, 0.0) if v.get("down") else v.get("rpy")
    R = None if rpy is None else tuple(map(tuple, spatial.srt(rotation=rpy)[:3, :3].tolist()))
    return Target(
        position=v.get("position"),
        part=v.get("part"),
        anchor=v.get("anchor", "centroid"),
        offset=v.get("offset", (0.0, 0.0, 0.0)),
        rotation=R,
    )


_ROBOT = Name("robot", "robot")
_JOINTS = Vector("q", None, "joints", robot_key="robot", what="joint values (deg)")


def _leaf(build: Any, syntax: str, summary: str, example: str) -> Leaf:
    return Leaf(build, syntax, summary, example)


def _robot_leaf(build: Any, syntax: str, summary: str, example: str, *more: Node) -> Node:
    return Seq(_ROBOT, *more, Leaf(build, syntax, summary, example))


_MOVE = Keys(
    {
        "joints": Keys(
            {
                "absolute": _robot_leaf(
                    lambda v: simc.MoveJointsAbsolute(v["robot"], v["q"]),
                    "move joints absolute ROBOT J1 .. Jn [deg|rad]",
                    "move the joints to these values (deg, or m for a prismatic joint)",
                    "move joints absolute puma -60 0 -70 0 90 30",
                    _JOINTS,
                ),
                "relative": _robot_leaf(
                    lambda v: simc.MoveJointsRelative(v["robot"], v["q"]),
                    "move joints relative ROBOT D1 .. Dn [deg|rad]",
                    "move the joints by these amounts (deg, or m for a prismatic joint)",
                    "move joints relative puma -70 -10 10 30 -20 -10",
                    _JOINTS,
                ),
            }
        ),
        "end_effector": _robot_leaf(
            lambda v: simc.MoveEndEffector(v["robot"], _target(v), v.get("config")),
            f"move end_effector ROBOT {POSE_SYNTAX} [config CFG]",
            "move the tool to a pose (inverse kinematics, then linear in joints); "
            "config: Puma solution letters l|r u|d n|f",
            "move end_effector puma at 0.4 0 0.3 down",
            Options({**_POSE, "config": Name("config", what="configuration, e.g. lun")}),
        ),
        "straight": _robot_leaf(
            lambda v: simc.MoveStraightLine(v["robot"], _target(v), v.get("step", 0.005)),
            f"move straight ROBOT {POSE_SYNTAX} [step L]",
            "move the tool along a straight line, orientation held; samples L (m) apart",
            "move straight puma offset 0 0 -0.05 step 0.005",
            Options({**_POSE, "step": Number("step", "length", what="step (m)")}),
        ),
    }
)

_GRIPPER_OPTIONS = {
    "distance": Number("max_distance", "length", what="max distance (m)"),
    "angle": Number("max_angle", "angle", what="max angle (deg)"),
}

_CELL = Keys(
    {
        "new": Seq(
            Name("name", new=True, what="cell name"),
            _leaf(
                lambda v: cellc.NewCell(v["name"]), "cell new NAME", "start a cell", "cell new c1"
            ),
        ),
        "load": Seq(
            Text("path"),
            _leaf(
                lambda v: cellc.LoadCell(v["path"]),
                "cell load FILE",
                "load a cell",
                "cell load c.json",
            ),
        ),
        "save": Seq(
            Text("path"),
            _leaf(
                lambda v: cellc.SaveCell(v["path"]),
                "cell save FILE",
                "save the cell",
                "cell save c.json",
            ),
        ),
        "example": Seq(
            Choice("name", {k: k for k in cellc.EXAMPLES}),
            _leaf(
                lambda v: cellc.ExampleCell(v["name"]),
                "cell example joints|pick-place|handoff",
                "load one of the thesis's example cells (ch. 5)",
                "cell example joints",
            ),
        ),
        "show": _leaf(
            lambda v: cellc.ShowCell(), "cell show", "robots, parts and cameras", "cell show"
        ),
        "remove": Seq(
            Name("name", "cellitem", what="part, robot or camera"),
            _leaf(
                lambda v: cellc.RemoveFromCell(v["name"]),
                "cell remove NAME",
                "remove a part, robot or camera from the cell",
                "cell remove table_1",
            ),
        ),
    }
)

_ADD = Keys(
    {
        "robot": Seq(
            Name("name", new=True, what="robot name"),
            Options(
                {
                    **{name: Set("model", name) for name in library()},
                    "gripper": Set("gripper", True),
                    "q": Vector("q", None, "angle", what="initial joint values (deg)"),
                    **TRANSFORM_OPTIONS,
                }
            ),
            _leaf(
                lambda v: cellc.AddRobot(
                    v["name"],
                    v.get("model", "puma260"),
                    v.get("gripper", False),
                    transform_of(v),
                    v.get("q"),
                ),
                f"add robot NAME [MODEL] [gripper] [q J1 .. Jn] {TRANSFORM_SYNTAX}",
                "place a library robot (MODEL: puma260 (default), ur5e, kuka_kr6_r700, ... "
                "see 'workcell robots'; base pose by the transform; q in deg)",
                "add robot puma puma260 q 0 0 -90 0 90 0",
            ),
        ),
        "static": Seq(
            Name("name", new=True, what="part name"),
            Ref("entity", "entity"),
            Options({**TRANSFORM_OPTIONS, **_COLOUR}),
            _leaf(
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
            _leaf(
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
            _leaf(
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


_MODES = {m: m for m in simc.MODES}
_SIMULATE_OPTIONS = Options(
    {"dt": Number("dt", "time", what="dt (s)"), "realtime": Set("realtime", True)}
)


def _simulate(v: dict[str, Any]) -> simc.Simulate:
    return simc.Simulate(v.get("mode", "path"), v.get("dt", 0.01), v.get("realtime", False))


_SIMULATE_LEAF = _leaf(
    _simulate,
    "simulate [path|joint-by-joint|playback] [dt T] [realtime]",
    "start simulating the cell (default path, dt 0.01 s)",
    "simulate path dt 0.01",
)
_SIMULATE = Keys(
    {
        "stop": _leaf(
            lambda v: simc.StopSimulation(), "simulate stop", "end the simulation", "simulate stop"
        ),
        **{m: Seq(Set("mode", m), _SIMULATE_OPTIONS, _SIMULATE_LEAF) for m in simc.MODES},
    },
    other=Seq(_SIMULATE_OPTIONS, _SIMULATE_LEAF),
    empty=_SIMULATE_LEAF,
)


def _query(build: Any, syntax: str, summary: str) -> Leaf:
    return Leaf(build, syntax, summary, syntax)


BRANCHES: dict[str, Node] = {
    "cell": _CELL,
    "add": _ADD,
    "simulate": _SIMULATE,
    "mode": Seq(
        Choice("mode", _MODES),
        _leaf(
            lambda v: simc.SetMode(v["mode"]),
            "mode path|joint-by-joint|playback",
            "switch mode",
            "mode playback",
        ),
    ),
    "speed": _robot_leaf(
        lambda v: simc.SetSpeed(v["robot"], v["speed"]),
        "speed ROBOT S [deg/s|rad/s]",
        "set the robot's speed: the speed of the joint that moves most (deg/s)",
        "speed puma 0.3 rad/s",
        Number("speed", "speed", what="speed (deg/s)"),
    ),
    "move": _MOVE,
    "close": Keys(
        {
            "gripper": _robot_leaf(
                lambda v: simc.CloseGripper(
                    v["robot"], v.get("max_distance", 0.02), v.get("max_angle", 0.17453292519943295)
                ),
                "close gripper ROBOT [distance L] [angle A]",
                "grasp the first movable part within L (m, 0.02) of the tool whose box axis "
                "is within A (deg, 10) of the tool's z axis",
                "close gripper puma distance 0.02 angle 10",
                Options(_GRIPPER_OPTIONS),
            )
        }
    ),
    "open": Keys(
        {
            "gripper": _robot_leaf(
                lambda v: simc.OpenGripper(v["robot"]),
                "open gripper ROBOT",
                "release the part",
                "open gripper puma",
            )
        }
    ),
    "wait": Seq(
        Number("seconds", "time", what="seconds"),
        _leaf(
            lambda v: simc.Wait(v["seconds"]),
            "wait T [s|ms]",
            "let simulated time pass",
            "wait 0.5",
        ),
    ),
    "play": Seq(
        Options({"realtime": Set("realtime", True)}),
        _leaf(
            lambda v: simc.Play(v.get("realtime")),
            "play [realtime]",
            "replay the stored frames",
            "play",
        ),
    ),
    "joints": _robot_leaf(
        lambda v: simc.Joints(v["robot"]), "joints ROBOT", "joint values (deg)", "joints puma"
    ),
    "pose": _robot_leaf(
        lambda v: simc.ToolPose(v["robot"]), "pose ROBOT", "tool pose (m, deg)", "pose puma"
    ),
    "held": _robot_leaf(
        lambda v: simc.Held(v["robot"]), "held ROBOT", "the part held", "held puma"
    ),
    "clearance": Seq(
        Name("a", "cellitem", what="part or robot"),
        Name("b", "cellitem", what="part or robot"),
        _leaf(
            lambda v: simc.Clearance(v["a"], v["b"]),
            "clearance A B",
            "distance (m)",
            "clearance puma table_1",
        ),
    ),
    "time": _query(lambda v: simc.SimTime(), "time", "the simulated clock (s)"),
    "frames": _query(lambda v: simc.Frames(), "frames", "frames on the timeline"),
    "events": _query(lambda v: simc.Events(), "events", "the timeline's events"),
    "robots": _query(lambda v: simc.Robots(), "robots", "the robots being simulated"),
    "summary": _query(
        lambda v: simc.Summary(), "summary", "simulated and wall time, frames, events"
    ),
    "positions": _query(
        lambda v: simc.PartPositions(), "positions", "movable parts' positions (m)"
    ),
}

# the Simulator's method names, accepted as keywords too (not offered in completion)
ALIASES: dict[str, Node] = {
    "move_joints_absolute": _MOVE.branches["joints"].branches["absolute"],  # type: ignore[attr-defined]
    "move_joints_relative": _MOVE.branches["joints"].branches["relative"],  # type: ignore[attr-defined]
    "move_end_effector": _MOVE.branches["end_effector"],
    "move_straight_line": _MOVE.branches["straight"],
    "close_gripper": BRANCHES["close"].branches["gripper"],  # type: ignore[attr-defined]
    "open_gripper": BRANCHES["open"].branches["gripper"],  # type: ignore[attr-defined]
    "set_speed": BRANCHES["speed"],
    "set_mode": BRANCHES["mode"],
    "tool_pose": BRANCHES["pose"],
    "sim_time": BRANCHES["time"],
}
