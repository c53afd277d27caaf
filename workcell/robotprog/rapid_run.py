"""What RAPID instructions and functions do when they run (the run-time half of
:mod:`workcell.robotprog.read_rapid`): operators, data records, ``Offs``, ``RelTool``,
frames and the motion instructions.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from workcell.errors import ProgramError
from workcell.robotprog.configs import abb_confdata
from workcell.robotprog.exprs import ARITH, COMPARE, Fn, boolean, number
from workcell.robotprog.rotations import quat_wxyz
from workcell.robotprog.runtime import VM
from workcell.robotprog.source import Loc, Token
from workcell.spatial import matrix_from_quat, translation

RECORDS: dict[str, tuple[tuple[str, str], ...]] = {
    "pos": (("x", "num"), ("y", "num"), ("z", "num")),
    "orient": (("q1", "num"), ("q2", "num"), ("q3", "num"), ("q4", "num")),
    "pose": (("trans", "pos"), ("rot", "orient")),
    "confdata": (("cf1", "num"), ("cf4", "num"), ("cf6", "num"), ("cfx", "num")),
    "extjoint": tuple((f"e{c}", "num") for c in "abcdef"),
    "robjoint": tuple((f"rax_{i}", "num") for i in range(1, 7)),
    "robtarget": (("trans", "pos"), ("rot", "orient"), ("robconf", "confdata"), ("extax", "extjoint")),
    "jointtarget": (("robax", "robjoint"), ("extax", "extjoint")),
    "loaddata": (("mass", "num"), ("cog", "pos"), ("aom", "orient"), ("ix", "num"), ("iy", "num"), ("iz", "num")),
    "tooldata": (("robhold", "bool"), ("tframe", "pose"), ("tload", "loaddata")),
    "wobjdata": (("robhold", "bool"), ("ufprog", "bool"), ("ufmec", "string"), ("uframe", "pose"), ("oframe", "pose")),
    "speeddata": (("v_tcp", "num"), ("v_ori", "num"), ("v_leax", "num"), ("v_reax", "num")),
    "zonedata": (("finep", "bool"), ("pzone_tcp", "num"), ("pzone_ori", "num"), ("pzone_eax", "num"),
                 ("zone_ori", "num"), ("zone_leax", "num"), ("zone_reax", "num")),
}  # fmt: skip


ATOMS = {"num", "bool", "string", "dionum", "signaldo", "signaldi"}


_IDENTITY_POSE = [[0, 0, 0], [1, 0, 0, 0]]


SPEEDS = (5, 10, 20, 30, 40, 50, 60, 80, 100, 150, 200, 300, 400, 500, 600, 800, 1000, 1500,
          2000, 2500, 3000, 4000, 5000, 6000, 7000)  # fmt: skip


ZONES = (0, 1, 5, 10, 15, 20, 30, 40, 50, 60, 80, 100, 150, 200)


def record(typ: str, v: Any, what: str) -> Any:
    """An aggregate (nested lists) as a record of RAPID type ``typ`` (dicts by field)."""
    if typ in ATOMS:
        if typ == "num":
            return number(v, f"{what} (num)")
        if typ == "bool":
            return boolean(v, what)
        return v
    fields = RECORDS[typ]
    if isinstance(v, dict):
        return v
    if not isinstance(v, list) or len(v) != len(fields):
        raise ProgramError(f"{what} must be a {typ} of {len(fields)} components")
    return {name: record(t, x, f"{what}.{name}") for (name, t), x in zip(fields, v, strict=True)}


def _predefined() -> dict[str, tuple[str, Any]]:
    pre: dict[str, tuple[str, Any]] = {
        "tool0": ("tooldata", record("tooldata", [True, _IDENTITY_POSE, [0.001, [0, 0, 0.001], [1, 0, 0, 0], 0, 0, 0]], "tool0")),
        "wobj0": ("wobjdata", record("wobjdata", [False, True, "", _IDENTITY_POSE, _IDENTITY_POSE], "wobj0")),
        "vmax": ("speeddata", record("speeddata", [10000, 500, 5000, 1000], "vmax")),
        "fine": ("zonedata", record("zonedata", [True, 0, 0, 0, 0, 0, 0], "fine")),
    }  # fmt: skip
    for v in SPEEDS:
        pre[f"v{v}"] = ("speeddata", record("speeddata", [v, 500, 5000, 1000], f"v{v}"))
    for z in ZONES:
        o, r = 1.5 * z if z else 0.3, 0.15 * z if z else 0.03
        pre[f"z{z}"] = (
            "zonedata",
            record("zonedata", [False, z if z else 0.3, o, o, r, o, r], f"z{z}"),
        )
    return pre


PREDEFINED = _predefined()


def pose_matrix(p: dict[str, Any]) -> np.ndarray:
    """The 4x4 (m) of a RAPID pose-like record (trans mm, rot quaternion w, x, y, z)."""
    t, r = p["trans"], p["rot"]
    q = [number(r[k]) for k in ("q1", "q2", "q3", "q4")]
    n = math.sqrt(sum(x * x for x in q))
    if not 0.9 < n < 1.1:
        raise ProgramError(f"the quaternion {q} is not a unit quaternion (norm {n:.6g})")
    return matrix_from_quat(q, [number(t[k]) / 1000.0 for k in ("x", "y", "z")])


def pose_record(T: np.ndarray) -> dict[str, Any]:
    w, x, y, z = quat_wxyz(T)
    return {
        "trans": {"x": 1000.0 * T[0, 3], "y": 1000.0 * T[1, 3], "z": 1000.0 * T[2, 3]},
        "rot": {"q1": w, "q2": x, "q3": y, "q4": z},
    }


__all__ = [
    "BINARY",
    "INSTRUCTIONS",
    "PREDEFINED",
    "RECORDS",
    "UNARY",
    "pose_matrix",
    "pose_record",
    "record",
]


MATH = {
    "ABS": abs, "SQRT": math.sqrt, "SIN": lambda d: math.sin(math.radians(d)),
    "COS": lambda d: math.cos(math.radians(d)), "TAN": lambda d: math.tan(math.radians(d)),
    "ROUND": round, "TRUNC": math.trunc,
}  # fmt: skip
BINARY: dict[str, tuple[int, Any]] = {
    "=": (1, COMPARE["="]), "<>": (1, COMPARE["<>"]), "<": (1, COMPARE["<"]),
    ">": (1, COMPARE[">"]), "<=": (1, COMPARE["<="]), ">=": (1, COMPARE[">="]),
    "OR": (2, lambda a, b: boolean(a, "OR") or boolean(b, "OR")),
    "XOR": (2, lambda a, b: boolean(a, "XOR") != boolean(b, "XOR")),
    "AND": (3, lambda a, b: boolean(a, "AND") and boolean(b, "AND")),
    "+": (4, ARITH["+"]), "-": (4, ARITH["-"]),
    "*": (5, ARITH["*"]), "/": (5, ARITH["/"]),
    "DIV": (5, lambda a, b: _intdiv(a, b, "DIV")),
    "MOD": (5, lambda a, b: _intdiv(a, b, "MOD")),
}  # fmt: skip
UNARY: dict[str, tuple[int, Any]] = {
    "NOT": (6, lambda a: not boolean(a, "NOT")),
    "-": (6, lambda a: -number(a)),
    "+": (6, lambda a: number(a)),
}
# instruction: (positional arguments, optional arguments accepted)
INSTRUCTIONS: dict[str, tuple[int, set[str]]] = {
    "MOVEABSJ": (4, {"WOBJ"}), "MOVEJ": (4, {"WOBJ"}), "MOVEL": (4, {"WOBJ"}),
    "MOVEC": (5, {"WOBJ"}), "SETDO": (2, set()), "WAITDI": (2, set()),
    "WAITTIME": (1, set()), "VELSET": (2, set()), "ACCSET": (2, set()),
    "PATHACCLIM": (2, {"ACCMAX", "DECELMAX"}), "CONFJ": (0, {"ON", "OFF"}),
    "CONFL": (0, {"ON", "OFF"}), "TPWRITE": (1, set()),
}  # fmt: skip


def _intdiv(a: Any, b: Any, op: str) -> float:
    x, y = int(number(a)), int(number(b))
    if y == 0:
        raise ProgramError(f"{op} by zero")
    return float(x // y if op == "DIV" else x % y)


def _component_of(base: Fn, c: Token) -> Fn:
    return lambda vm: _component(base(vm), c.text.lower(), c.text)


def _element_of(base: Fn, idx: Fn, what: str) -> Fn:
    return lambda vm: _element(base(vm), idx(vm), what)


def _setup(vm: VM) -> None:
    vm.lang.update(confj=True, acc=None)


def _run_data(vm: VM, routine: Any) -> None:
    vm.program.routines["#DATA"] = routine
    vm.call("#DATA", Loc(vm.program.path, 1, 1), 0)


def _component(v: Any, name: Any, what: str) -> Any:
    if not isinstance(v, dict) or name not in v:
        raise ProgramError(f"{what} has no component {name}")
    return v[name]


def _array_index(v: Any, i: Any, what: str) -> int:
    if not isinstance(v, list):
        raise ProgramError(f"{what} is not an array")
    k = int(number(i, "an index"))
    if not 1 <= k <= len(v):
        raise ProgramError(f"{what}{{{k}}} is outside the array (1 to {len(v)})")
    return k - 1


def _element(v: Any, i: Any, what: str) -> Any:
    return v[_array_index(v, i, what)]


def _offs(p: Any, dx: Any, dy: Any, dz: Any) -> Any:
    out = {**record("robtarget", p, "Offs's point")}
    t = out["trans"]
    out["trans"] = {"x": number(t["x"]) + number(dx), "y": number(t["y"]) + number(dy),
                    "z": number(t["z"]) + number(dz)}  # fmt: skip
    return out


def _reltool(args: list[Any], rot: dict[str, Any]) -> Any:
    p = record("robtarget", args[0], "RelTool's point")
    T = pose_matrix(p)
    d = translation(*(number(a) / 1000.0 for a in args[1:4]))
    from workcell.robotprog.rotations import from_zyx

    R = from_zyx(number(rot.get("RZ", 0.0)), number(rot.get("RY", 0.0)), number(rot.get("RX", 0.0)))
    return {**p, **pose_record(T @ d @ R)}


def _crobt(vm: VM) -> Any:
    m = vm.motion
    q = m.joints()
    cf = abb_confdata(m.model, q)
    return {**pose_record(m.program_pose(q)),
            "robconf": dict(zip(("cf1", "cf4", "cf6", "cfx"), cf, strict=True)),
            "extax": {f"e{c}": 9e9 for c in "abcdef"}}  # fmt: skip


def _signal(vm: VM, name: str) -> int:
    for n, s in vm.program.outputs.items():
        if s.lower() == name.lower():
            return n
    for n, s in vm.program.inputs.items():
        if s.lower() == name.lower():
            return n
    return 0


def _dinput(vm: VM, name: str) -> float:
    return 1.0 if vm.motion.input(_signal(vm, name), name) else 0.0


def _frames(vm: VM, tool: Any, wobj: Any) -> None:
    m = vm.motion
    tool = record("tooldata", tool, "the tool")
    m.tcp = pose_matrix(tool["tframe"])
    if not boolean(tool["robhold"], "the tool's robhold"):
        raise ProgramError("a stationary tool (robhold FALSE) is not supported")
    if wobj is None:
        m.base = np.eye(4)
        return
    w = record("wobjdata", wobj, "the work object")
    if boolean(w["robhold"], "the work object's robhold") or not boolean(w["ufprog"], "ufprog"):
        raise ProgramError(
            "a work object held by the robot or moved by a mechanical unit is not supported"
        )
    m.base = pose_matrix(w["uframe"]) @ pose_matrix(w["oframe"])


def _instruction(vm: VM, u: str, args: list[Fn], opts: dict[str, Fn | None]) -> None:
    m = vm.motion
    a = [f(vm) for f in args]
    if u in ("MOVEABSJ", "MOVEJ", "MOVEL", "MOVEC"):
        wobj = opts["WOBJ"](vm) if opts.get("WOBJ") is not None else None  # type: ignore[misc]
        *points, speed, zone, tool = a
        _frames(vm, tool, wobj if u != "MOVEABSJ" else None)
        sp = record("speeddata", speed, "the speed")
        zd = record("zonedata", zone, "the zone")
        z = 0.0 if boolean(zd["finep"], "finep") else number(zd["pzone_tcp"]) / 1000.0
        m.trapezoid = None
        m.joint_fraction = 1.0
        m.override = vm.lang.get("velset", 1.0)
        if u == "MOVEABSJ":
            j = record("jointtarget", points[0], "the joint target")["robax"]
            q = np.radians([number(j[f"rax_{i + 1}"]) for i in range(len(m.joints()))])
            m.move_joints(q, z)
            return
        targets = [record("robtarget", p, "the target") for p in points]
        T = pose_matrix(targets[-1])
        if u == "MOVEJ":
            c = targets[-1]["robconf"]
            want = tuple(int(number(c[k])) for k in ("cf1", "cf4", "cf6", "cfx"))
            key = abb_confdata if vm.lang["confj"] else None
            m.move_pose(T, z, key, want, "MoveJ target (confdata)")
            return
        v = number(sp["v_tcp"], "v_tcp") / 1000.0
        acc = vm.lang["acc"] or 1.2
        if v <= 0:
            raise ProgramError("the speed's v_tcp must be > 0")
        if u == "MOVEL":
            m.move_linear(T, v, acc, z)
        else:
            m.move_circular(pose_matrix(targets[0]), T, v, acc, z)
    elif u == "SETDO":
        name = args_name(vm, a[0])
        m.set_output(_signal(vm, name), name, number(a[1]) != 0)
    elif u == "WAITDI":
        name = args_name(vm, a[0])
        m.wait_input(_signal(vm, name), name, number(a[1]) != 0)
    elif u == "WAITTIME":
        m.dwell(a[0], "WaitTime")
    elif u == "VELSET":
        ov = number(a[0], "VelSet's override")
        if not 0 < ov <= 100:
            raise ProgramError(f"VelSet's override must be in (0, 100] %, got {ov:g}")
        vm.lang["velset"] = ov / 100.0
    elif u == "PATHACCLIM":
        on = boolean(a[0], "PathAccLim")
        acc = opts.get("ACCMAX")
        vm.lang["acc"] = number(acc(vm), "AccMax") if on and acc is not None else None
    elif u in ("CONFJ", "CONFL"):
        if ("ON" in opts) == ("OFF" in opts):
            raise ProgramError(f"{u.title()} takes \\On or \\Off")
        if u == "CONFJ":
            vm.lang["confj"] = "ON" in opts


def args_name(vm: VM, v: Any) -> str:
    if isinstance(v, str):
        return v
    raise ProgramError("a signal must be named")
