"""What the four post-processors share: the header, names, and speeds a language lacks.

- :func:`header`: the lines every exported file starts with (as comments): the robot,
  the simulated cycle time, the frames and units, the I/O table, and the notes on what
  the language cannot say exactly;
- :func:`identifier`: a program or variable name the language accepts;
- :func:`line_law`: a tool speed and acceleration for a straight line that had none (a
  thesis or profile "jerk" straight line): the trapezoid that takes the line's own time;
- :func:`joint_notes`: the notes for joint moves timed by a profile the language lacks;
- :func:`override_of`, :func:`via_pose`: a motion's speed override, a circular move's
  via point as a pose.
"""

from __future__ import annotations

import math
import re

import numpy as np
from numpy.typing import NDArray

from workcell.robotprog.instructions import (
    MoveCircular,
    MoveJoint,
    MoveLinear,
    Program,
)

__all__ = [
    "DEFAULT_TOOL_ACCELERATION",
    "end_pose",
    "header",
    "identifier",
    "joint_notes",
    "line_law",
    "override_of",
    "via_pose",
]

Array = NDArray[np.float64]
DEFAULT_TOOL_ACCELERATION = 1.2  # m/s^2, as the simulator's


def identifier(name: str, *, max_len: int = 24, upper: bool = False, default: str = "prog") -> str:
    """``name`` as an identifier: letters, digits and underscores, starting with a letter."""
    s = re.sub(r"[^A-Za-z0-9_]", "_", name)
    if not s or not s[0].isalpha():
        s = f"{default}_{s}" if s else default
    s = s[:max_len]
    return s.upper() if upper else s


def header(prog: Program, units: str, io_word: str = "output") -> list[str]:
    """The header lines (without comment marks; module doc)."""
    lines = [
        f"workcell: the program of robot '{prog.robot}' ({prog.model.name}) as it ran in the "
        f"simulation; simulated cycle time {prog.cycle_time:.6f} s",
        f"targets in the robot's base frame; {units}",
    ]
    for n, name in sorted(prog.outputs.items()):
        what = " (TRUE closes the gripper)" if name == "gripper" else ""
        lines.append(f"I/O: {io_word} {n} = {name}{what}")
    for n, name in sorted(prog.inputs.items()):
        lines.append(f"I/O: input {n} = {name}")
    lines += [f"note: {n}" for n in dict.fromkeys(prog.notes)]
    return lines


def end_pose(prog: Program, q: Array) -> Array:
    """The tool pose (4x4, base frame) at joints q."""
    return prog.model.fk(q)


def line_law(length: float, duration: float) -> tuple[float, float]:
    """(speed m/s, acceleration m/s^2) of the trapezoid covering ``length`` (m) in
    ``duration`` (s) with the default acceleration (more when even a triangle at that
    acceleration is too slow)."""
    if length <= 0.0 or duration <= 0.0:
        return 0.1, DEFAULT_TOOL_ACCELERATION
    a = DEFAULT_TOOL_ACCELERATION
    if duration < 2.0 * math.sqrt(length / a):  # a triangle: T = 2 sqrt(L / a)
        a = 4.0 * length / duration**2
        return 2.0 * length / duration, a
    disc = duration * duration * a * a - 4.0 * a * length
    v = 0.5 * (duration * a - math.sqrt(max(disc, 0.0)))  # T = L / v + v / a
    return v, a


def tool_law(prog: Program, i: int) -> tuple[float, float]:
    """The tool speed and acceleration (m/s, m/s^2, before the override) of instruction i,
    a linear or circular move (:func:`line_law` for a line without a tool speed)."""
    ins = prog.instructions[i]
    assert isinstance(ins, MoveLinear | MoveCircular)
    if ins.speed is not None and ins.acceleration is not None:
        return ins.speed, ins.acceleration
    start = previous_q(prog, i)
    p0 = end_pose(prog, start)[:3, 3]
    length = float(np.linalg.norm(ins.pose[:3, 3] - p0))
    v, a = line_law(length, ins.duration)
    f = ins.override
    return v / f, a / (f * f)


def previous_q(prog: Program, i: int) -> Array:
    """The joints at the end of the last motion before instruction i."""
    for ins in reversed(prog.instructions[:i]):
        if isinstance(ins, MoveJoint | MoveLinear | MoveCircular):
            return ins.q
    return prog.instructions[0].q  # type: ignore[union-attr]


def joint_notes(prog: Program, language: str, native: tuple[str, ...]) -> list[str]:
    """Notes for joint moves timed by a profile ``language`` cannot say (``native``: the
    profiles it can)."""
    other = sorted(
        {i.speed.profile for i in prog.instructions if isinstance(i, MoveJoint)} - set(native)
    )
    if not other:
        return []
    how = {
        "jerk": "each joint's own speed, acceleration and jerk limits",
        "trapezoid": "the robot speed and acceleration of the joint that moves most",
    }
    return [
        f"joint moves were timed by profile '{p}' in the simulation; {language} times them "
        f"by {how[native[0]]}, so their times differ"
        for p in other
    ]


def override_of(ins: MoveJoint | MoveLinear | MoveCircular) -> float:
    """The speed override (0 < f <= 1) a motion ran with."""
    return ins.speed.override if isinstance(ins, MoveJoint) else ins.override


def via_pose(ins: MoveCircular) -> Array:
    """A circular move's via point (m, base frame) as a pose: the end pose's orientation."""
    via = ins.pose.copy()
    via[:3, 3] = ins.via
    return via
