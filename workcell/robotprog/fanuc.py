"""FANUC TP as ASCII (``.ls``): the post-processor.

What it writes (the LS layout FANUC's tools print): ``/PROG``, ``/ATTR``, ``/MN``, ``/POS``,
``/END``:

- ``/MN``: ``UFRAME_NUM=0``, ``UTOOL_NUM=1``, ``OVERRIDE=n%`` (the override, when it
  changes), ``J P[n] 100% FINE|CNTn`` (joint moves at each joint's limits x the override:
  the simulator's profile "jerk"), ``L P[n] v mm/sec FINE|CNTn [ACCn]``, ``C P[via]`` then
  ``: P[end] v mm/sec ...``, ``DO[n:name]=ON|OFF``, ``WAIT s(sec)``, ``WAIT DI[n]=ON``,
  and ``!`` remarks (the header, 32 characters a line as the pendant shows them);
- ``/POS``: ``P[n]{ GP1: UF : 0, UT : 1, CONFIG : 'N U T, t4, t5, t6', X, Y, Z (mm), W, P,
  R (deg, about the fixed X, Y, Z) }`` for tool poses, ``J1 .. J6`` (deg, the controller's
  values: J3 from the horizontal on the LR Mate, :mod:`workcell.robotprog.configs`) for
  joint targets.

FANUC's CNT n (0-100) has no length: workcell writes a zone of n mm as CNTn (n <= 100)
and reads CNTn as n mm. ``ACCn`` is n % of the default tool acceleration (1.2 m/s^2).
Speeds in mm/sec and percentages are whole numbers (the header says when one was
rounded). UT 1 is the tool set on the controller (the header gives it) and UF 0 the
robot's base frame; targets are printed with more decimals than the pendant shows so
that they read back to 1e-6.
"""

from __future__ import annotations

import textwrap

import numpy as np
from numpy.typing import NDArray

from workcell.robotprog.configs import fanuc_config, fanuc_from_joints
from workcell.robotprog.instructions import (
    MoveCircular,
    MoveJoint,
    MoveLinear,
    Program,
    SetOutput,
    Wait,
    WaitInput,
)
from workcell.robotprog.rotations import fmt, zyx
from workcell.robotprog.writing import (
    DEFAULT_TOOL_ACCELERATION,
    header,
    identifier,
    joint_notes,
    override_of,
    tool_law,
    via_pose,
)

__all__ = ["wpr", "write"]

Array = NDArray[np.float64]
_ATTR = """/ATTR
OWNER		= MNEDITOR;
COMMENT		= "workcell";
PROG_SIZE	= 0;
CREATE		= DATE 00-01-01  TIME 00:00:00;
MODIFIED	= DATE 00-01-01  TIME 00:00:00;
FILE_NAME	= ;
VERSION		= 0;
LINE_COUNT	= {lines};
MEMORY_SIZE	= 0;
PROTECT		= READ_WRITE;
TCD:  STACK_SIZE	= 0,
      TASK_PRIORITY	= 50,
      TIME_SLICE	= 0,
      BUSY_LAMP_OFF	= 0,
      ABORT_REQUEST	= 0,
      PAUSE_REQUEST	= 0;
DEFAULT_GROUP	= 1,*,*,*,*;
CONTROL_CODE	= 00000000 00000000;"""


def wpr(T: Array) -> tuple[float, float, float]:
    """FANUC's W, P, R (deg) of a rotation: R = Rz(R) Ry(P) Rx(W)."""
    a, b, c = zyx(T)
    return c, b, a


def _cart(prog: Program, T: Array, q: Array) -> list[str]:
    flags, t4, t5, t6 = fanuc_config(prog.model, q)
    x, y, z = (1000.0 * v for v in T[:3, 3])
    w, p, r = wpr(T)
    return [
        f"\tUF : 0, UT : 1,\t\tCONFIG : '{flags}, {t4}, {t5}, {t6}',",
        f"\tX = {fmt(x, 6)}  mm,\tY = {fmt(y, 6)}  mm,\tZ = {fmt(z, 6)}  mm,",
        f"\tW = {fmt(w, 6)} deg,\tP = {fmt(p, 6)} deg,\tR = {fmt(r, 6)} deg",
    ]


def _joints(prog: Program, q: Array) -> list[str]:
    j = np.degrees(fanuc_from_joints(prog.model, q))
    cells = [f"J{i + 1}= {fmt(v, 6)} deg" for i, v in enumerate(j)]
    rows = [",\t".join(cells[k : k + 3]) for k in range(0, len(cells), 3)]
    ends = ["," if k < len(rows) - 1 else "" for k in range(len(rows))]
    return ["\tUF : 0, UT : 1,\t", *[f"\t{r}{e}" for r, e in zip(rows, ends, strict=True)]]


