"""What KRL statements do when they run (the run-time half of
:mod:`workcell.robotprog.read_krl`): operators, conversions, I/O, motions and ``BAS``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from workcell.errors import ProgramError
from workcell.robotprog.configs import kuka_status_turn
from workcell.robotprog.exprs import ARITH, COMPARE, Fn, boolean, number
from workcell.robotprog.kuka_values import (
    STRUCT_TYPES,
    frame_matrix,
    geometric,
    joints_of,
    pose_dict,
    program_pose,
    tcp_of_tool,
)
from workcell.robotprog.runtime import VM
from workcell.robotprog.source import Token, error

DEF_VEL_CP, DEF_ACC_CP = 2.0, 2.3  # m/s, m/s^2: BAS(#INITMOV) (workcell's choice)


__all__ = ["BINARY", "DEF_ACC_CP", "DEF_VEL_CP", "UNARY"]


BINARY: dict[str, tuple[int, Any]] = {
    "==": (1, COMPARE["=="]), "<>": (1, COMPARE["<>"]), "<": (1, COMPARE["<"]),
    ">": (1, COMPARE[">"]), "<=": (1, COMPARE["<="]), ">=": (1, COMPARE[">="]),
    "OR": (2, lambda a, b: boolean(a, "OR") or boolean(b, "OR")),
    "EXOR": (3, lambda a, b: boolean(a, "EXOR") != boolean(b, "EXOR")),
    "AND": (4, lambda a, b: boolean(a, "AND") and boolean(b, "AND")),
    "+": (5, ARITH["+"]), "-": (5, ARITH["-"]),
    "*": (6, ARITH["*"]), "/": (6, ARITH["/"]),
    ":": (8, geometric),
}  # fmt: skip
UNARY: dict[str, tuple[int, Any]] = {
    "NOT": (7, lambda a: not boolean(a, "NOT")),
    "-": (7, lambda a: -number(a)),
    "+": (7, lambda a: number(a)),
}


# ---------------------------------------------------------------------- run time
def _convert(typ: str, old: Any, v: Any) -> Any:
    if typ in STRUCT_TYPES:
        if not isinstance(v, dict):
            raise ProgramError(f"a {typ} takes a structure {{...}}, got {v!r}")
        return {**(old if isinstance(old, dict) else {}), **v}
    if typ == "INT":
        return int(number(v))
    if typ == "REAL":
        return number(v)
    if typ == "BOOL":
        return boolean(v, "a BOOL")
    return v


def _index(holder: Any, i: Any, what: str, base: int = 1) -> int:
    if not isinstance(holder, list):
        raise ProgramError(f"{what} is not an array")
    k = int(number(i, "an index"))
    if not base <= k < base + len(holder):
        raise ProgramError(f"{what}[{k}] is outside the array (1 to {len(holder)})")
    return k - base


def _element(v: Any, i: Any, t: Token) -> Any:
    return v[_index(v, i, t.text)]


def _field(v: Any, f: Token) -> Any:
    if not isinstance(v, dict) or f.upper not in v:
        raise error(f.loc, f"no field {f.text} here")
    return v[f.upper]


def _element_of(base: Fn, idx: Fn, t: Token) -> Fn:
    return lambda vm: _element(base(vm), idx(vm), t)


def _field_of(base: Fn, f: Token) -> Fn:
    return lambda vm: _field(base(vm), f)


def _io_name(vm: VM, kind: str, n: int) -> str:
    names = vm.program.outputs if kind == "$OUT" else vm.program.inputs
    return names.get(n, "")


def _io_read(vm: VM, kind: str, n: int, name: str) -> bool:
    if kind == "$OUT":
        return vm.motion.outputs.get(n, False)
    return vm.motion.input(n, name or _io_name(vm, kind, n))


def _wait_for(vm: VM, cond: Fn, t: Token) -> None:
    if boolean(cond(vm), "WAIT FOR"):
        return
    raise ProgramError(
        "WAIT FOR waits for a condition that is false and that nothing in this cell can "
        "change (the simulator has no signals for it)"
    )


def _st(vm: VM) -> dict[str, int]:
    s, t = kuka_status_turn(vm.motion.model, vm.motion.joints())
    return {"S": s, "T": t}


def _zone(vm: VM, approx: str | None) -> float:
    if approx == "C_DIS":
        return vm.lang["cdis"] / 1000.0
    if approx == "C_PTP":
        return vm.lang["cptp"] / 1000.0  # n % read as n mm (module doc)
    return 0.0


def _settings(vm: VM) -> None:
    m = vm.motion
    m.override = vm.lang["ov"] / 100.0
    axes = vm.lang["vel_axis"]
    if max(axes) - min(axes) > 1e-9:
        raise ProgramError(
            f"$VEL_AXIS differs between axes ({', '.join(f'{v:g}' for v in axes)} %): the "
            "simulator scales every joint's limits by one factor"
        )
    m.joint_fraction = axes[0] / 100.0
    m.trapezoid = None


def _move(vm: VM, kind: str, target: Any, via: Any, approx: str | None) -> None:
    if not isinstance(target, dict):
        raise ProgramError(f"{kind} needs a position or axis structure, got {target!r}")
    _settings(vm)
    m = vm.motion
    zone = _zone(vm, approx)
    q = m.joints()
    if kind == "PTP" and any(k.startswith("A") and k[1:].isdigit() for k in target):
        m.move_joints(joints_of(target, q, "the PTP target"), zone)
        return
    full = {**pose_dict(m.program_pose(q)), **target}
    T = program_pose(full, f"the {kind} target")
    if kind == "PTP":
        s, t = full.get("S") if "S" in target else None, full.get("T") if "T" in target else None
        if s is None and t is None:
            m.move_pose(T, zone, None, None, "PTP target")
        else:

            def key(robot: Any, v: Any) -> object:
                st = kuka_status_turn(robot, v)
                return (st[0] if s is not None else None, st[1] if t is not None else None)

            want = (
                int(number(s)) if s is not None else None,
                int(number(t)) if t is not None else None,
            )
            m.move_pose(T, zone, key, want, "PTP target (S, T)")
        return
    v, a = vm.lang["vel_cp"], vm.lang["acc_cp"]
    if v <= 0 or a <= 0:
        raise ProgramError(f"{kind} needs $VEL.CP and $ACC.CP > 0")
    if kind == "LIN":
        m.move_linear(T, v, a, zone)
        return
    if not isinstance(via, dict):
        raise ProgramError("CIRC needs an auxiliary position structure")
    V = program_pose({**full, **via}, "the CIRC auxiliary point")
    m.move_circular(V, T, v, a, zone)


def _bas(vm: VM, what: str, arg: Any) -> None:
    lang = vm.lang
    if what == "#INITMOV":
        lang.update(
            vel_cp=DEF_VEL_CP, acc_cp=DEF_ACC_CP, vel_axis=[100.0] * 6, acc_axis=[100.0] * 6
        )
    elif what in ("#VEL_PTP", "#PTP_PARAMS"):
        x = number(arg, f"BAS({what})'s percentage")
        if not 0 < x <= 100:
            raise ProgramError(f"BAS({what}, {x:g}): the speed must be in (0, 100] %")
        lang["vel_axis"] = [x] * 6
        if what == "#PTP_PARAMS":
            pdat = vm.vars.get("PDAT_ACT") or {}
            if "APO_DIST" in pdat:
                lang["cdis"] = number(pdat["APO_DIST"], "PDAT_ACT.APO_DIST")
    elif what == "#ACC_PTP":
        lang["acc_axis"] = [number(arg)] * 6
    elif what in ("#VEL_CP", "#CP_PARAMS"):
        x = number(arg, f"BAS({what})'s speed (m/s)")
        if x <= 0:
            raise ProgramError(f"BAS({what}, {x:g}): the speed must be > 0 m/s")
        lang["vel_cp"] = x
        if what == "#CP_PARAMS":
            ldat = vm.vars.get("LDAT_ACT") or {}
            if "APO_DIST" in ldat:
                lang["cdis"] = number(ldat["APO_DIST"], "LDAT_ACT.APO_DIST")
    elif what == "#ACC_CP":
        x = number(arg, "BAS(#ACC_CP)'s percentage")
        lang["acc_cp"] = DEF_ACC_CP * x / 100.0
    elif what in ("#TOOL", "#BASE"):
        table = vm.vars.get("TOOL_DATA" if what == "#TOOL" else "BASE_DATA")
        frame = None
        if isinstance(table, list):
            frame = table[_index(table, arg, what)]
        if what == "#TOOL":
            vm.motion.tcp = None if not frame else tcp_of_tool(frame)
        else:
            vm.motion.base = np.eye(4) if not frame else frame_matrix(frame, "BASE_DATA")
