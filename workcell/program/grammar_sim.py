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
from workcell.sim.profiles import PROFILES

__all__ = ["ALIASES", "BRANCHES"]


class PointOrPart(Node):
    """After ``at`` (``via``, ``to``): three numbers (a position, m) or a part name (its
    centroid), stored under ``prefix`` + position / part / anchor."""

    def __init__(self, prefix: str = "") -> None:
        self.prefix = prefix

    def expects(self, cur: Cursor) -> list[str]:
        return ["<x y z (m)>", *(cur.names("part") or ["<part>"])]

    def match(self, cur: Cursor) -> None:
        tok = cur.peek()
        if tok is None and cur.completing:
            cur.fail("", self.expects(cur))
        if tok is not None and tok.kind == "number":
            Vector(self.prefix + "position", 3, "length", what="x y z (m)").match(cur)
        else:
            Name(self.prefix + "part", "part").match(cur)
            cur.values[self.prefix + "anchor"] = "centroid"


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
_APPROACH = {"approach": Number("approach", "length", what="approach (m)")}
_JOINTS = Vector("q", None, "joints", robot_key="robot", what="joint values (deg)")
_ZONE = {"zone": Number("zone", "length", what="zone (m)")}
_TOOL = {
    "speed": Number("speed", "tool_speed", what="tool speed (m/s)"),
    "acceleration": Number("acceleration", "tool_acceleration", what="tool acceleration (m/s^2)"),
    **_ZONE,
}
TOOL_SYNTAX = "speed V [acceleration A] [zone Z]"


def _tool_move(build: Any, v: dict[str, Any], what: str) -> Any:
    if "speed" not in v:
        raise ProgramError(f"{what}: give the tool speed, e.g. 'speed 250 mm/s'")
    return build(v["speed"], v.get("acceleration"), v.get("zone", 0.0))


def _circular(v: dict[str, Any]) -> simc.MoveCircular:
    via = Target(position=v.get("via_position"), part=v.get("via_part"))
    return _tool_move(
        lambda sp, ac, z: simc.MoveCircular(v["robot"], via, _target(v), sp, ac, z),
        v,
        "move circular",
    )


class JointsOrPose(Node):
    """After ``move joints absolute ROBOT``: joint values (deg; m for a prismatic joint)
    or the name of one of the robot's poses (``home``)."""

    pose = Name("q", "pose:robot", what="pose name")

    def expects(self, cur: Cursor) -> list[str]:
        return [*_JOINTS.expects(cur), *self.pose.expects(cur)]

    def match(self, cur: Cursor) -> None:
        tok = cur.peek()
        if tok is None and cur.completing:
            cur.fail("", self.expects(cur))
        if tok is not None and tok.kind == "word":
            self.pose.match(cur)
        else:
            _JOINTS.match(cur)


def _leaf(build: Any, syntax: str, summary: str, example: str) -> Leaf:
    return Leaf(build, syntax, summary, example)


def _robot_leaf(build: Any, syntax: str, summary: str, example: str, *more: Node) -> Node:
    return Seq(_ROBOT, *more, Leaf(build, syntax, summary, example))


