"""What URScript does when it runs (the run-time half of
:mod:`workcell.robotprog.read_urscript`): operators and the built-in functions.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from workcell.errors import ProgramError
from workcell.robotprog.exprs import ARITH, COMPARE, Fn, boolean, number
from workcell.robotprog.rotations import from_rotvec, rotvec
from workcell.robotprog.runtime import VM
from workcell.robotprog.source import Token
from workcell.spatial import invert

SYNC = 0.002  # s: one controller cycle (e-Series, 500 Hz)


class Pose(list):  # type: ignore[type-arg]
    """A URScript pose: [x, y, z, rx, ry, rz] (m, rotation vector in rad)."""


def pose_matrix(p: Any, what: str = "a pose") -> np.ndarray:
    if not isinstance(p, list) or len(p) != 6:
        raise ProgramError(f"{what} must be a pose p[x, y, z, rx, ry, rz]")
    v = [number(x, what) for x in p]
    T = from_rotvec(v[3:])
    T[:3, 3] = v[:3]
    return T


def pose_of(T: np.ndarray) -> Pose:
    return Pose([*(float(x) for x in T[:3, 3]), *(float(x) for x in rotvec(T))])


def _joints(v: Any, n: int, what: str) -> np.ndarray:
    if not isinstance(v, list) or isinstance(v, Pose) or len(v) != n:
        raise ProgramError(f"{what} must be a list of {n} joint values (rad)")
    return np.array([number(x, what) for x in v])


__all__ = ["BINARY", "BUILTINS", "SYNC", "UNARY", "Pose", "pose_matrix", "pose_of"]


def _index_of(base: Fn, idx: Fn, t: Token) -> Fn:
    def get(vm: VM) -> Any:
        v = base(vm)
        if not isinstance(v, list):
            raise ProgramError("only lists and poses can be indexed")
        i = int(number(idx(vm), "an index"))
        if not 0 <= i < len(v):
            raise ProgramError(f"index {i} is outside 0 to {len(v) - 1}")
        return v[i]

    return get


def _name(vm: VM, n: int) -> str:
    return vm.program.inputs.get(n, "")


def _add(a: Any, b: Any) -> Any:
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        if isinstance(a, Pose) or isinstance(b, Pose):
            raise ProgramError("poses are added with pose_add or pose_trans, not +")
        return [ARITH["+"](x, y) for x, y in zip(a, b, strict=True)]
    return ARITH["+"](a, b)


BINARY: dict[str, tuple[int, Any]] = {
    "OR": (1, lambda a, b: boolean(a, "or") or boolean(b, "or")),
    "AND": (2, lambda a, b: boolean(a, "and") and boolean(b, "and")),
    "==": (4, lambda a, b: a == b if isinstance(a, list) or isinstance(b, list) else COMPARE["=="](a, b)),
    "!=": (4, lambda a, b: a != b if isinstance(a, list) or isinstance(b, list) else COMPARE["!="](a, b)),
    "<": (4, COMPARE["<"]), ">": (4, COMPARE[">"]), "<=": (4, COMPARE["<="]), ">=": (4, COMPARE[">="]),
    "+": (5, _add), "-": (5, ARITH["-"]), "*": (6, ARITH["*"]), "/": (6, ARITH["/"]),
    "%": (6, lambda a, b: math.fmod(number(a), number(b)) if number(b) != 0 else ARITH["/"](1, 0)),
}  # fmt: skip
UNARY: dict[str, tuple[int, Any]] = {
    "NOT": (3, lambda a: not boolean(a, "not")),
    "-": (7, lambda a: -number(a)),
}
# name: (positional parameters in order, their defaults (None: required))
BUILTINS: dict[str, tuple[tuple[str, ...], tuple[Any, ...]]] = {
    "movej": (("q", "a", "v", "t", "r"), (None, 1.4, 1.05, 0.0, 0.0)),
    "movel": (("pose", "a", "v", "t", "r"), (None, 1.2, 0.25, 0.0, 0.0)),
    "movec": (("pose_via", "pose_to", "a", "v", "r", "mode"), (None, None, 1.2, 0.25, 0.0, 0)),
    "set_tcp": (("pose",), (None,)),
    "set_standard_digital_out": (("n", "b"), (None, None)),
    "set_digital_out": (("n", "b"), (None, None)),
    "get_standard_digital_in": (("n",), (None,)),
    "get_digital_in": (("n",), (None,)),
    "sleep": (("t",), (None,)),
    "sync": ((), ()),
    "textmsg": (("s1", "s2"), (None, "")),
    "pose_trans": (("p_from", "p_from_to"), (None, None)),
    "pose_add": (("p_1", "p_2"), (None, None)),
    "pose_inv": (("p_from",), (None,)),
    "get_inverse_kin": (
        ("x", "qnear", "maxPositionError", "maxOrientationError", "tcp"),
        (None, None, 1e-10, 1e-10, None),
    ),
    "get_actual_joint_positions": ((), ()),
    "get_actual_tcp_pose": ((), ()),
    "d2r": (("d",), (None,)),
    "r2d": (("r",), (None,)),
    "sqrt": (("f",), (None,)),
    "sin": (("f",), (None,)),
    "cos": (("f",), (None,)),
    "norm": (("a",), (None,)),
}


def _builtin(
    vm: VM,
    name: str,
    spec: tuple[tuple[str, ...], tuple[Any, ...]],
    args: list[Any],
    kw: dict[str, Any],
) -> Any:
    params, defaults = spec
    if len(args) > len(params):
        raise ProgramError(f"{name} takes at most {len(params)} arguments, got {len(args)}")
    unknown = sorted(set(kw) - set(params))
    if unknown:
        raise ProgramError(
            f"{name} has no argument {unknown[0]}; its arguments: {', '.join(params)}"
        )
    a = dict(zip(params, defaults, strict=True))
    a.update(zip(params, args, strict=False))
    a.update(kw)
    missing = [k for k in params if a[k] is None and k not in ("qnear", "tcp")]
    if missing:
        raise ProgramError(f"{name} needs {missing[0]}")
    m = vm.motion
    n = len(m.joints())
    if name in ("movej", "movel", "movec") and number(a.get("t", 0.0), "t") != 0:
        raise ProgramError(f"{name} by time (t=) is not supported by workcell's URScript reader")
    if name == "movej":
        v, acc, r = (number(a[k], k) for k in ("v", "a", "r"))
        if v <= 0 or acc <= 0 or r < 0:
            raise ProgramError("movej needs v > 0, a > 0 and r >= 0")
        m.trapezoid, m.override, m.joint_fraction = (v, acc), 1.0, 1.0
        if isinstance(a["q"], Pose):
            m.move_pose(pose_matrix(a["q"], "movej's pose"), r, None, None, "movej pose")
        else:
            m.move_joints(_joints(a["q"], n, "movej's q"), r)
        return None
    if name in ("movel", "movec"):
        v, acc, r = (number(a[k], k) for k in ("v", "a", "r"))
        if v <= 0 or acc <= 0 or r < 0:
            raise ProgramError(f"{name} needs v > 0, a > 0 and r >= 0")
        m.trapezoid, m.override = None, 1.0
        if name == "movel":
            target = a["pose"]
            if not isinstance(target, Pose):  # joint positions: the pose they give
                target = pose_of(m.program_pose(_joints(target, n, "movel's target")))
            m.move_linear(pose_matrix(target, "movel's pose"), v, acc, r)
            return None
        if number(a["mode"], "mode") != 0:
            raise ProgramError(
                "movec mode=1 (fixed orientation) is not supported by workcell's URScript reader"
            )
        m.move_circular(
            pose_matrix(a["pose_via"], "movec's via"),
            pose_matrix(a["pose_to"], "movec's end"),
            v,
            acc,
            r,
        )
        return None
    if name == "set_tcp":
        m.tcp = pose_matrix(a["pose"], "set_tcp's pose")
        return None
    if name in ("set_standard_digital_out", "set_digital_out"):
        k = int(number(a["n"], "the output number"))
        m.set_output(k, vm.program.outputs.get(k, ""), boolean(a["b"], "the output's value"))
        return None
    if name in ("get_standard_digital_in", "get_digital_in"):
        k = int(number(a["n"], "the input number"))
        return m.input(k, _name(vm, k))
    if name in ("sleep", "sync"):
        m.dwell(SYNC if name == "sync" else a["t"], name)
        return None
    if name == "textmsg":
        return None
    if name == "pose_trans":
        return pose_of(pose_matrix(a["p_from"]) @ pose_matrix(a["p_from_to"]))
    if name == "pose_add":
        A, B = pose_matrix(a["p_1"]), pose_matrix(a["p_2"])
        T = np.eye(4)
        T[:3, :3] = B[:3, :3] @ A[:3, :3]
        T[:3, 3] = A[:3, 3] + B[:3, 3]
        return pose_of(T)
    if name == "pose_inv":
        return pose_of(invert(pose_matrix(a["p_from"])))
    if name == "get_inverse_kin":
        from workcell.robotprog.configs import solutions

        Tb = m.robot_pose(pose_matrix(a["x"], "get_inverse_kin's pose"))
        near = m.joints() if a["qnear"] is None else _joints(a["qnear"], n, "qnear")
        sols = solutions(m.model, Tb, near)
        if not sols:
            raise ProgramError("get_inverse_kin: the pose is out of reach")
        return [float(x) for x in min(sols, key=lambda s: float(np.abs(s - near).max()))]
    if name == "get_actual_joint_positions":
        return [float(x) for x in m.joints()]
    if name == "get_actual_tcp_pose":
        return pose_of(m.program_pose(m.joints()))
    if name in ("d2r", "r2d"):
        x = number(a["d" if name == "d2r" else "r"])
        return math.radians(x) if name == "d2r" else math.degrees(x)
    if name in ("sqrt", "sin", "cos"):
        x = number(a["f"])
        if name == "sqrt" and x < 0:
            raise ProgramError("sqrt of a negative number")
        return {"sqrt": math.sqrt, "sin": math.sin, "cos": math.cos}[name](x)
    if name == "norm":
        v = a["a"]
        return math.sqrt(sum(number(x) ** 2 for x in v)) if isinstance(v, list) else abs(number(v))
    raise ProgramError(f"{name} is not supported")  # pragma: no cover (every builtin is above)
