"""ABB RAPID: the reader (``.mod``).

Read: ``!`` comments, ``MODULE`` ... ``ENDMODULE``, data declarations (``VAR``, ``PERS``,
``CONST``, ``LOCAL``) of num, bool, string, pos, orient, pose, confdata, robtarget,
jointtarget, tooldata, wobjdata, speeddata, zonedata (one-dimensional arrays too), the
predefined ``tool0``, ``wobj0``, ``vmax``, ``v5`` ... ``v7000``, ``fine``, ``z0`` ... ``z200``,
``PROC name()`` ... ``ENDPROC`` (``main``, else the first, runs), assignments ``:=`` with
arithmetic (``+ - * / DIV MOD``), fields (``p.trans.z``), ``Offs``, ``RelTool``,
``CRobT()``, ``CJointT()``, ``DInput``; ``MoveAbsJ``, ``MoveJ``, ``MoveL``, ``MoveC`` (with
``\\WObj``), ``SetDO``, ``WaitDI``, ``WaitTime``, ``VelSet``, ``AccSet``, ``PathAccLim``,
``ConfJ``/``ConfL`` ``\\On``/``\\Off``, ``TPWrite`` (nothing to show), ``IF``/``ELSEIF``/
``ELSE``/``ENDIF`` and the one-line ``IF``, ``FOR``/``ENDFOR``, ``WHILE``/``ENDWHILE``,
calls of the module's procedures, ``RETURN``.

Semantics: robtargets are the tool's ``tframe`` in the work object's user x object
frame; ``MoveJ`` takes the solution the confdata names (``ConfJ \\Off``: the nearest);
linear and circular moves run at the speeddata's ``v_tcp`` (mm/s) with ``PathAccLim``'s
``AccMax`` (m/s^2; 1.2 without it) and the zonedata's ``pzone_tcp`` (mm; ``fine``: a
stop); joint moves at each joint's limits x ``VelSet``'s override (their speeddata's TCP
speed is not used), ``AccSet`` and ``v_ori`` are accepted and not simulated, ``ConfL``
is not checked. Signals are by name (``gripper`` is the gripper); their numbers come from
the file's header. Everything else (functions, traps, arguments to procedures, optional
arguments other than ``\\WObj``, ``TEST``, ``GOTO``, ...) is a ProgramError at its place.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from workcell.errors import ProgramError
from workcell.robotprog.configs import abb_confdata
from workcell.robotprog.exprs import ARITH, COMPARE, ExprParser, Fn, boolean, number
from workcell.robotprog.rotations import quat_wxyz
from workcell.robotprog.runtime import VM, Code, RobotProgram, check_calls
from workcell.robotprog.source import Loc, Parser, Token, error, tokenize
from workcell.spatial import matrix_from_quat, translation

__all__ = ["read"]

RULES = [
    ("_ws", r"[ \t\r\f\n]+"),
    ("_comment", r"![^\n]*"),
    ("num", r"(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?"),
    ("str", r'"[^"\n]*"'),
    ("id", r"[A-Za-z_][A-Za-z0-9_]*"),
    ("op", r":=|<>|>=|<=|[-+*/(){}\[\],.:;=<>\\]"),
]
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


class RapidReader:
    """Reads one RAPID module (module doc)."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.types: dict[str, str] = {k.upper(): t for k, (t, _) in PREDEFINED.items()}
        self.routines: dict[str, Code] = {}
        self.setup: list[Any] = [_setup]
        self.first: str | None = None
        self.signals: set[str] = set()

    def read(self, text: str) -> None:
        p = Parser(tokenize(text, self.path, RULES), "RAPID")
        self.p = p
        self.ex = ExprParser(p, BINARY, UNARY, self.primary)
        p.expect("MODULE", "MODULE")
        p.expect_kind("id", "the module's name")
        if p.accept("("):
            while not p.accept(")"):
                if p.tok.kind == "eof":
                    raise p.fail("expected ')'")
                p.next()
        data = Code("#DATA")
        while not p.at("ENDMODULE"):
            if p.tok.kind == "eof":
                raise p.fail("expected ENDMODULE")
            p.accept("LOCAL", "TASK")
            if p.at("VAR", "PERS", "CONST"):
                self.declaration(data)
            elif p.at("PROC"):
                self.proc()
            elif p.at("FUNC", "TRAP", "RECORD", "ALIAS"):
                raise p.unsupported(p.tok.text)
            else:
                raise p.fail("expected a declaration, PROC or ENDMODULE")
        p.next()
        routine = data.finish()
        self.setup.append(lambda vm: _run_data(vm, routine))

    def declaration(self, code: Code) -> None:
        p = self.p
        p.next()
        type_tok = p.expect_kind("id", "a data type")
        typ = type_tok.text.lower()
        if typ not in RECORDS and typ not in ATOMS:
            raise p.unsupported(f"the data type {type_tok.text}", type_tok)
        name = p.expect_kind("id", "the data's name")
        size = None
        if p.accept("{"):
            size = int(number(float(p.expect_kind("num", "the array's size").text)))
            if p.accept(","):
                raise p.unsupported("an array of several dimensions")
            p.expect("}")
        init = None
        if p.accept(":="):
            init = self.ex.parse()
        p.expect(";", "';'")
        key = name.upper
        self.types[key] = typ

        def run(vm: VM) -> None:
            value: Any = None
            if init is not None:
                v = init(vm)
                value = (
                    [record(typ, x, name.text) for x in v]
                    if size is not None
                    else record(typ, v, name.text)
                )
                if size is not None and len(value) != size:
                    raise ProgramError(f"{name.text} has {size} elements, its value {len(value)}")
            elif size is not None:
                value = [None] * size
            vm.vars[key] = value

        code.do(name.loc, run)

    def proc(self) -> None:
        p = self.p
        p.next()
        name = p.expect_kind("id", "the procedure's name")
        p.expect("(")
        if not p.at(")"):
            raise p.unsupported("a procedure with parameters")
        p.next()
        code = Code(name.upper)
        if name.upper in self.routines:
            raise error(name.loc, f"procedure {name.text} is defined twice")
        self.routines[name.upper] = code
        self.first = self.first or name.upper
        while p.at("VAR", "PERS", "CONST", "LOCAL"):
            p.accept("LOCAL")
            self.declaration(code)
        self.block(code, {"ENDPROC"})
        p.next()

    # ------------------------------------------------------------------ statements
    def block(self, code: Code, until: set[str]) -> None:
        p = self.p
        while not (p.tok.kind == "id" and p.tok.upper in until):
            if p.tok.kind == "eof":
                raise p.fail(f"expected {' or '.join(sorted(until))}")
            self.statement(code)

    def statement(self, code: Code) -> None:
        p = self.p
        t = p.tok
        u = t.upper
        if t.kind != "id":
            raise p.fail("expected a statement")
        if u == "IF":
            self.if_(code)
        elif u == "FOR":
            self.for_(code)
        elif u == "WHILE":
            p.next()
            top, done = code.new_label(), code.new_label()
            code.place(top)
            cond = self.ex.parse()
            p.expect("DO")
            code.unless(t.loc, cond, done)
            self.block(code, {"ENDWHILE"})
            p.next()
            code.jump(t.loc, top)
            code.place(done)
        elif u == "RETURN":
            p.next()
            p.expect(";", "';'")
            code.ret(t.loc)
        elif p.peek().text == ":=" or p.peek().text in (".", "{"):
            self.assignment(code)
        elif u in INSTRUCTIONS:
            self.instruction(code)
        elif p.peek().text == ";":
            p.next()
            p.next()
            if u not in self.routines and u in self.types:
                raise error(t.loc, f"{t.text} is data, not a procedure")
            code.call(t.loc, u)
        else:
            raise p.unsupported(f"the instruction {t.text}")

    def assignment(self, code: Code) -> None:
        p = self.p
        t = p.next()
        path: list[Any] = []
        while True:
            if p.accept("."):
                path.append(p.expect_kind("id", "a component").text.lower())
            elif p.accept("{"):
                path.append(self.ex.parse())
                p.expect("}")
            else:
                break
        p.expect(":=", "':='")
        value = self.ex.parse()
        p.expect(";", "';'")
        key = t.upper
        typ = self.types.get(key)
        if typ is None:
            raise error(t.loc, f"{t.text} is not declared")

        def run(vm: VM) -> None:
            v = value(vm)
            if not path:
                vm.vars[key] = record(typ, v, t.text)
                return
            holder = vm.vars.get(key)
            for step in path[:-1]:
                holder = _component(holder, step(vm) if callable(step) else step, t.text)
            last = path[-1]
            if callable(last):
                i = _array_index(holder, last(vm), t.text)
                holder[i] = v
            else:
                if not isinstance(holder, dict) or last not in holder:
                    raise ProgramError(f"{t.text} has no component {last}")
                holder[last] = v

        code.do(t.loc, run)

    def instruction(self, code: Code) -> None:
        p = self.p
        t = p.next()
        u = t.upper
        args: list[Fn] = []
        opts: dict[str, Fn | None] = {}
        if u in ("SETDO", "WAITDI"):
            sig = p.expect_kind("id", "a signal's name").text
            args.append(lambda vm: sig)
            p.expect(",", "',' and the value")
        while not p.at(";"):
            if p.tok.kind == "eof":
                raise p.fail("expected ';'")
            if p.accept("\\"):
                o = p.expect_kind("id", "an optional argument").upper
                opts[o] = None
                if p.accept(":="):
                    opts[o] = self.ex.parse()
            else:
                args.append(self.ex.parse())
            if not p.accept(",") and not p.at(";", "\\"):
                raise p.fail("expected ',' or ';'")
        p.next()
        n_args, allowed = INSTRUCTIONS[u]
        if len(args) != n_args:
            raise error(t.loc, f"{t.text} takes {n_args} argument(s), got {len(args)}")
        extra = sorted(set(opts) - allowed)
        if extra:
            raise error(t.loc, f"{t.text} \\{extra[0]} is not supported by workcell's RAPID reader")
        code.do(t.loc, lambda vm: _instruction(vm, u, args, opts))

    def if_(self, code: Code) -> None:
        p = self.p
        t = p.next()
        cond = self.ex.parse()
        done = code.new_label()
        if not p.at("THEN"):  # the one-line IF: IF cond statement
            skip = code.new_label()
            code.unless(t.loc, cond, skip)
            self.statement(code)
            code.place(skip)
            return
        p.next()
        while True:
            other = code.new_label()
            code.unless(t.loc, cond, other)
            self.block(code, {"ELSEIF", "ELSE", "ENDIF"})
            code.jump(t.loc, done)
            code.place(other)
            if p.at("ELSEIF"):
                t = p.next()
                cond = self.ex.parse()
                p.expect("THEN")
                continue
            if p.accept("ELSE"):
                self.block(code, {"ENDIF"})
            p.expect("ENDIF")
            break
        code.place(done)

    def for_(self, code: Code) -> None:
        p = self.p
        t = p.next()
        var = p.expect_kind("id", "the loop variable").upper
        p.expect("FROM")
        start = self.ex.parse()
        p.expect("TO")
        stop = self.ex.parse()
        step: Fn = lambda vm: 1  # noqa: E731
        if p.accept("STEP"):
            step = self.ex.parse()
        p.expect("DO")
        self.types.setdefault(var, "num")

        def get(vm: VM) -> Any:
            return vm.vars[var]

        def put(vm: VM, v: float) -> None:
            vm.vars[var] = v

        head = code.for_open(t.loc, get, put, start, stop, step)
        self.block(code, {"ENDFOR"})
        end = p.next()
        code.for_close(end.loc, get, put, head)

    # ------------------------------------------------------------------ expressions
    def primary(self) -> Fn:
        p = self.p
        t = p.next()
        if t.kind == "num":
            v = float(t.text)
            return lambda vm: v
        if t.kind == "str":
            s = t.text[1:-1]
            return lambda vm: s
        if t.text == "(":
            inner = self.ex.parse()
            p.expect(")")
            return inner
        if t.text == "[":
            items = []
            while not p.at("]"):
                items.append(self.ex.parse())
                if not p.accept(","):
                    break
            p.expect("]")
            return lambda vm: [f(vm) for f in items]
        if t.kind != "id":
            raise p.fail("expected a value", t)
        u = t.upper
        if u in ("TRUE", "FALSE"):
            return lambda vm: u == "TRUE"
        if p.at("("):
            return self.function(t)
        if u not in self.types:
            if t.text.lower() in self.signals:  # a signal the file's header lists
                sig = t.text
                return lambda vm: _dinput(vm, sig)
            raise error(t.loc, f"{t.text} is not declared (nor a signal the file's header lists)")

        def var(vm: VM) -> Any:
            if u in vm.vars:
                v = vm.vars[u]
            elif t.text.lower() in PREDEFINED or u.lower() in PREDEFINED:
                v = PREDEFINED[t.text.lower() if t.text.lower() in PREDEFINED else u.lower()][1]
            else:
                v = None
            if v is None:
                raise error(t.loc, f"{t.text} is used before it has a value")
            return v

        base: Fn = var
        while True:
            if p.accept("."):
                c = p.expect_kind("id", "a component")
                base = _component_of(base, c)
            elif p.accept("{"):
                idx = self.ex.parse()
                p.expect("}")
                base = _element_of(base, idx, t.text)
            else:
                return base

    def function(self, t: Token) -> Fn:
        p = self.p
        p.expect("(")
        if t.upper == "DINPUT":
            sig = p.expect_kind("id", "a signal's name").text
            p.expect(")")
            return lambda vm: _dinput(vm, sig)
        args: list[Fn] = []
        opts: dict[str, Fn] = {}
        while not p.at(")"):
            if p.accept("\\"):
                o = p.expect_kind("id", "an optional argument").upper
                p.expect(":=")
                opts[o] = self.ex.parse()
            else:
                args.append(self.ex.parse())
            if not p.accept(","):
                break
        p.expect(")")
        u = t.upper
        if u == "OFFS" and len(args) == 4 and not opts:
            return lambda vm: _offs(*(f(vm) for f in args))
        if u == "RELTOOL" and len(args) == 4 and set(opts) <= {"RX", "RY", "RZ"}:
            return lambda vm: _reltool([f(vm) for f in args], {k: f(vm) for k, f in opts.items()})
        if u == "CROBT" and not args and not opts:
            return lambda vm: _crobt(vm)
        if u == "CJOINTT" and not args and not opts:
            return lambda vm: {"robax": {f"rax_{i + 1}": math.degrees(v) for i, v in enumerate(vm.motion.joints())},
                               "extax": {f"e{c}": 9e9 for c in "abcdef"}}  # fmt: skip
        if u in ("ABS", "SQRT", "SIN", "COS", "TAN", "ROUND", "TRUNC") and len(args) == 1:
            f = MATH[u]
            return lambda vm: f(number(args[0](vm), t.text))
        raise error(
            t.loc,
            f"the function {t.text} (with these arguments) is not supported by workcell's RAPID reader",
        )


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
        s = number(a[0], "WaitTime's seconds")
        if s < 0:
            raise ProgramError(f"WaitTime needs seconds >= 0, got {s:g}")
        m.dwell(s)
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


def read(path: Path, outputs: dict[int, str], inputs: dict[int, str]) -> RobotProgram:
    """Read a RAPID module as a :class:`RobotProgram`."""
    r = RapidReader(str(path))
    r.signals = {s.lower() for s in (*outputs.values(), *inputs.values())}
    text = path.read_text(encoding="utf-8", errors="replace")
    r.read(text)
    if not r.routines:
        raise error(Loc(str(path), 1, 1), "no PROC in the module")
    main = "MAIN" if "MAIN" in r.routines else r.first
    routines = {k: c.finish() for k, c in r.routines.items()}
    check_calls(routines, "RAPID")
    return RobotProgram(str(path), "rapid", routines, main or "", r.setup, inputs, outputs)
