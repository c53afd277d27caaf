"""One instruction list: what a robot did in a simulation, command by command.

:func:`from_sim` reads the timeline of a :class:`~workcell.sim.simulator.Simulator` that
ran (each command's record carries what the command was asked, see
:mod:`workcell.sim.cycle`) and returns a :class:`Program`: the robot's tool (TCP in its
flange frame), then its instructions in order. Every target is in the robot's base frame
(m, rad); the instruction list does not depend on any robot language, the
post-processors (:mod:`workcell.robotprog.urscript`, ``krl``, ``rapid``, ``fanuc``)
write it in theirs, and the readers of those languages produce the same instructions.

- :class:`MoveJoint`: a joint move to ``q`` (joint targets), or to the tool pose ``pose``
  through the joint solution ``q`` (``move_end_effector``); its timing: ``speed``
  (:class:`JointSpeed`: the simulator's profile, robot speed, acceleration and override);
- :class:`MoveLinear`, :class:`MoveCircular`: tool poses, tool speed (m/s; None: as fast
  as the joints allow, a straight line of the thesis or of profile "jerk") and
  acceleration (m/s^2), the override, ``q`` the joints the move ends at;
- every move has a ``zone`` (m, 0: a stop);
- :class:`Wait`: a dwell (s): the simulation's waits and the time the robot stood still
  while others moved (a signal wait will become :class:`WaitInput` once the cell has
  signals);
- :class:`SetOutput`, :class:`WaitInput`: digital I/O by number and name; the gripper is
  the output named ``"gripper"`` (True closes it);
- planned and task-level moves (``plan=True``, ``pick``, ``place``) appear as the joint
  and straight-line moves they became (a planned path: one joint move per waypoint).

The list starts with a joint move to the joints the robot had when the simulation
started (it takes no time there; a real controller needs a joint move first).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell.errors import ProgramError
from workcell.robots.robot import Robot
from workcell.spatial import invert

__all__ = [
    "GRIPPER",
    "Instruction",
    "JointSpeed",
    "MoveCircular",
    "MoveJoint",
    "MoveLinear",
    "Program",
    "SetOutput",
    "Wait",
    "WaitInput",
    "flange_of",
    "from_sim",
    "tcp_of",
]

Array = NDArray[np.float64]
GRIPPER = "gripper"  # the output that opens (False) and closes (True) the robot's gripper
_GAP = 1e-9  # s: a pause shorter than this is no wait


@dataclass(frozen=True)
class JointSpeed:
    """How a joint move is timed: the simulator's ``profile`` ("jerk": each joint's own
    limits x ``override``; the thesis profiles: ``speed`` rad/s, ``acceleration`` rad/s^2
    of the joint that moves most, x ``override``)."""

    profile: str = "jerk"
    speed: float = 0.3
    acceleration: float = 2.0
    override: float = 1.0


@dataclass(frozen=True)
class MoveJoint:
    """A joint move to ``q`` (rad/m); ``pose``: the tool pose it was asked for (4x4, base
    frame) when it was a Cartesian target, with the requested ``config`` letters."""

    q: Array
    speed: JointSpeed = field(default_factory=JointSpeed)
    zone: float = 0.0
    pose: Array | None = None
    config: str | None = None


@dataclass(frozen=True)
class MoveLinear:
    """The tool point along a straight line to ``pose`` (4x4, base frame) at ``speed``
    (m/s; None: as fast as the joints allow) and ``acceleration`` (m/s^2); ``q`` the joints
    at its end; ``override`` the speed override; ``duration``: how long it took (s, for
    the languages that need a speed when ``speed`` is None)."""

    pose: Array
    q: Array
    speed: float | None = None
    acceleration: float | None = None
    zone: float = 0.0
    override: float = 1.0
    duration: float = 0.0


@dataclass(frozen=True)
class MoveCircular:
    """The tool point along the circle through its start, ``via`` (3,) and ``pose``'s
    position (base frame), orientation slerped to ``pose``; otherwise as
    :class:`MoveLinear` (``speed`` always set)."""

    via: Array
    pose: Array
    q: Array
    speed: float
    acceleration: float
    zone: float = 0.0
    override: float = 1.0


@dataclass(frozen=True)
class Wait:
    """A dwell of ``seconds`` (s)."""

    seconds: float


@dataclass(frozen=True)
class SetOutput:
    """Digital output ``number`` (named ``name``) set to ``value``."""

    number: int
    name: str
    value: bool


@dataclass(frozen=True)
class WaitInput:
    """Wait until digital input ``number`` (named ``name``) is ``value``."""

    number: int
    name: str
    value: bool = True


Instruction = MoveJoint | MoveLinear | MoveCircular | Wait | SetOutput | WaitInput


@dataclass
class Program:
    """A robot's program: ``robot`` (its name in the cell), the robot model (``model``),
    its ``tcp`` (4x4, the tool centre point in the flange frame), ``instructions``,
    ``outputs`` and ``inputs`` (I/O number -> name), the simulated ``cycle_time`` (s), and
    ``notes`` (what the language cannot say exactly, written in the file's header)."""

    robot: str
    model: Robot
    tcp: Array
    instructions: list[Instruction]
    outputs: dict[int, str] = field(default_factory=dict)
    inputs: dict[int, str] = field(default_factory=dict)
    cycle_time: float = 0.0
    notes: list[str] = field(default_factory=list)


def flange_of(robot: Robot) -> Array:
    """The flange (ROS ``tool0``) in the last link's frame: the gripper's mount, else the
    robot's tool."""
    g = robot.gripper
    mount = getattr(g, "mount", None) if g is not None else None
    return np.array(mount if mount is not None else robot.tool, dtype=np.float64)


def tcp_of(robot: Robot) -> Array:
    """The robot's tool centre point in its flange frame (4x4)."""
    return invert(flange_of(robot)) @ robot.tool


def _records(sim: Any, robot: str) -> list[dict[str, Any]]:
    """The robot's command records and the cell's waits, in order of their start."""
    recs = [e.data for e in sim.events if e.data is not None and "program" in e.data]
    order = sorted(range(len(recs)), key=lambda i: (recs[i]["t_start"], i))
    return [recs[i] for i in order if recs[i]["robot"] in (robot, None)]


def _speed(p: Mapping[str, Any]) -> JointSpeed:
    return JointSpeed(
        str(p.get("profile", "jerk")),
        float(p.get("robot_speed", 0.3)),
        float(p.get("profile_acceleration", 2.0)),
        float(p.get("override", 1.0)),
    )


def _arr(v: Any) -> Array:
    return np.array(v, dtype=np.float64)


def from_sim(sim: Any, robot: str, *, signals: Mapping[str, int] | None = None) -> Program:
    """The instruction list of ``robot`` in simulator ``sim`` as it ran (module doc).

    ``signals`` maps signal names (``"gripper"``, ...) to I/O numbers; outputs without one
    get the lowest free number from 1. ProgramError for an unknown robot or bad numbers.
    """
    name = sim._robot(robot)
    numbers = dict(signals or {})
    for k, v in numbers.items():
        if not isinstance(k, str) or isinstance(v, bool) or not isinstance(v, int) or v < 0:
            raise ProgramError(
                f"signals must map signal names to I/O numbers >= 0, got {k!r}: {v!r}"
            )
    model = sim.cell.robots[name].robot
    prog = Program(name, model, tcp_of(model), [], cycle_time=0.0)
    used = set(numbers.values())

    def number(signal: str) -> int:
        if signal not in numbers:
            n = 1
            while n in used:
                n += 1
            numbers[signal] = n
            used.add(n)
        return numbers[signal]

    t = 0.0
    out: list[Instruction] = []
    for rec in _records(sim, name):
        start, dur = float(rec["t_start"]), float(rec["duration_s"])
        p = rec["program"]
        kind = p["kind"]
        if kind == "wait":  # the cell's clock: a dwell up to its end (with any gap before)
            if start + dur > t + _GAP:
                out.append(Wait(start + dur - t))
            t = max(t, start + dur)
            continue
        if start > t + _GAP:
            out.append(Wait(start - t))
        t = max(t, start + dur)
        if kind == "joint":
            pose = None if p.get("pose") is None else _arr(p["pose"])
            out.append(MoveJoint(_arr(p["q"]), _speed(p), float(p["zone"]), pose, p.get("config")))
        elif kind == "path":
            out.extend(MoveJoint(_arr(w), _speed(p)) for w in p["waypoints"])
        elif kind == "linear":
            out.append(
                MoveLinear(
                    _arr(p["pose"]), _arr(p["q"]), float(p["speed"]), float(p["acceleration"]),
                    float(p["zone"]), float(p["override"]), dur,
                )
            )  # fmt: skip
        elif kind == "line":
            out.append(
                MoveLinear(
                    _arr(p["pose"]), _arr(p["q"]), None, None, 0.0, float(p["override"]), dur
                )
            )
        elif kind == "circular":
            out.append(
                MoveCircular(
                    _arr(p["via"]), _arr(p["pose"]), _arr(p["q"]), float(p["speed"]),
                    float(p["acceleration"]), float(p["zone"]), float(p["override"]),
                )
            )  # fmt: skip
        elif kind == "gripper":
            n = number(GRIPPER)
            prog.outputs[n] = GRIPPER
            out.append(SetOutput(n, GRIPPER, bool(p["closed"])))
        elif kind == "set_signal":  # cell signals (issue 22): an output
            n = number(str(p["name"]))
            prog.outputs[n] = str(p["name"])
            out.append(SetOutput(n, str(p["name"]), bool(p["value"])))
        elif kind == "wait_signal":
            n = number(str(p["name"]))
            prog.inputs[n] = str(p["name"])
            out.append(WaitInput(n, str(p["name"]), bool(p.get("value", True))))
    q0 = sim.timeline.frame(0)[2][sim._qadr[name]].astype(np.float64)
    first = next((i.speed for i in out if isinstance(i, MoveJoint)), None)
    prog.instructions = [MoveJoint(q0, first or _speed(_settings(sim, name))), *out]
    prog.cycle_time = t
    return prog


def _settings(sim: Any, name: str) -> dict[str, Any]:
    """The simulator's current motion settings of robot ``name`` (as in a record)."""
    return {
        "profile": sim.profile,
        "robot_speed": sim.speed(name),
        "profile_acceleration": sim.acceleration,
        "override": sim._override[name],
    }
