"""KUKA KRL: the post-processor (``.src`` and ``.dat``).

What it writes (KUKA System Software's expert syntax, no inline-form folds):

- ``NAME.dat``: ``DEFDAT NAME PUBLIC`` with the targets: ``DECL E6AXIS XPn={A1 .., A6
  .., E1 0.0, ...}`` (deg) for joint targets and ``DECL E6POS XPn={X, Y, Z (mm), A, B, C
  (deg, about Z, Y', X''), S, T, E1 0.0, ...}`` for tool poses, S and T from the
  solution's configuration (:mod:`workcell.robotprog.configs`);
- ``NAME.src``: ``DEF NAME( )`` ... ``END``: ``$TOOL`` (the TCP in KUKA's flange frame,
  x out of the flange) and ``$BASE`` (the robot's base), ``$ORI_TYPE = #VAR`` and
  ``$CIRC_TYPE = #BASE`` (the orientation turns evenly from start to end, as the
  simulator's), then ``$OV_PRO`` (the override, %), ``$VEL_AXIS[i]``/``$ACC_AXIS[i]``
  (% of each axis's limits: joint moves as the simulator's profile "jerk"), ``$VEL.CP``
  (m/s), ``$ACC.CP`` (m/s^2), ``$APO.CDIS`` (mm) when they change, and ``PTP XPn``,
  ``LIN XPn``, ``CIRC XPaux, XPn`` with ``C_DIS`` for a zone; ``$OUT[n] = TRUE|FALSE``,
  ``WAIT SEC s``, ``WAIT FOR $IN[n]``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from workcell.robotprog.configs import kuka_status_turn
from workcell.robotprog.instructions import (
    MoveCircular,
    MoveJoint,
    MoveLinear,
    Program,
    SetOutput,
    Wait,
    WaitInput,
)
from workcell.robotprog.rotations import KUKA_FROM_OURS, fmt, to_kuka_frame, zyx
from workcell.robotprog.writing import (
    header,
    identifier,
    joint_notes,
    override_of,
    tool_law,
    via_pose,
)

__all__ = ["frame", "write"]

Array = NDArray[np.float64]
_EXT = ",E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0"


def frame(T: Array) -> str:
    """``{X .., Y .., Z .., A .., B .., C ..}`` of a KUKA frame (mm, deg)."""
    a, b, c = zyx(T)
    x, y, z = (1000.0 * v for v in T[:3, 3])
    return f"X {fmt(x, 6)},Y {fmt(y, 6)},Z {fmt(z, 6)},A {fmt(a, 6)},B {fmt(b, 6)},C {fmt(c, 6)}"


def _e6pos(prog: Program, T: Array, q: Array) -> str:
    s, t = kuka_status_turn(prog.model, q)
    return "{" + frame(to_kuka_frame(T)) + f",S {s},T {t}" + _EXT + "}"


def _e6axis(q: Array) -> str:
    deg = np.degrees(q)
    return "{" + ",".join(f"A{i + 1} {fmt(v, 6)}" for i, v in enumerate(deg)) + _EXT + "}"


def _pct(f: float) -> int:
    return max(1, min(100, round(100.0 * f)))


def write(prog: Program, name: str) -> dict[str, str]:
    """The program as KRL: ``{".src": text, ".dat": text}``."""
    prog.notes += joint_notes(prog, "KRL", ("jerk",))
    fs = [
        override_of(i)
        for i in prog.instructions
        if isinstance(i, MoveJoint | MoveLinear | MoveCircular)
    ]
    if any(abs(100.0 * f - _pct(f)) > 1e-9 for f in fs):
        prog.notes.append("$OV_PRO is a whole percentage: overrides were rounded")
    nm = identifier(name, upper=True)
    src = ["&ACCESS RVP", "&REL 1", f"DEF {nm}( )"]
    src += [f"; {h}" for h in header(prog, "mm, deg (A, B, C about Z, Y', X''), m/s, m/s^2")]
    tool = KUKA_FROM_OURS.T @ prog.tcp @ KUKA_FROM_OURS
    src += [
        "$TOOL = {" + frame(tool) + "}",
        "$BASE = {X 0.0,Y 0.0,Z 0.0,A 0.0,B 0.0,C 0.0}",
        "$ORI_TYPE = #VAR",
        "$CIRC_TYPE = #BASE",
    ]
    for i in range(1, 7):
        src.append(f"$VEL_AXIS[{i}] = 100")
    for i in range(1, 7):
        src.append(f"$ACC_AXIS[{i}] = 100")
    dat = ["&ACCESS RVP", "&REL 1", f"DEFDAT {nm} PUBLIC"]
    state: dict[str, str] = {}

    def setting(var: str, value: str) -> None:
        if state.get(var) != value:
            src.append(f"{var} = {value}")
            state[var] = value

    n = 0

    def point(kind: str, value: str) -> str:
        nonlocal n
        n += 1
        dat.append(f"DECL {kind} XP{n}={value}")
        return f"XP{n}"

    for i, ins in enumerate(prog.instructions):
        if isinstance(ins, MoveJoint | MoveLinear | MoveCircular):
            f = override_of(ins)
            setting("$OV_PRO", str(_pct(f)))
            if ins.zone > 0:
                setting("$APO.CDIS", fmt(1000.0 * ins.zone, 6))
            apo = " C_DIS" if ins.zone > 0 else ""
        if isinstance(ins, MoveJoint):
            if ins.pose is not None:
                p = point("E6POS", _e6pos(prog, ins.pose, ins.q))
            else:
                p = point("E6AXIS", _e6axis(ins.q))
            src.append(f"PTP {p}{apo}")
        elif isinstance(ins, MoveLinear | MoveCircular):
            v, a = tool_law(prog, i)
            setting("$VEL.CP", f"{v:.10g}")
            setting("$ACC.CP", f"{a:.10g}")
            if isinstance(ins, MoveLinear):
                src.append(f"LIN {point('E6POS', _e6pos(prog, ins.pose, ins.q))}{apo}")
            else:
                via = via_pose(ins)
                aux = point("POS", "{" + frame(to_kuka_frame(via)) + "}")
                end = point("E6POS", _e6pos(prog, ins.pose, ins.q))
                src.append(f"CIRC {aux}, {end}{apo}")
        elif isinstance(ins, Wait):
            src.append(f"WAIT SEC {ins.seconds:.10g}")
        elif isinstance(ins, SetOutput):
            src.append(f"$OUT[{ins.number}] = {'TRUE' if ins.value else 'FALSE'}")
        elif isinstance(ins, WaitInput):
            cond = f"$IN[{ins.number}]" if ins.value else f"NOT $IN[{ins.number}]"
            src.append(f"WAIT FOR {cond}")
    src.append("END")
    dat.append("ENDDAT")
    return {".src": "\n".join(src) + "\n", ".dat": "\n".join(dat) + "\n"}
