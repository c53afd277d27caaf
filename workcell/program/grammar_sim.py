"""The command language, cell and simulation part (thesis §4.4-4.6): the one place that
assembles its key tree.

Each entry of :data:`BRANCHES` is a top-level keyword and its key tree; every leaf
builds a command of :mod:`workcell.program.cellcommands` or
:mod:`workcell.program.simcommands`. The cell's keywords are in
:mod:`~workcell.program.grammar_cell`, the moves and motion settings in
:mod:`~workcell.program.grammar_motion` (with the tool-pose options), the grippers and
task-level commands in :mod:`~workcell.program.grammar_tasks`; this module holds
``simulate``, ``mode``, the clocks (``wait``, ``play``, ``time``) and the read-backs.
Joint values are degrees (metres for prismatic joints) unless a unit says otherwise;
speeds deg/s; times s; lengths m.
"""

from __future__ import annotations

from typing import Any

from workcell.program import grammar_logic
from workcell.program import progcommands as progc
from workcell.program import simcommands as simc
from workcell.program.grammar_cell import ADD, CELL
from workcell.program.grammar_motion import JOG, MOVE, OVERRIDE, PROFILE, SPEED, robot_leaf
from workcell.program.grammar_tasks import CLOSE, HANDOVER, OPEN, PICK, PLACE, PLANNING
from workcell.program.keytree import Keys, Leaf, Node, Options, Seq, Set
from workcell.program.params import Choice, Name, Number, Text

__all__ = ["ALIASES", "BRANCHES"]


_MODES = {m: m for m in simc.MODES}
_SIMULATE_OPTIONS = Options(
    {"dt": Number("dt", "time", what="dt (s)"), "realtime": Set("realtime", True)}
)


def _simulate(v: dict[str, Any]) -> simc.Simulate:
    return simc.Simulate(v.get("mode", "path"), v.get("dt", 0.01), v.get("realtime", False))


_SIMULATE_LEAF = Leaf(
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
        "stop": Leaf(
            lambda v: simc.StopSimulation(), "simulate stop", "end the simulation", "simulate stop"
        ),
        **{m: Seq(Set("mode", m), _SIMULATE_OPTIONS, _SIMULATE_LEAF) for m in simc.MODES},
    },
    other=Seq(_SIMULATE_OPTIONS, _SIMULATE_LEAF),
    empty=_SIMULATE_LEAF,
)


_LANGUAGE = Options({"language": Choice("language", {k: k for k in progc.LANGUAGES})})
_EXPORT = Keys(
    {
        "program": robot_leaf(
            lambda v: progc.ExportProgram(v["robot"], v["path"], v.get("language")),
            "export program ROBOT FILE [language urscript|krl|rapid|fanuc_ls]",
            "write the robot's program as it ran in URScript, KRL (.src and .dat), RAPID or "
            "FANUC TP (default: from the suffix .script, .src, .mod, .ls; "
            "docs/robot-programs.md)",
            "export program puma pick.src",
            Text("path"),
            _LANGUAGE,
        )
    }
)
_RUN = Keys(
    {
        "program": robot_leaf(
            lambda v: progc.RunRobotProgram(v["robot"], v["path"], v.get("language")),
            "run program ROBOT FILE [language urscript|krl|rapid|fanuc_ls]",
            "run a robot program (URScript, KRL, RAPID, FANUC LS) on the robot",
            "run program puma pick.src",
            Text("path"),
            _LANGUAGE,
        )
    }
)


def _query(build: Any, syntax: str, summary: str) -> Leaf:
    return Leaf(build, syntax, summary, syntax)


BRANCHES: dict[str, Node] = {
    "cell": CELL,
    "add": Keys({**ADD.branches, **grammar_logic.ADD_DEVICES}),
    "simulate": _SIMULATE,
    "mode": Seq(
        Choice("mode", _MODES),
        Leaf(
            lambda v: simc.SetMode(v["mode"]),
            "mode path|joint-by-joint|playback",
            "switch mode",
            "mode playback",
        ),
    ),
    "speed": SPEED,
    "override": OVERRIDE,
    "profile": PROFILE,
    "move": MOVE,
    "close": CLOSE,
    "open": OPEN,
    "planning": PLANNING,
    "pick": PICK,
    "place": PLACE,
    "handover": HANDOVER,
    "jog": JOG,
    "export": _EXPORT,
    "wait": Seq(
        Number("seconds", "time", what="seconds"),
        Leaf(
            lambda v: simc.Wait(v["seconds"]),
            "wait T [s|ms]",
            "let simulated time pass",
            "wait 0.5",
        ),
    ),
    "play": Seq(
        Options({"realtime": Set("realtime", True)}),
        Leaf(
            lambda v: simc.Play(v.get("realtime")),
            "play [realtime]",
            "replay the stored frames",
            "play",
        ),
    ),
    "joints": robot_leaf(
        lambda v: simc.Joints(v["robot"]), "joints ROBOT", "joint values (deg)", "joints puma"
    ),
    "pose": robot_leaf(
        lambda v: simc.ToolPose(v["robot"]), "pose ROBOT", "tool pose (m, deg)", "pose puma"
    ),
    "held": robot_leaf(lambda v: simc.Held(v["robot"]), "held ROBOT", "the part held", "held puma"),
    "clearance": Seq(
        Name("a", "cellitem", what="part or robot"),
        Name("b", "cellitem", what="part or robot"),
        Leaf(
            lambda v: simc.Clearance(v["a"], v["b"]),
            "clearance A B",
            "distance (m)",
            "clearance puma table_1",
        ),
    ),
    "time": Keys(
        {
            "detail": Leaf(
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
    **grammar_logic.BRANCHES,
    # 'run program ROBOT FILE' (a robot program) beside 'run programs' (programs together)
    "run": Keys({**_RUN.branches, **grammar_logic.BRANCHES["run"].branches}),  # type: ignore[attr-defined]
}

# the Simulator's method names, accepted as keywords too (not offered in completion)
ALIASES: dict[str, Node] = {
    "move_joints_absolute": MOVE.branches["joints"].branches["absolute"],  # type: ignore[attr-defined]
    "move_joints_relative": MOVE.branches["joints"].branches["relative"],  # type: ignore[attr-defined]
    "move_end_effector": MOVE.branches["end_effector"],
    "move_straight_line": MOVE.branches["straight"],
    "move_linear": MOVE.branches["linear"],
    "move_circular": MOVE.branches["circular"],
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
    **grammar_logic.ALIASES,
}
