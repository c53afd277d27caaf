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

from workcell.errors import ProgramError
from workcell.robotprog.exprs import ExprParser, Fn, number
from workcell.robotprog.rapid_run import (
    ATOMS,
    BINARY,
    INSTRUCTIONS,
    MATH,
    PREDEFINED,
    RECORDS,
    UNARY,
    _array_index,
    _component,
    _component_of,
    _crobt,
    _dinput,
    _element_of,
    _instruction,
    _offs,
    _reltool,
    _run_data,
    _setup,
    record,
)
from workcell.robotprog.runtime import VM, Code, RobotProgram, check_calls
from workcell.robotprog.source import Loc, Parser, Token, error, tokenize

__all__ = ["read"]

RULES = [
    ("_ws", r"[ \t\r\f\n]+"),
    ("_comment", r"![^\n]*"),
    ("num", r"(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?"),
    ("str", r'"[^"\n]*"'),
    ("id", r"[A-Za-z_][A-Za-z0-9_]*"),
    ("op", r":=|<>|>=|<=|[-+*/(){}\[\],.:;=<>\\]"),
]


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
