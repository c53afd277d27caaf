"""Universal Robots URScript: the post-processor (``.script``).

What it writes (the URScript manual's functions): one ``def NAME():`` ... ``end``

- ``set_tcp(p[x, y, z, rx, ry, rz])``: the tool centre point in the flange frame;
- ``movej([q1, ..., q6], a=, v=, r=)``: joint targets (rad); ``a`` and ``v`` the
  acceleration (rad/s^2) and speed (rad/s) of the leading axis: exactly the simulator's
  "trapezoid" profile (robot speed and acceleration x the override); other profiles are
  approximated (a note in the header);
- ``movej(get_inverse_kin(p[...], qnear=[...]), ...)``: a Cartesian joint target; qnear
  is the solution the simulation used, which UR's inverse kinematics then picks;
- ``movel(p[...], a=, v=, r=)`` and ``movec(p_via, p_to, a=, v=, r=, mode=0)``: tool
  poses in m and rotation vectors (rad), tool speed m/s and acceleration m/s^2 with the
  override applied (URScript has none), blend radius ``r`` m (the zone); ``mode=0``
  interpolates the orientation from the start to ``p_to`` as the simulator does;
- ``set_standard_digital_out(n, True|False)`` (the gripper and other outputs),
  ``sleep(s)`` (waits), and ``while not get_standard_digital_in(n) == True: sync() end``
  (input waits).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from workcell.robotprog.instructions import (
    MoveCircular,
    MoveJoint,
    MoveLinear,
    Program,
    SetOutput,
    Wait,
    WaitInput,
)
from workcell.robotprog.rotations import fmt, rotvec
from workcell.robotprog.writing import header, identifier, joint_notes, tool_law, via_pose

__all__ = ["write"]

Array = NDArray[np.float64]


def pose(T: Array) -> str:
    """``p[x, y, z, rx, ry, rz]`` (m, rad)."""
    v = [*T[:3, 3], *rotvec(T)]
    return "p[" + ", ".join(fmt(x, 9) for x in v) + "]"


def joints(q: Array) -> str:
    return "[" + ", ".join(fmt(x, 9) for x in q) + "]"


def _num(v: float) -> str:
    return f"{float(v):.10g}"


def _movej(prog: Program, ins: MoveJoint) -> tuple[float, float]:
    s = ins.speed
    f = s.override
    if s.profile in ("trapezoid", "linear", "quintic"):
        return s.speed * f, s.acceleration * f * f
    m = prog.model
    return float(np.min(m.max_speeds)) * f, float(np.min(m.max_accelerations)) * f * f


def write(prog: Program, name: str) -> dict[str, str]:
    """The program as URScript: ``{".script": text}``."""
    prog.notes += joint_notes(prog, "URScript", ("trapezoid",))
    head = header(prog, "m, rad, rotation vectors (rad), m/s, m/s^2")
    out = [f"def {identifier(name)}():"]
    out += [f"  # {h}" for h in head]
    out.append(f"  set_tcp({pose(prog.tcp)})")
    for i, ins in enumerate(prog.instructions):
        if isinstance(ins, MoveJoint):
            v, a = _movej(prog, ins)
            target = joints(ins.q)
            if ins.pose is not None:
                target = f"get_inverse_kin({pose(ins.pose)}, qnear={joints(ins.q)})"
            out.append(f"  movej({target}, a={_num(a)}, v={_num(v)}, r={_num(ins.zone)})")
        elif isinstance(ins, MoveLinear | MoveCircular):
            v, a = tool_law(prog, i)
            f = ins.override
            law = f"a={_num(a * f * f)}, v={_num(v * f)}, r={_num(ins.zone)}"
            if isinstance(ins, MoveLinear):
                out.append(f"  movel({pose(ins.pose)}, {law})")
            else:
                via = via_pose(ins)
                out.append(f"  movec({pose(via)}, {pose(ins.pose)}, {law}, mode=0)")
        elif isinstance(ins, Wait):
            out.append(f"  sleep({_num(ins.seconds)})")
        elif isinstance(ins, SetOutput):
            out.append(f"  set_standard_digital_out({ins.number}, {ins.value})")
        elif isinstance(ins, WaitInput):
            out.append(f"  while not get_standard_digital_in({ins.number}) == {ins.value}:")
            out.append("    sync()")
            out.append("  end")
    out.append("end")
    return {".script": "\n".join(out) + "\n"}