_MOVE = Keys(
    {
        "joints": Keys(
            {
                "absolute": _robot_leaf(
                    lambda v: simc.MoveJointsAbsolute(
                        v["robot"], v["q"], v.get("plan", False), v.get("zone", 0.0)
                    ),
                    "move joints absolute ROBOT J1 .. Jn [deg|rad] | POSE [plan] [zone Z]",
                    "move the joints to these values (deg, or m for a prismatic joint), or "
                    "to a named pose of the robot (home); plan: along a collision-free path; "
                    "zone: blend into the next move within Z (m) of the end",
                    "move joints absolute puma -60 0 -70 0 90 30 plan",
                    JointsOrPose(),
                    Options({"plan": Set("plan", True), **_ZONE}),
                ),
                "relative": _robot_leaf(
                    lambda v: simc.MoveJointsRelative(v["robot"], v["q"], v.get("zone", 0.0)),
                    "move joints relative ROBOT D1 .. Dn [deg|rad] [zone Z]",
                    "move the joints by these amounts (deg, or m for a prismatic joint); "
                    "zone: blend into the next move",
                    "move joints relative puma -70 -10 10 30 -20 -10",
                    _JOINTS,
                    Options(_ZONE),
                ),
            }
        ),
        "end_effector": _robot_leaf(
            lambda v: simc.MoveEndEffector(
                v["robot"], _target(v), v.get("config"), v.get("plan", False), v.get("zone", 0.0)
            ),
            f"move end_effector ROBOT {POSE_SYNTAX} [config CFG] [plan] [zone Z]",
            "move the tool to a pose (inverse kinematics, then a joint move); "
            "config: Puma solution letters l|r u|d n|f; plan: along a collision-free path; "
            "zone: blend into the next move",
            "move end_effector puma at 0.4 0 0.3 down",
            Options(
                {
                    **_POSE,
                    "config": Name("config", what="configuration, e.g. lun"),
                    "plan": Set("plan", True),
                    **_ZONE,
                }
            ),
        ),
        "linear": _robot_leaf(
            lambda v: _tool_move(
                lambda sp, ac, z: simc.MoveLinear(v["robot"], _target(v), sp, ac, z),
                v,
                "move linear",
            ),
            f"move linear ROBOT {POSE_SYNTAX} {TOOL_SYNTAX}",
            "move the tool point along a straight line at speed V (m/s; mm/s) and "
            "acceleration A (m/s^2, default 1.2), slower only where the joints must; "
            "zone: blend into the next move within Z (m)",
            "move linear puma offset 0 0.1 0 speed 250 mm/s zone 10 mm",
            Options({**_POSE, **_TOOL}),
        ),
        "circular": _robot_leaf(
            _circular,
            "move circular ROBOT via X Y Z|PART [to X Y Z|PART | on PART] [offset DX DY DZ] "
            f"[rpy RX RY RZ | down] {TOOL_SYNTAX}",
            "move the tool point along the arc through its position, the via point and "
            "the end point, at speed V; orientation interpolated to the end pose's",
            "move circular puma via 0.3 0.05 0.5 to 0.25 0.1 0.5 speed 200 mm/s",
            Keys({"via": PointOrPart("via_")}),
            Options(
                {
                    "to": PointOrPart(),
                    **{k: _POSE[k] for k in ("on", "offset", "rpy", "down")},
                    **_TOOL,
                }
            ),
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
                "cell example joints|pick-place|handoff|obstacle",
                "load an example cell: the thesis's three (ch. 5), or a wall between two stages",
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
    "start simulating the cell (default path, dt 0.01 s); in joint-by-joint mode the joints "
    "move one after another, a frame every dt, while the simulated time is the thesis's "
    "clock (each move lasts its largest joint motion / speed, as in path mode): 'summary' "
    "shows both",
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
    "override": _robot_leaf(
        lambda v: simc.SetOverride(v["robot"], v["override"]),
        "override ROBOT P [%]",
        "the robot's speed override: P % of its speeds, (P %)^2 of its accelerations: "
        "the same paths in 100/P the time",
        "override puma 50 %",
        Number("override", "fraction", what="override (%)"),
    ),
    "profile": Seq(
        Choice("profile", {p: p for p in PROFILES}),
        Options({"acceleration": Number("acceleration", "angular_acceleration", what="rad/s^2")}),
        _leaf(
            lambda v: simc.SetProfile(v["profile"], v.get("acceleration")),
            "profile linear|trapezoid|quintic|jerk [acceleration A]",
            "joint moves at the robot's speed (the thesis's linear; trapezoid with "
            "acceleration A, deg/s^2; quintic) or within every joint's own limits (jerk)",
            "profile jerk",
        ),
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
                lambda v: simc.OpenGripper(v["robot"], v.get("settle", False)),
                "open gripper ROBOT [settle]",
                "release the part; settle: a part in mid-air drops onto what is below it",
                "open gripper puma",
                Options({"settle": Set("settle", True)}),
            )
        }
    ),
    "planning": Seq(
        Options(
            {
                "clearance": Number("clearance", "length", what="clearance (m)"),
                "time": Number("time_limit", "time", what="time limit (s)"),
                "seed": Number("seed", integer=True, what="seed"),
                "near": Number("near_clearance", "length", what="near clearance (m)"),
            }
        ),
        _leaf(
            lambda v: simc.SetPlanning(
                v.get("clearance"), v.get("time_limit"), v.get("seed"), v.get("near_clearance")
            ),
            "planning [clearance L] [time T] [seed N] [near L]",
            "how planned moves search: clearance L (m, 0.005), time limit T (s, 5) per "
            "search, random seed N (0), near clearance L (m, 0.001) of task-level close work; "
            "shows the settings",
            "planning clearance 5mm time 5 seed 0",
        ),
    ),
    "pick": Seq(
        Name("part", "movable", what="movable part"),
        Keys(
            {
                "with": Seq(
                    _ROBOT,
                    Options(_APPROACH),
                    _leaf(
                        lambda v: simc.Pick(v["robot"], v["part"], v.get("approach", 0.08)),
                        "pick PART with ROBOT [approach L]",
                        "grasp a part: grasp pose, configuration and a collision-free path "
                        "chosen automatically; approach and retreat L (m, 0.08) along the "
                        "tool axis",
                        "pick cube with puma",
                    ),
                )
            }
        ),
    ),
    "place": Seq(
        Name("part", "movable", what="movable part"),
        Keys(
            {
                "on": Seq(
                    Name("on", "part", what="support (a part)"),
                    Keys(
                        {
                            "with": Seq(
                                _ROBOT,
                                Options(
                                    {
                                        "at": Vector("position", 2, "length", what="x y (m)"),
                                        **_APPROACH,
                                    }
                                ),
                                _leaf(
                                    lambda v: simc.Place(
                                        v["robot"],
                                        v["part"],
                                        v["on"],
                                        v.get("position"),
                                        v.get("approach", 0.08),
                                    ),
                                    "place PART on SUPPORT with ROBOT [at X Y] [approach L]",
                                    "put a held part down resting on a support, its centroid "
                                    "over X Y (m; default the centre of the support's top), "
                                    "release it, retreat",
                                    "place cube on stage_1 with puma",
                                ),
                            )
                        }
                    ),
                )
            }
        ),
    ),
    "handover": Seq(
        Name("part", "movable", what="movable part"),
        Keys(
            {
                "from": Seq(
                    Name("giver", "robot", what="robot holding it"),
                    Keys(
                        {
                            "to": Seq(
                                Name("receiver", "robot", what="robot taking it"),
                                Options(_APPROACH),
                                _leaf(
                                    lambda v: simc.Handover(
                                        v["giver"],
                                        v["receiver"],
                                        v["part"],
                                        v.get("approach", 0.08),
                                    ),
                                    "handover PART from GIVER to RECEIVER [approach L]",
                                    "hand a part over at a meeting pose found in both workspaces",
                                    "handover sphere from puma_1 to puma_2",
                                ),
                            )
                        }
                    ),
                )
            }
        ),
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
    "time": Keys(
        {
            "detail": _leaf(
                lambda v: simc.CycleTime(),
                "time detail",
                "the cycle-time report: each command's start, duration and the limit that set it",
                "time detail",
            )
        },
        empty=_query(lambda v: simc.SimTime(), "time", "the simulated clock (s)"),
    ),
    "frames": _query(lambda v: simc.Frames(), "frames", "frames on the timeline"),
    "events": _query(lambda v: simc.Events(), "events", "the timeline's events"),
    "robots": _query(lambda v: simc.Robots(), "robots", "the robots being simulated"),
    "summary": _query(
        lambda v: simc.Summary(), "summary", "simulated and wall time, frames, events"
    ),
    "positions": _query(
        lambda v: simc.PartPositions(), "positions", "movable parts' centroids (m)"
    ),
}

# the Simulator's method names, accepted as keywords too (not offered in completion)
ALIASES: dict[str, Node] = {
    "move_joints_absolute": _MOVE.branches["joints"].branches["absolute"],  # type: ignore[attr-defined]
    "move_joints_relative": _MOVE.branches["joints"].branches["relative"],  # type: ignore[attr-defined]
    "move_end_effector": _MOVE.branches["end_effector"],
    "move_straight_line": _MOVE.branches["straight"],
    "move_linear": _MOVE.branches["linear"],
    "move_circular": _MOVE.branches["circular"],
    "set_override": BRANCHES["override"],
    "set_profile": BRANCHES["profile"],
    "cycle_time": BRANCHES["time"].branches["detail"],  # type: ignore[attr-defined]
    "close_gripper": BRANCHES["close"].branches["gripper"],  # type: ignore[attr-defined]
    "open_gripper": BRANCHES["open"].branches["gripper"],  # type: ignore[attr-defined]
    "set_speed": BRANCHES["speed"],
    "set_mode": BRANCHES["mode"],
    "set_planning": BRANCHES["planning"],
    "tool_pose": BRANCHES["pose"],
    "sim_time": BRANCHES["time"].empty,  # type: ignore[attr-defined]
}
