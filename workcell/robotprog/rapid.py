"""ABB RAPID: the post-processor (``.mod``).

What it writes (the RAPID reference's instructions and data types): ``MODULE NAME`` with

- ``PERS tooldata`` (the TCP in the flange frame: mm and a quaternion w, x, y, z) and
  ``PERS wobjdata`` (the robot's base: user and object frames at the origin);
- ``CONST jointtarget jN := [[a1, ..., a6], [9E+09, ...]]`` (deg) and ``CONST robtarget
  pN := [[x, y, z], [q1, q2, q3, q4], [cf1, cf4, cf6, cfx], [9E+09, ...]]`` (mm,
  quaternion w, x, y, z, confdata from the solution's configuration);
- ``speeddata`` ``[v_tcp mm/s, v_ori deg/s, v_leax, v_reax]`` and ``zonedata`` (the
  predefined z1 ... z200 when they fit, else declared; ``fine`` for a stop);
- ``PROC main()``: ``ConfJ \\On``, ``VelSet`` (the override, %), ``PathAccLim`` (the tool
  acceleration, m/s^2) when it changes, ``MoveAbsJ`` (joint targets), ``MoveJ``
  (Cartesian joint targets), ``MoveL``, ``MoveC`` (via, end), ``SetDO``, ``WaitTime``,
  ``WaitDI``. Joint moves use ``vmax``: their time is each joint's limits x the
  override (the simulator's profile "jerk").

Signals are named by the program's I/O names (``gripper``): RAPID's I/O is by name; the
header lists the numbers.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from workcell.robotprog.configs import abb_confdata
from workcell.robotprog.instructions import (
    MoveCircular,
    MoveJoint,
    MoveLinear,
    Program,
    SetOutput,
    Wait,
    WaitInput,
)
from workcell.robotprog.rotations import fmt, quat_wxyz
from workcell.robotprog.writing import (
    header,
    identifier,
    joint_notes,
    override_of,
    tool_law,
    via_pose,
)

__all__ = ["PREDEFINED_ZONES", "write"]

Array = NDArray[np.float64]
PREDEFINED_ZONES = (1, 5, 10, 15, 20, 30, 40, 50, 60, 80, 100, 150, 200)  # mm: z1 ... z200
_EAX = "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"
_LOAD = "[1,[0,0,0.001],[1,0,0,0],0,0,0]"


def _frame(T: Array) -> str:
    pos = ",".join(fmt(1000.0 * v, 6) for v in T[:3, 3])
    q = ",".join(fmt(v, 10) for v in quat_wxyz(T))
    return f"[[{pos}],[{q}]]"


def _signal(name: str, number: int, prefix: str) -> str:
    return identifier(name, max_len=32, default=f"{prefix}{number}")


def write(prog: Program, name: str) -> dict[str, str]:
    """The program as RAPID: ``{".mod": text}``."""
    prog.notes += joint_notes(prog, "RAPID", ("jerk",))
    nm = identifier(name, max_len=32)
    out = [f"MODULE {nm}"]
    out += [f"  ! {h}" for h in header(prog, "mm, quaternions w, x, y, z, deg, mm/s, m/s^2")]
    out.append(f"  PERS tooldata t_tcp := [TRUE,{_frame(prog.tcp)},{_LOAD}];")
    out.append('  PERS wobjdata w_base := [FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];')
    decl: list[str] = []
    body = ["  PROC main()", "    ConfJ \\On;", "    ConfL \\Off;"]
    state: dict[str, str] = {}
    speeds: dict[str, str] = {}
    zones: dict[str, str] = {}
    n = 0

    def setting(key: str, line: str) -> None:
        if state.get(key) != line:
            body.append(line)
            state[key] = line

    def point(kind: str, value: str) -> str:
        nonlocal n
        n += 1
        p = f"{'j' if kind == 'jointtarget' else 'p'}{n}"
        decl.append(f"  CONST {kind} {p} := {value};")
        return p

    def zone(z: float) -> str:
        if z <= 0:
            return "fine"
        mm = 1000.0 * z
        if any(abs(mm - k) < 1e-9 for k in PREDEFINED_ZONES):
            return f"z{round(mm)}"
        key = fmt(mm, 6)
        if key not in zones:
            zones[key] = f"z_{len(zones) + 1}"
            o, r = fmt(1.5 * mm, 6), fmt(0.15 * mm, 6)
            decl.append(f"  CONST zonedata {zones[key]} := [FALSE,{key},{o},{o},{r},{o},{r}];")
        return zones[key]

    def speed(v: float) -> str:
        key = fmt(1000.0 * v, 6)
        if key not in speeds:
            speeds[key] = f"v_{len(speeds) + 1}"
            decl.append(f"  CONST speeddata {speeds[key]} := [{key},500,5000,1000];")
        return speeds[key]

    for i, ins in enumerate(prog.instructions):
        if isinstance(ins, MoveJoint | MoveLinear | MoveCircular):
            f = override_of(ins)
            setting("velset", f"    VelSet {100.0 * f:.10g}, 5000;")
        if isinstance(ins, MoveJoint):
            z = zone(ins.zone)
            if ins.pose is not None:
                conf = ",".join(str(c) for c in abb_confdata(prog.model, ins.q))
                p = point("robtarget", f"[{_frame(ins.pose)[1:-1]},[{conf}],{_EAX}]")
                body.append(f"    MoveJ {p}, vmax, {z}, t_tcp \\WObj:=w_base;")
            else:
                deg = ",".join(fmt(v, 6) for v in np.degrees(ins.q))
                p = point("jointtarget", f"[[{deg}],{_EAX}]")
                body.append(f"    MoveAbsJ {p}, vmax, {z}, t_tcp;")
        elif isinstance(ins, MoveLinear | MoveCircular):
            v, a = tool_law(prog, i)
            acc = f"{a:.10g}"
            setting("acc", f"    PathAccLim TRUE \\AccMax:={acc}, TRUE \\DecelMax:={acc};")
            conf = ",".join(str(c) for c in abb_confdata(prog.model, ins.q))
            sp, z = speed(v), zone(ins.zone)
            if isinstance(ins, MoveLinear):
                end = point("robtarget", f"[{_frame(ins.pose)[1:-1]},[{conf}],{_EAX}]")
                body.append(f"    MoveL {end}, {sp}, {z}, t_tcp \\WObj:=w_base;")
            else:
                via = via_pose(ins)
                cv = point("robtarget", f"[{_frame(via)[1:-1]},[{conf}],{_EAX}]")
                end = point("robtarget", f"[{_frame(ins.pose)[1:-1]},[{conf}],{_EAX}]")
                body.append(f"    MoveC {cv}, {end}, {sp}, {z}, t_tcp \\WObj:=w_base;")
        elif isinstance(ins, Wait):
            body.append(f"    WaitTime {ins.seconds:.10g};")
        elif isinstance(ins, SetOutput):
            sig = _signal(ins.name, ins.number, "do")
            body.append(f"    SetDO {sig}, {1 if ins.value else 0};")
        elif isinstance(ins, WaitInput):
            sig = _signal(ins.name, ins.number, "di")
            body.append(f"    WaitDI {sig}, {1 if ins.value else 0};")
    body.append("  ENDPROC")
    out += decl + body + ["ENDMODULE"]
    return {".mod": "\n".join(out) + "\n"}
