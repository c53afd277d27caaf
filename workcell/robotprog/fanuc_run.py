"""What FANUC TP statements do when they run (the run-time half of
:mod:`workcell.robotprog.read_fanuc`): operators, registers, frames and motions.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from workcell.errors import ProgramError
from workcell.robotprog.configs import fanuc_config, fanuc_from_joints, fanuc_to_joints
from workcell.robotprog.exprs import ARITH, COMPARE, Fn, boolean, number
from workcell.robotprog.fanuc import wpr
from workcell.robotprog.rotations import from_zyx
from workcell.robotprog.runtime import VM
from workcell.robotprog.writing import DEFAULT_TOOL_ACCELERATION


class Position(dict):  # type: ignore[type-arg]
    """A position: Cartesian (X, Y, Z mm; W, P, R deg; config; uf; ut) or joint
    (J1..J6, the controller's deg)."""


__all__ = ["BINARY", "UNARY", "Position"]


BINARY: dict[str, tuple[int, Any]] = {
    "OR": (1, lambda a, b: boolean(a, "OR") or boolean(b, "OR")),
    "AND": (2, lambda a, b: boolean(a, "AND") and boolean(b, "AND")),
    "=": (3, lambda a, b: COMPARE["="](a, b)), "<>": (3, COMPARE["<>"]),
    "<": (3, COMPARE["<"]), ">": (3, COMPARE[">"]), "<=": (3, COMPARE["<="]),
    ">=": (3, COMPARE[">="]),
    "+": (4, lambda a, b: _plus(a, b, 1.0)), "-": (4, lambda a, b: _plus(a, b, -1.0)),
    "*": (5, ARITH["*"]), "/": (5, ARITH["/"]),
}  # fmt: skip
UNARY: dict[str, tuple[int, Any]] = {
    "-": (6, lambda a: -number(a)),
    "!": (6, lambda a: not boolean(a, "!")),
}
_CART = ("X", "Y", "Z", "W", "P", "R")


def _constant(v: float) -> Fn:
    return lambda vm: v


def _plus(a: Any, b: Any, sign: float) -> Any:
    if isinstance(a, Position) and isinstance(b, Position):
        keys = _CART if "X" in a else tuple(k for k in a if k.startswith("J"))
        out = Position(a)
        for k in keys:
            if k not in b:
                raise ProgramError("adding a joint and a Cartesian position")
            out[k] = a[k] + sign * b[k]
        return out
    return ARITH["+" if sign > 0 else "-"](a, b)


def _name(vm: VM, n: int, kind: str) -> str:
    names = vm.program.outputs if kind in ("DO", "RO") else vm.program.inputs
    return names.get(n, "")


def _io(vm: VM, kind: str, n: int, name: str) -> bool:
    if kind in ("DO", "RO"):
        return vm.motion.outputs.get(n, False)
    return vm.motion.input(n, name or _name(vm, n, kind))


def _r(vm: VM, n: int) -> float:
    return vm.lang.setdefault("R", {}).get(n, 0.0)


def _set_r(vm: VM, n: int, v: float) -> None:
    vm.lang.setdefault("R", {})[n] = v


def _pr(vm: VM, n: int) -> Position:
    pr = vm.lang.setdefault("PR", {})
    if n not in pr:
        raise ProgramError(f"PR[{n}] has no value (position registers are set on the controller)")
    return Position(pr[n])


def _set_pr(vm: VM, n: int, v: Any) -> None:
    if not isinstance(v, Position):
        raise ProgramError("a position register takes a position")
    vm.lang.setdefault("PR", {})[n] = Position(v)


def _element_key(pos: Position, i: int) -> str:
    keys = _CART if "X" in pos else tuple(f"J{k}" for k in range(1, 10) if f"J{k}" in pos)
    if not 1 <= i <= len(keys):
        raise ProgramError(f"element {i} is outside 1 to {len(keys)}")
    return keys[i - 1]


def _pr_element(vm: VM, n: int, i: int) -> float:
    pos = _pr(vm, n)
    return float(pos[_element_key(pos, i)])


def _set_pr_element(vm: VM, n: int, i: int, v: Any) -> None:
    pr = vm.lang.setdefault("PR", {})
    pos = pr.setdefault(n, Position({k: 0.0 for k in _CART} | {"uf": 0, "ut": 0}))
    pos[_element_key(pos, i)] = number(v, f"PR[{n},{i}]")


def _matrix(pos: Position) -> np.ndarray:
    T = from_zyx(pos["R"], pos["P"], pos["W"])
    T[:3, 3] = [pos["X"] / 1000.0, pos["Y"] / 1000.0, pos["Z"] / 1000.0]
    return T


def _current(vm: VM, which: str) -> Position:
    m = vm.motion
    q = m.joints()
    if which == "JPOS":
        j = np.degrees(fanuc_from_joints(m.model, q))
        return Position({f"J{i + 1}": float(v) for i, v in enumerate(j)})
    T = m.program_pose(q)
    w, pp, r = wpr(T)
    flags, *turns = fanuc_config(m.model, q)
    out = Position(
        {"X": 1000 * T[0, 3], "Y": 1000 * T[1, 3], "Z": 1000 * T[2, 3], "W": w, "P": pp, "R": r}
    )
    out["config"] = (flags, *turns)
    out["uf"], out["ut"] = vm.lang.get("uf", 0), vm.lang.get("ut", 0)
    return out


def _set_frame_number(vm: VM, key: str, v: Any) -> None:
    n = number(v, key)
    if n != int(n) or n < 0:
        raise ProgramError(f"a frame number must be a whole number >= 0, got {n:g}")
    vm.lang[key] = int(n)
    _apply_frames(vm)


def _define_frame(vm: VM, key: str, n: int, v: Any) -> None:
    if not isinstance(v, Position) or "X" not in v:
        raise ProgramError("a frame takes a Cartesian position")
    vm.lang.setdefault(key, {})[n] = _matrix(v)
    _apply_frames(vm)


def _apply_frames(vm: VM) -> None:
    m = vm.motion
    uf, ut = vm.lang.get("uf", 0), vm.lang.get("ut", 0)
    m.base = vm.lang.get("uframes", {}).get(uf, np.eye(4)) if uf else np.eye(4)
    tools = vm.lang.get("utools", {})
    m.tcp = np.eye(4) if ut == 0 else tools.get(ut)


def _override(vm: VM, v: Any) -> None:
    x = number(v, "OVERRIDE")
    if not 0 < x <= 100:
        raise ProgramError(f"OVERRIDE must be in (0, 100] %, got {x:g}")
    vm.lang["ov"] = x / 100.0


def _resolve(vm: VM, target: Any) -> Position:
    kind, n, pos = target
    if kind == "PR":
        return _pr(vm, n)
    uf, ut = vm.lang.get("uf", 0), vm.lang.get("ut", 0)
    if (pos["uf"], pos["ut"]) != (uf, ut) and "X" in pos:
        raise ProgramError(
            f"P[{n}] was taught in UF {pos['uf']}, UT {pos['ut']}; the active frames are UF "
            f"{uf}, UT {ut}"
        )
    return Position(pos)


def _move(vm: VM, kind: str, target: Any, via: Any, speed: Fn, unit: str, cnt: Fn, acc: Fn | None,
          offset: Fn | None) -> None:  # fmt: skip
    m = vm.motion
    _apply_frames(vm)
    m.trapezoid = None
    m.override = vm.lang.get("ov", 1.0)
    zone = number(cnt(vm), "CNT") / 1000.0
    if zone < 0 or zone > 0.1:
        raise ProgramError(f"CNT must be in 0 to 100, got {zone * 1000:g}")
    pos = _resolve(vm, target)
    off = None
    if offset is not None:
        o = offset(vm)
        if not isinstance(o, Position) or "X" not in o:
            raise ProgramError("Offset takes a Cartesian position register")
        off = _matrix(o)
    v = number(speed(vm), "the speed")
    if v <= 0:
        raise ProgramError("the speed must be > 0")
    if kind == "J":
        if v > 100:
            raise ProgramError(f"a joint speed is at most 100 %, got {v:g}")
        m.joint_fraction = v / 100.0
        if "J1" in pos:
            if off is not None:
                raise ProgramError("Offset applies to Cartesian positions")
            j = np.radians([pos[f"J{i + 1}"] for i in range(len(m.joints()))])
            m.move_joints(fanuc_to_joints(m.model, j), zone)
            return
        T = _matrix(pos) if off is None else off @ _matrix(pos)
        if "config" in pos:
            m.move_pose(T, zone, fanuc_config, pos["config"], f"{target[0]}[{target[1]}] (CONFIG)")
        else:
            m.move_pose(T, zone, None, None, f"{target[0]}[{target[1]}]")
        return
    scale = {"mm/sec": 1e-3, "cm/min": 1e-2 / 60.0, "inch/min": 0.0254 / 60.0}.get(unit)
    if scale is None:
        raise ProgramError(f"a speed in {unit} is not supported for {kind} by workcell's reader")
    a = DEFAULT_TOOL_ACCELERATION * (1.0 if acc is None else number(acc(vm), "ACC") / 100.0)
    if a <= 0:
        raise ProgramError("ACC must be > 0")
    if "J1" in pos:
        raise ProgramError(f"{kind} to a joint position is not supported by workcell's reader")
    T = _matrix(pos) if off is None else off @ _matrix(pos)
    if kind == "L":
        m.move_linear(T, v * scale, a, zone)
        return
    vpos = _resolve(vm, via)
    if "J1" in vpos:
        raise ProgramError("the via point of C must be Cartesian")
    m.move_circular(_matrix(vpos), T, v * scale, a, zone)
