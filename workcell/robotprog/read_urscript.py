"""Universal Robots URScript: the reader (``.script``).

Read: ``#`` comments, ``def name():`` ... ``end`` (the statements outside any ``def`` run,
else the file's only or first ``def``), assignments (``global``/``local`` too) with
arithmetic, lists, poses ``p[x, y, z, rx, ry, rz]`` and indexing, ``if``/``elif``/``else``,
``while`` (bounded by the work budget; ``while not <input>: sync() end`` is an input
wait), calls of the file's functions, ``return``; ``movej`` (joints, or a pose solved
near the current joints), ``movel``, ``movec`` (``mode=0``), ``set_tcp``,
``set_standard_digital_out``/``set_digital_out``, ``get_standard_digital_in``/
``get_digital_in``, ``sleep``, ``sync`` (2 ms, one controller cycle), ``textmsg`` (nothing to
show), ``pose_trans``, ``pose_add``, ``pose_inv``, ``get_inverse_kin(p, qnear=q)``,
``get_actual_joint_positions()``, ``get_actual_tcp_pose()``, ``d2r``, ``r2d``, ``sqrt``,
``sin``, ``cos``, ``norm``.

Semantics: ``movej``'s ``v`` and ``a`` are the leading axis's speed (rad/s) and
acceleration (rad/s^2): the simulator's "trapezoid" profile; ``movel``/``movec`` run at
``v`` m/s and ``a`` m/s^2; ``r`` is the zone (m). Defaults as UR's: movej a=1.4, v=1.05;
movel/movec a=1.2, v=0.25. Moves by time (``t=``), ``movec`` ``mode=1``, ``movep``,
``servoj``, ``speedj``/``speedl``, threads and everything else stop with a ProgramError.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from workcell.errors import ProgramError
from workcell.robotprog.exprs import ARITH, COMPARE, ExprParser, Fn, boolean, number
from workcell.robotprog.rotations import from_rotvec, rotvec
from workcell.robotprog.runtime import VM, Code, RobotProgram, check_calls
from workcell.robotprog.source import Loc, Parser, Token, error, tokenize
from workcell.spatial import invert

__all__ = ["Pose", "read"]

RULES = [
    ("_ws", r"[ \t\r\f]+"),
    ("_cont", r"\\\n"),
    ("_comment", r"#[^\n]*"),
    ("nl", r"\n"),
    ("num", r"(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?"),
    ("str", r'"[^"\n]*"|\'[^\'\n]*\''),
    ("pose", r"p\["),
    ("id", r"[A-Za-z_][A-Za-z0-9_]*"),
    ("op", r"==|!=|>=|<=|[-+*/%()\[\],:=<>]"),
]
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


class UrReader:
    """Reads one URScript file (module doc)."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.routines: dict[str, Code] = {}
        self.first: str | None = None

    def read(self, text: str) -> str:
        p = Parser(tokenize(text, self.path, RULES), "URScript")
        self.p = p
        self.ex = ExprParser(p, BINARY, UNARY, self.primary)
        top = Code("#TOP")
        p.skip_nl()
        while p.tok.kind != "eof":
            if p.at("def"):
                self.function()
            else:
                self.statement(top, None)
            p.skip_nl()
        if top.ops:
            self.routines["#TOP"] = top
            return "#TOP"
        if self.first is None:
            raise error(Loc(self.path, 1, 1), "no statements and no def in the file")
        return self.first

    def function(self) -> None:
        p = self.p
        p.next()
        name = p.expect_kind("id", "the function's name")
        p.expect("(")
        if not p.at(")"):
            raise p.unsupported("a function with parameters")
        p.next()
        p.expect(":", "':'")
        p.end_line()
        code = Code(name.text)
        if name.text in self.routines:
            raise error(name.loc, f"function {name.text} is defined twice")
        self.routines[name.text] = code
        self.first = self.first or name.text
        self.block(code, {"end"}, None)
        p.next()
        p.end_line()

    def block(self, code: Code, until: set[str], loop_end: str | None) -> None:
        p = self.p
        p.skip_nl()
        while not (p.tok.kind == "id" and p.tok.text in until):
            if p.tok.kind == "eof":
                raise p.fail(f"expected {' or '.join(sorted(until))}")
            self.statement(code, loop_end)
            p.skip_nl()

    def statement(self, code: Code, loop_end: str | None) -> None:
        p = self.p
        t = p.tok
        if t.kind != "id":
            raise p.fail("expected a statement")
        w = t.text
        if w == "if":
            self.if_(code, loop_end)
        elif w == "while":
            self.while_(code)
        elif w == "return":
            p.next()
            p.end_line()
            code.ret(t.loc)
        elif w in ("global", "local"):
            p.next()
            self.assignment(code)
        elif w in ("thread", "run", "join", "kill", "halt", "break", "continue", "enter_critical",
                   "exit_critical", "def", "for"):  # fmt: skip
            raise p.unsupported(f"'{w}'")
        elif p.peek().text == "=" or (p.peek().text == "[" and self._indexed_assignment()):
            self.assignment(code)
        elif p.peek().text == "(" and w not in BUILTINS:
            p.next()
            p.next()
            if not p.accept(")"):
                raise p.unsupported("a call with arguments")
            p.end_line()
            code.call(t.loc, w)
        elif p.peek().text == "(":
            call = self.call_expr(p.next())
            p.end_line()
            code.do(t.loc, lambda vm: call(vm))
        else:
            raise p.fail("expected an assignment or a call")

    def _indexed_assignment(self) -> bool:
        p = self.p
        depth, i = 0, p.i + 1
        while i < len(p.toks) and p.toks[i].kind not in ("nl", "eof"):
            if p.toks[i].text == "[":
                depth += 1
            elif p.toks[i].text == "]":
                depth -= 1
                if depth == 0:
                    return p.toks[i + 1].text == "="
            i += 1
        return False

    def assignment(self, code: Code) -> None:
        p = self.p
        t = p.expect_kind("id", "a variable name")
        index = None
        if p.accept("["):
            index = self.ex.parse()
            p.expect("]")
        p.expect("=", "'='")
        value = self.ex.parse()
        p.end_line()

        def run(vm: VM) -> None:
            v = value(vm)
            if index is None:
                vm.vars[t.text] = v
                return
            target = vm.vars.get(t.text)
            if not isinstance(target, list):
                raise ProgramError(f"{t.text} is not a list")
            i = int(number(index(vm), "an index"))
            if not 0 <= i < len(target):
                raise ProgramError(f"{t.text}[{i}] is outside the list (0 to {len(target) - 1})")
            target[i] = v

        code.do(t.loc, run)

    def if_(self, code: Code, loop_end: str | None) -> None:
        p = self.p
        t = p.next()
        done = code.new_label()
        cond = self.ex.parse()
        while True:
            p.expect(":", "':'")
            p.end_line()
            other = code.new_label()
            code.unless(t.loc, cond, other)
            self.block(code, {"elif", "else", "end"}, loop_end)
            code.jump(t.loc, done)
            code.place(other)
            if p.at("elif"):
                t = p.next()
                cond = self.ex.parse()
                continue
            if p.accept("else"):
                p.expect(":", "':'")
                p.end_line()
                self.block(code, {"end"}, loop_end)
            p.expect("end")
            p.end_line()
            break
        code.place(done)

    def while_(self, code: Code) -> None:
        p = self.p
        t = p.next()
        start = p.i
        wait = self._input_wait()
        if wait is not None:
            n, value = wait
            code.do(t.loc, lambda vm: vm.motion.wait_input(n, _name(vm, n), value))
            return
        p.i = start
        cond = self.ex.parse()
        p.expect(":", "':'")
        p.end_line()
        top, done = code.new_label(), code.new_label()
        code.place(top)
        code.unless(t.loc, cond, done)
        self.block(code, {"end"}, done)
        p.next()
        p.end_line()
        code.jump(t.loc, top)
        code.place(done)

    def _input_wait(self) -> tuple[int, bool] | None:
        """``[not] get_(standard_)digital_in(n) [== True|False]: sync()|sleep(x) ... end``:
        (input number, value waited for); None for other loops (the cursor moved)."""
        p = self.p
        neg = bool(p.accept("not"))
        paren = bool(p.accept("("))
        fn = p.next()
        if fn.text not in ("get_standard_digital_in", "get_digital_in") or not p.accept("("):
            return None
        num = p.next()
        if num.kind != "num" or not p.accept(")"):
            return None
        value = True
        if p.accept("=="):
            lit = p.next()
            if lit.text not in ("True", "False"):
                return None
            value = lit.text == "True"
        if paren and not p.accept(")"):
            return None
        if not p.accept(":"):
            return None
        # the loop runs while the condition holds: it waits for its negation
        waited = value if neg else not value
        p.skip_nl()
        while not p.at("end"):
            t = p.next()
            if t.text not in ("sync", "sleep") or not p.accept("("):
                return None
            while not p.accept(")"):
                if p.tok.kind in ("nl", "eof"):
                    return None
                p.next()
            p.skip_nl()
        p.next()
        p.end_line()
        return int(float(num.text)), waited

    # ------------------------------------------------------------------ expressions
    def primary(self) -> Fn:
        p = self.p
        t = p.tok
        if t.kind == "num":
            p.next()
            v = float(t.text) if any(c in t.text for c in ".eE") else int(t.text)
            return self.postfix(lambda vm: v)
        if t.kind == "str":
            p.next()
            s = t.text[1:-1]
            return lambda vm: s
        if t.text == "(":
            p.next()
            inner = self.ex.parse()
            p.expect(")")
            return self.postfix(inner)
        if t.kind == "pose" or t.text == "[":
            p.next()
            items = []
            while not p.at("]"):
                items.append(self.ex.parse())
                if not p.accept(","):
                    break
            p.expect("]")
            if t.kind == "pose":
                if len(items) != 6:
                    raise error(t.loc, f"a pose has 6 numbers, got {len(items)}")
                return self.postfix(
                    lambda vm: Pose(number(f(vm), "a pose's number") for f in items)
                )
            return self.postfix(lambda vm: [f(vm) for f in items])
        if t.kind == "id":
            p.next()
            if t.text in ("True", "False"):
                return lambda vm: t.text == "True"
            if p.at("("):
                return self.postfix(self.call_expr(t))

            def var(vm: VM) -> Any:
                if t.text not in vm.vars:
                    raise error(t.loc, f"{t.text} has no value")
                return vm.vars[t.text]

            return self.postfix(var)
        raise p.fail("expected a value")

    def postfix(self, base: Fn) -> Fn:
        p = self.p
        while p.at("["):
            t = p.next()
            idx = self.ex.parse()
            p.expect("]")
            base = _index_of(base, idx, t)
        return base

    def call_expr(self, t: Token) -> Fn:
        p = self.p
        p.expect("(")
        args: list[Fn] = []
        kw: dict[str, Fn] = {}
        while not p.at(")"):
            if p.tok.kind == "id" and p.peek().text == "=":
                k = p.next().text
                p.next()
                kw[k] = self.ex.parse()
            else:
                if kw:
                    raise p.fail("a positional argument after a named one")
                args.append(self.ex.parse())
            if not p.accept(","):
                break
        p.expect(")")
        name = t.text
        if name in BUILTINS:
            spec = BUILTINS[name]
            return lambda vm: _builtin(
                vm, name, spec, [f(vm) for f in args], {k: f(vm) for k, f in kw.items()}
            )
        raise error(
            t.loc,
            f"{name}(...) as a value is not supported by workcell's URScript reader "
            "(the file's functions are called as statements)",
        )


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
        s = SYNC if name == "sync" else number(a["t"], "sleep's seconds")
        if s < 0:
            raise ProgramError(f"sleep needs seconds >= 0, got {s:g}")
        m.dwell(s)
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


def read(path: Path, outputs: dict[int, str], inputs: dict[int, str]) -> RobotProgram:
    """Read a URScript file as a :class:`RobotProgram`."""
    r = UrReader(str(path))
    main = r.read(path.read_text(encoding="utf-8", errors="replace"))
    routines = {k: c.finish() for k, c in r.routines.items()}
    check_calls(routines, "URScript")
    return RobotProgram(str(path), "urscript", routines, main, [], inputs, outputs)