def write(prog: Program, name: str) -> dict[str, str]:
    """The program as FANUC LS: ``{".ls": text}``."""
    prog.notes += joint_notes(prog, "FANUC TP", ("jerk",))
    mn: list[str] = []
    pos: list[str] = []
    state: dict[str, str] = {}
    rounded: set[str] = set()

    def whole(v: float, what: str) -> int:
        k = round(v)
        if abs(v - k) > 1e-6:
            rounded.add(what)
        return k

    count = [0]

    def point(lines: list[str]) -> int:
        count[0] += 1
        pos.extend([f"P[{count[0]}]{{", "   GP1:", *lines, "};"])
        return count[0]

    def term(zone: float) -> str:
        if zone <= 0:
            return "FINE"
        return f"CNT{min(100, whole(1000.0 * zone, 'zones (CNT)'))}"

    for i, ins in enumerate(prog.instructions):
        if isinstance(ins, MoveJoint | MoveLinear | MoveCircular):
            f = override_of(ins)
            ov = f"OVERRIDE={max(1, min(100, whole(100.0 * f, 'overrides')))}%"
            if state.get("ov") != ov:
                mn.append(ov)
                state["ov"] = ov
        if isinstance(ins, MoveJoint):
            lines = _joints(prog, ins.q) if ins.pose is None else _cart(prog, ins.pose, ins.q)
            mn.append(f"J P[{point(lines)}] 100% {term(ins.zone)}")
        elif isinstance(ins, MoveLinear | MoveCircular):
            v, a = tool_law(prog, i)
            speed = f"{whole(1000.0 * v, 'speeds (mm/sec)')}mm/sec"
            acc = whole(100.0 * a / DEFAULT_TOOL_ACCELERATION, "accelerations (ACC)")
            if acc > 150:
                rounded.add("accelerations (ACC, at most 150)")
                acc = 150
            opt = f" ACC{acc}" if acc != 100 else ""
            if isinstance(ins, MoveLinear):
                end = point(_cart(prog, ins.pose, ins.q))
                mn.append(f"L P[{end}] {speed} {term(ins.zone)}{opt}")
            else:
                via = via_pose(ins)
                pv = point(_cart(prog, via, ins.q))
                end = point(_cart(prog, ins.pose, ins.q))
                mn.append(f"C P[{pv}]")
                mn.append(f":  P[{end}] {speed} {term(ins.zone)}{opt}")
        elif isinstance(ins, Wait):
            mn.append(f"WAIT {ins.seconds:.10g}(sec)")
        elif isinstance(ins, SetOutput):
            mn.append(f"DO[{ins.number}:{ins.name}]={'ON' if ins.value else 'OFF'}")
        elif isinstance(ins, WaitInput):
            mn.append(f"WAIT DI[{ins.number}:{ins.name}]={'ON' if ins.value else 'OFF'}")
    if rounded:
        prog.notes.append(
            "FANUC TP takes whole numbers for " + ", ".join(sorted(rounded)) + ": rounded"
        )
    x, y, z = (fmt(1000.0 * v, 3) for v in prog.tcp[:3, 3])
    w, pp, r = (fmt(v, 3) for v in wpr(prog.tcp))
    prog.notes.append(f"UTOOL 1 = X {x} Y {y} Z {z} mm, W {w} P {pp} R {r} deg (the TCP)")
    remarks = []
    for h in header(prog, "mm, deg (W, P, R about fixed X, Y, Z), mm/sec; CNTn = n mm zone"):
        remarks += [f"! {c}" for c in textwrap.wrap(h, 30)]
    lines = [*remarks, "UFRAME_NUM=0", "UTOOL_NUM=1", *mn]
    body = []
    k = 0
    for line in lines:
        if line.startswith(":"):
            body.append(f"    {line} ;")
        elif line.startswith("C "):  # the via line: the statement goes on below
            k += 1
            body.append(f"{k:4d}:  {line}")
        else:
            k += 1
            body.append(f"{k:4d}:  {line} ;")
    text = [f"/PROG  {identifier(name, max_len=36, upper=True)}", _ATTR.format(lines=k), "/MN"]
    text += [*body, "/POS", *pos, "/END"]
    return {".ls": "\n".join(text) + "\n"}
