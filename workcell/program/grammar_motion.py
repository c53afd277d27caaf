"""The command language, motion part: joint and tool moves and a robot's motion settings.

``move joints absolute|relative``, ``move end_effector``, ``move straight``, ``move
linear``, ``move circular`` (each with a blend ``zone``), and ``speed``, ``override``,
``profile``; :mod:`workcell.program.grammar_sim` puts them in the tree. Joint values are
degrees (metres for prismatic joints) unless a unit says otherwise; speeds deg/s; tool
speeds m/s; lengths m.

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
from workcell.program import simcommands as simc
from workcell.program.grammar_model import transform_of
from workcell.program.keytree import Cursor, Keys, Leaf, Node, Options, Seq, Set
from workcell.program.params import Choice, Name, Number, Vector
from workcell.program.targets import Target
from workcell.sim.profiles import PROFILES

__all__ = [
    "JOG",
    "MOVE",
    "OVERRIDE",
    "POSE_SYNTAX",
    "PROFILE",
    "ROBOT",
    "SPEED",
    "TOOL_SYNTAX",
    "JointsOrPose",
    "PointOrPart",
    "robot_leaf",
]


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


ROBOT = Name("robot", "robot")
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


def robot_leaf(build: Any, syntax: str, summary: str, example: str, *more: Node) -> Node:
    """A command that starts with a robot's name, then ``more``, then its leaf."""
    return Seq(ROBOT, *more, Leaf(build, syntax, summary, example))


JOG = robot_leaf(
    lambda v: simc.Jog(v["robot"], v["q"]),
    "jog ROBOT J1 .. Jn [deg|rad]",
    "set the joints at once (deg, or m for a prismatic joint): no simulated time passes, "
    "as with a teach pendant",
    "jog puma 10 0 -90 0 90 0",
    _JOINTS,
)

MOVE = Keys(
    {
        "joints": Keys(
            {
                "absolute": robot_leaf(
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
                "relative": robot_leaf(
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
        "end_effector": robot_leaf(
            lambda v: simc.MoveEndEffector(
                v["robot"], _target(v), v.get("config"), v.get("plan", False), v.get("zone", 0.0)
            ),
            f"move end_effector ROBOT {POSE_SYNTAX} [config CFG] [plan] [zone Z]",
            "move the tool to a pose (inverse kinematics, then a joint move); "
            "config: configuration letters l|r u|d n|f (default: the nearest solution whose "
            "joint move is clear); plan: along a collision-free path; zone: blend into the "
            "next move",
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
        "linear": robot_leaf(
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
        "circular": robot_leaf(
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
        "straight": robot_leaf(
            lambda v: simc.MoveStraightLine(v["robot"], _target(v), v.get("step", 0.005)),
            f"move straight ROBOT {POSE_SYNTAX} [step L]",
            "move the tool along a straight line, orientation held; samples L (m) apart",
            "move straight puma offset 0 0 -0.05 step 0.005",
            Options({**_POSE, "step": Number("step", "length", what="step (m)")}),
        ),
    }
)

SPEED = robot_leaf(
    lambda v: simc.SetSpeed(v["robot"], v["speed"]),
    "speed ROBOT S [deg/s|rad/s]",
    "set the robot's speed: the speed of the joint that moves most (deg/s)",
    "speed puma 0.3 rad/s",
    Number("speed", "speed", what="speed (deg/s)"),
)
OVERRIDE = robot_leaf(
    lambda v: simc.SetOverride(v["robot"], v["override"]),
    "override ROBOT P [%]",
    "the robot's speed override: P % of its speeds, (P %)^2 of its accelerations: "
    "the same paths in 100/P the time",
    "override puma 50 %",
    Number("override", "fraction", what="override (%)"),
)
PROFILE = Seq(
    Choice("profile", {p: p for p in PROFILES}),
    Options({"acceleration": Number("acceleration", "angular_acceleration", what="rad/s^2")}),
    Leaf(
        lambda v: simc.SetProfile(v["profile"], v.get("acceleration")),
        "profile linear|trapezoid|quintic|jerk [acceleration A]",
        "joint moves at the robot's speed (the thesis's linear; trapezoid with "
        "acceleration A, deg/s^2; quintic) or within every joint's own limits (jerk)",
        "profile jerk",
    ),
)
