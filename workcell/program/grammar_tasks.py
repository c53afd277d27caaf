"""The command language, grippers and task-level commands: ``close|open gripper``,
``planning`` (how planned moves search), ``pick``, ``place``, ``handover``;
:mod:`workcell.program.grammar_sim` puts them in the tree. Lengths m, angles deg,
times s.
"""

from __future__ import annotations

from workcell.program import simcommands as simc
from workcell.program.grammar_motion import ROBOT, robot_leaf
from workcell.program.keytree import Keys, Leaf, Options, Seq, Set
from workcell.program.params import Name, Number, Vector

__all__ = ["CLOSE", "HANDOVER", "OPEN", "PICK", "PLACE", "PLANNING"]

_APPROACH = {"approach": Number("approach", "length", what="approach (m)")}
_GRIPPER_OPTIONS = {
    "distance": Number("max_distance", "length", what="max distance (m)"),
    "angle": Number("max_angle", "angle", what="max angle (deg)"),
}

CLOSE = Keys(
    {
        "gripper": robot_leaf(
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
)
OPEN = Keys(
    {
        "gripper": robot_leaf(
            lambda v: simc.OpenGripper(v["robot"], v.get("settle", False)),
            "open gripper ROBOT [settle]",
            "release the part; settle: a part in mid-air drops onto what is below it",
            "open gripper puma",
            Options({"settle": Set("settle", True)}),
        )
    }
)
PLANNING = Seq(
    Options(
        {
            "clearance": Number("clearance", "length", what="clearance (m)"),
            "time": Number("time_limit", "time", what="time limit (s)"),
            "seed": Number("seed", integer=True, what="seed"),
            "near": Number("near_clearance", "length", what="near clearance (m)"),
        }
    ),
    Leaf(
        lambda v: simc.SetPlanning(
            v.get("clearance"), v.get("time_limit"), v.get("seed"), v.get("near_clearance")
        ),
        "planning [clearance L] [time T] [seed N] [near L]",
        "how planned moves search: clearance L (m, 0.005), time limit T (s, 5) per "
        "search, random seed N (0), near clearance L (m, 0.001) of task-level close work; "
        "shows the settings",
        "planning clearance 5mm time 5 seed 0",
    ),
)
PICK = Seq(
    Name("part", "movable", what="movable part"),
    Keys(
        {
            "with": Seq(
                ROBOT,
                Options(_APPROACH),
                Leaf(
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
)
PLACE = Seq(
    Name("part", "movable", what="movable part"),
    Keys(
        {
            "on": Seq(
                Name("on", "part", what="support (a part)"),
                Keys(
                    {
                        "with": Seq(
                            ROBOT,
                            Options(
                                {
                                    "at": Vector("position", 2, "length", what="x y (m)"),
                                    **_APPROACH,
                                }
                            ),
                            Leaf(
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
)
HANDOVER = Seq(
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
                            Leaf(
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
)
