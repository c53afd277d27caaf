"""KUKA KRL: the reader (``.src``, with the ``.dat`` of the same name beside it).

Read: ``&`` header lines, ``;`` comments and folds (``;FOLD`` ... ``;ENDFOLD``: the code
inside runs), ``DEF name( )`` ... ``END`` (every routine of the file; the first is the
main one), ``DEFDAT`` ... ``ENDDAT`` (in the ``.dat`` or the ``.src``), declarations
(``DECL``, ``INT``/``REAL``/``BOOL``/``FRAME``/``POS``/``E6POS``/``AXIS``/``E6AXIS``/
``FDAT``/``PDAT``/``LDAT``, arrays of one dimension, ``SIGNAL name $OUT[n]``), assignments
with arithmetic, aggregates and the geometric operator ``:``, ``PTP``/``LIN``/``CIRC``
with ``C_DIS`` and ``C_PTP``, ``$VEL.CP``, ``$ACC.CP``, ``$VEL_AXIS[i]``, ``$ACC_AXIS[i]``,
``$OV_PRO``, ``$APO.CDIS``, ``$APO.CPTP``, ``$TOOL``, ``$BASE``, ``$ORI_TYPE = #VAR``,
``$CIRC_TYPE = #BASE``, ``$OUT[n]``, ``$IN[n]``, ``$POS_ACT``, ``$AXIS_ACT``,
``WAIT SEC``, ``WAIT FOR``, ``IF``/``ELSE``/``ENDIF``, ``FOR``/``ENDFOR``, ``WHILE``,
``REPEAT``/``UNTIL``, ``LOOP``/``EXIT``, calls of the file's routines, ``RETURN``, and
``BAS(#INITMOV|#VEL_PTP|#ACC_PTP|#VEL_CP|#ACC_CP|#TOOL|#BASE|#PTP_PARAMS|#CP_PARAMS, x)``.

Semantics (:mod:`workcell.robotprog.runtime`): ``$VEL_AXIS`` (equal on every axis) x
``$OV_PRO`` scales joint moves, ``$OV_PRO`` the tool speeds; ``C_PTP`` with ``$APO.CPTP``
n % is a zone of n mm (the percentage has no length); ``$ACC_AXIS`` and the orientation
speeds ``$VEL.ORI1/2``, ``$ACC.ORI1/2`` are accepted and not simulated (the joints' own
limits and the tool acceleration time the moves); ``$ADVANCE`` and ``$BWDSTART`` change
nothing in a simulation. A tool or base number the file does not define (``TOOL_DATA[n]``
of ``$config.dat``) is the robot's own tool, the robot's base. Everything else
(functions ``DEFFCT``, parameters, ``SWITCH``, ``GOTO``, interrupts, triggers, ``PULSE``,
``HALT``, ``C_VEL``, ``C_ORI``, ``CIRC`` with ``CA``, other system variables) stops with a
ProgramError at its place.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from workcell.errors import ProgramError
from workcell.robotprog.configs import kuka_status_turn
from workcell.robotprog.exprs import ARITH, COMPARE, ExprParser, Fn, boolean, number
from workcell.robotprog.kuka_values import (
    SIMPLE_TYPES,
    STRUCT_TYPES,
    frame_matrix,
    geometric,
    joints_of,
    pose_dict,
    program_pose,
    tcp_of_tool,
)
from workcell.robotprog.runtime import VM, Code, RobotProgram, check_calls
from workcell.robotprog.source import Loc, Parser, Token, error, tokenize

__all__ = ["read"]

RULES = [
    ("_ws", r"[ \t\r\f]+"),
    ("_comment", r";[^\n]*"),
    ("_attr", r"&[^\n]*"),
    ("nl", r"\n"),
    ("bits", r"'[BbHh][0-9A-Fa-f]+'"),
    ("num", r"(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?"),
    ("str", r'"[^"\n]*"'),
    ("sys", r"\$[A-Za-z_][A-Za-z0-9_]*"),
    ("enum", r"#[A-Za-z_][A-Za-z0-9_]*"),
    ("id", r"[A-Za-z_][A-Za-z0-9_]*"),
    ("op", r"==|<>|>=|<=|[-+*/(){}\[\],.:=<>]"),
]
DEF_VEL_CP, DEF_ACC_CP = 2.0, 2.3  # m/s, m/s^2: BAS(#INITMOV) (workcell's choice)
SETTINGS = {
    "$VEL.CP": "vel_cp", "$ACC.CP": "acc_cp", "$OV_PRO": "ov", "$APO.CDIS": "cdis",
    "$APO.CPTP": "cptp",
}  # fmt: skip
IGNORED = {"$VEL.ORI1", "$VEL.ORI2", "$ACC.ORI1", "$ACC.ORI2", "$ADVANCE", "$BWDSTART"}
ENDS = {"END", "ENDIF", "ELSE", "ENDFOR", "ENDWHILE", "UNTIL", "ENDLOOP", "ENDDAT"}


def _setup(vm: VM) -> None:
    vm.lang.update(
        vel_cp=DEF_VEL_CP, acc_cp=DEF_ACC_CP, ov=100.0, cdis=0.0, cptp=0.0,
        vel_axis=[100.0] * 6, acc_axis=[100.0] * 6, ori="#VAR", circ="#BASE",
    )  # fmt: skip


class KrlReader:
    """Reads one KRL program (module doc)."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.types: dict[str, str] = {}
        self.signals: dict[str, tuple[str, int]] = {}
        self.setup: list[Any] = [_setup]
        self.routines: dict[str, Code] = {}
        self.main: str | None = None

    # ------------------------------------------------------------------ files
    def read_file(self, path: Path) -> None:
        text = path.read_text(encoding="utf-8", errors="replace")
        p = Parser(tokenize(text, str(path), RULES), "KRL")
        self.p = p
        self.ex = ExprParser(p, BINARY, UNARY, self.primary)
        p.skip_nl()
        while p.tok.kind != "eof":
            if p.accept("GLOBAL"):
                pass
            if p.at("DEF"):
                self.routine()
            elif p.at("DEFDAT"):
                self.data()
            elif p.at("DEFFCT"):
                raise p.unsupported("a function (DEFFCT)")
            else:
                raise p.fail("expected DEF, DEFDAT or the end of the file")
            p.skip_nl()

    def data(self) -> None:
        p = self.p
        p.next()
        p.expect_kind("id", "the data list's name")
        p.accept("PUBLIC")
        p.end_line()
        code = Code("#DAT")
        while not p.at("ENDDAT"):
            if p.tok.kind == "eof":
                raise p.fail("expected ENDDAT")
            if not self.declaration(code):
                raise p.fail("a data list holds declarations only")
        p.next()
        p.end_line()
        routine = code.finish()

        def run_data(vm: VM, routine: Any = routine) -> None:
            vm.program.routines["#DAT"] = routine
            vm.call("#DAT", routine.ops[0].loc if routine.ops else Loc(self.path, 1, 1), 0)

        self.setup.append(run_data)

    def routine(self) -> None:
        p = self.p
        p.next()
        name_tok = p.expect_kind("id", "the routine's name")
        name = name_tok.upper
        if name in self.routines:
            raise error(name_tok.loc, f"routine {name_tok.text} is defined twice")
        p.expect("(")
        if not p.at(")"):
            raise p.unsupported("a routine with parameters")
        p.next()
        p.end_line()
        code = Code(name)
        self.routines[name] = code
        if self.main is None:
            self.main = name
        self.block(code, {"END"}, None)
        p.next()
        p.end_line()

    # ------------------------------------------------------------------ statements
    def block(self, code: Code, until: set[str], exit_label: str | None) -> None:
        p = self.p
        while not (p.tok.kind in ("id",) and p.tok.upper in until):
            if p.tok.kind == "eof":
                raise p.fail(f"expected {' or '.join(sorted(until))}")
            self.statement(code, exit_label)

    def statement(self, code: Code, exit_label: str | None) -> None:
        p = self.p
        t = p.tok
        u = t.upper if t.kind in ("id", "sys") else ""
        if t.kind == "id" and u in ENDS:
            raise p.fail("unexpected " + u)
        if self.declaration(code):
            return
        if u in ("PTP", "LIN", "CIRC"):
            self.motion(code)
        elif u in ("PTP_REL", "LIN_REL", "CIRC_REL", "SPLINE", "SPL", "SLIN", "SCIRC", "SPTP"):
            raise p.unsupported(f"the motion {t.text}")
        elif u == "WAIT":
            self.wait(code)
        elif u == "IF":
            self.if_(code, exit_label)
        elif u == "FOR":
            self.for_(code)
        elif u == "WHILE":
            p.next()
            top, done = code.new_label(), code.new_label()
            code.place(top)
            cond = self.condition()
            p.end_line()
            code.unless(t.loc, cond, done)
            self.block(code, {"ENDWHILE"}, done)
            p.next()
            p.end_line()
            code.jump(t.loc, top)
            code.place(done)
        elif u == "REPEAT":
            p.next()
            p.end_line()
            top, done = code.new_label(), code.new_label()
            code.place(top)
            self.block(code, {"UNTIL"}, done)
            until = p.next()
            cond = self.condition()
            p.end_line()
            code.unless(until.loc, cond, top)
            code.place(done)
        elif u == "LOOP":
            p.next()
            p.end_line()
            top, done = code.new_label(), code.new_label()
            code.place(top)
            self.block(code, {"ENDLOOP"}, done)
            p.next()
            p.end_line()
            code.jump(t.loc, top)
            code.place(done)
        elif u == "EXIT":
            if exit_label is None:
                raise error(t.loc, "EXIT outside a loop")
            p.next()
            p.end_line()
            code.jump(t.loc, exit_label)
        elif u == "RETURN":
            p.next()
            p.end_line()
            code.ret(t.loc)
        elif u == "BAS":
            self.bas(code)
        elif u in ("HALT", "GOTO", "SWITCH", "INTERRUPT", "TRIGGER", "PULSE", "ANIN", "ANOUT",
                   "BRAKE", "RESUME", "CONTINUE", "CWRITE", "CREAD", "SREAD", "SWRITE"):  # fmt: skip
            raise p.unsupported(f"the statement {t.text}")
        elif t.kind == "id" and p.peek().text == "(":
            p.next()
            p.expect("(")
            if not p.at(")"):
                raise p.unsupported("a call with arguments")
            p.next()
            p.end_line()
            code.call(t.loc, u)
        elif t.kind in ("id", "sys"):
            self.assignment(code)
        else:
            raise p.fail("expected a statement")

    def declaration(self, code: Code) -> bool:
        """DECL / a typed declaration / SIGNAL; False when the line is none of them."""
        p = self.p
        t = p.tok
        if t.kind != "id":
            return False
        if t.upper == "SIGNAL":
            p.next()
            name = p.expect_kind("id", "the signal's name")
            io = p.expect_kind("sys", "$IN[n] or $OUT[n]")
            if io.upper not in ("$IN", "$OUT"):
                raise p.unsupported(f"a signal on {io.text}")
            p.expect("[")
            n = int(number(float(p.expect_kind("num", "the I/O number").text)))
            p.expect("]")
            if p.accept("TO"):
                raise p.unsupported("a signal of several bits (TO)")
            p.end_line()
            self.signals[name.upper] = (io.upper, n)
            return True
        words = {"DECL", "GLOBAL", "CONST"}
        if t.upper not in words and not (
            t.upper in STRUCT_TYPES | SIMPLE_TYPES and p.peek().kind == "id"
        ):
            return False
        while p.at(*words):
            p.next()
        type_tok = p.expect_kind("id", "a type")
        typ = type_tok.upper
        if typ not in STRUCT_TYPES | SIMPLE_TYPES:
            raise p.unsupported(f"the type {type_tok.text}")
        while True:
            name = p.expect_kind("id", "a variable name")
            key = name.upper
            size = None
            if p.accept("["):
                size = int(number(float(p.expect_kind("num", "the array's size").text)))
                if p.accept(","):
                    raise p.unsupported("an array of several dimensions")
                p.expect("]")
            self.types[key] = typ
            init = None
            if p.accept("="):
                init = self.ex.parse()
            code.do(name.loc, self._declare(key, typ, size, init))
            if not p.accept(","):
                break
        p.end_line()
        return True

    def _declare(self, key: str, typ: str, size: int | None, init: Fn | None) -> Fn:
        def run(vm: VM) -> None:
            if size is not None:
                vm.vars[key] = [({} if typ in STRUCT_TYPES else None) for _ in range(size)]
            else:
                vm.vars[key] = {} if typ in STRUCT_TYPES else None
            if init is not None:
                vm.vars[key] = _convert(typ, vm.vars[key], init(vm))

        return run

    def assignment(self, code: Code) -> None:
        p = self.p
        t = p.tok
        target = self.lvalue()
        p.expect("=", "'='")
        value = self.ex.parse()
        p.end_line()
        code.do(t.loc, lambda vm: target(vm, value(vm)))

    def lvalue(self) -> Any:
        """A setter (vm, value) for a variable, an element, a field or a system variable."""
        p = self.p
        t = p.next()
        name = t.upper
        index = None
        if p.accept("["):
            index = self.ex.parse()
            p.expect("]")
        fields = []
        while p.accept("."):
            fields.append(p.expect_kind("id", "a field name").upper)
        if t.kind == "sys":
            return self._system_setter(t, name, index, fields)
        if name in self.signals:
            kind, n = self.signals[name]
            if kind != "$OUT" or index is not None or fields:
                raise error(t.loc, f"signal {t.text} is an input: it cannot be set")
            return lambda vm, v: vm.motion.set_output(n, t.text, boolean(v, t.text))

        def set_var(vm: VM, v: Any) -> None:
            if name not in vm.vars:
                raise error(t.loc, f"{t.text} is not declared")
            typ = self.types.get(name, "")
            if index is None and not fields:
                vm.vars[name] = _convert(typ, vm.vars[name], v)
                return
            holder = vm.vars[name]
            if index is not None:
                i = _index(holder, index(vm), t.text)
                if not fields:
                    holder[i] = _convert(typ, holder[i], v)
                    return
                holder = holder[i]
            for f in fields[:-1]:
                holder = holder.setdefault(f, {})
            if not isinstance(holder, dict):
                raise ProgramError(f"{t.text} has no fields")
            holder[fields[-1]] = v

        return set_var

    def _system_setter(self, t: Token, name: str, index: Fn | None, fields: list[str]) -> Any:
        full = name + "".join("." + f for f in fields)
        if full in IGNORED:
            return lambda vm, v: None
        if full in SETTINGS:
            key = SETTINGS[full]

            def set_number(vm: VM, v: Any) -> None:
                x = number(v, full)
                if x < 0 or (key == "ov" and not 0 < x <= 100):
                    raise ProgramError(f"{full} = {x:g} is out of range")
                vm.lang[key] = x

            return set_number
        if full in ("$VEL_AXIS", "$ACC_AXIS") and index is not None:
            key = full[1:].lower()

            def set_axis(vm: VM, v: Any) -> None:
                i = _index(vm.lang[key], index(vm), full, base=1)
                x = number(v, full)
                if not 0 < x <= 100:
                    raise ProgramError(f"{full}[{i + 1}] must be in (0, 100] %, got {x:g}")
                vm.lang[key][i] = x

            return set_axis
        if full == "$OUT" and index is not None:
            return lambda vm, v: vm.motion.set_output(
                int(number(index(vm))),
                _io_name(vm, "$OUT", int(number(index(vm)))),
                boolean(v, "$OUT"),
            )
        if full == "$TOOL":
            return lambda vm, v: setattr(vm.motion, "tcp", None if v is None else tcp_of_tool(v))
        if full == "$BASE":
            return lambda vm, v: setattr(
                vm.motion, "base", np.eye(4) if v is None else frame_matrix(v, "$BASE")
            )
        if full in ("$ORI_TYPE", "$CIRC_TYPE"):
            ok = {"$ORI_TYPE": "#VAR", "$CIRC_TYPE": "#BASE"}[full]

            def set_type(vm: VM, v: Any) -> None:
                if v != ok:
                    raise ProgramError(f"{full} = {v} is not supported (only {ok})")

            return set_type
        raise error(t.loc, f"the system variable {full} is not supported by workcell's KRL reader")

    # ------------------------------------------------------------------ motions and waits
    def motion(self, code: Code) -> None:
        p = self.p
        t = p.next()
        kind = t.upper
        via = None
        target = self.ex.parse()
        if kind == "CIRC":
            p.expect(",", "',' and the end point")
            via, target = target, self.ex.parse()
            if p.accept(","):
                raise p.unsupported("CIRC with a circular angle (CA)")
        approx = None
        if p.tok.kind == "id" and p.tok.upper in ("C_DIS", "C_PTP", "C_VEL", "C_ORI"):
            approx = p.next()
            if approx.upper in ("C_VEL", "C_ORI"):
                raise p.unsupported(f"approximation {approx.text}", approx)
            if approx.upper == "C_PTP" and kind != "PTP":
                raise error(approx.loc, "C_PTP goes with PTP; LIN and CIRC take C_DIS")
        p.end_line()
        ap = approx.upper if approx else None
        code.do(t.loc, lambda vm: _move(vm, kind, target(vm), None if via is None else via(vm), ap))

    def wait(self, code: Code) -> None:
        p = self.p
        t = p.next()
        if p.accept("SEC"):
            secs = self.ex.parse()
            p.end_line()
            code.do(t.loc, lambda vm: vm.motion.dwell(_seconds(secs(vm))))
            return
        p.expect("FOR", "SEC or FOR")
        single = self._single_input()
        if single is not None:
            kind, n, name, value = single
            code.do(t.loc, lambda vm: vm.motion.wait_input(n, name or _io_name(vm, kind, n), value))
            return
        cond = self.ex.parse()
        p.end_line()
        code.do(t.loc, lambda vm: _wait_for(vm, cond, t))

    def _single_input(self) -> tuple[str, int, str, bool] | None:
        """``[NOT] $IN[n] [== TRUE|FALSE]`` or a declared input signal, to the line's
        end: (kind, number, name, value waited for); None for other conditions."""
        p = self.p
        start = p.i
        neg = bool(p.accept("NOT"))
        t = p.next()
        kind, n, name = "", -1, ""
        if t.kind == "sys" and t.upper == "$IN" and p.accept("["):
            num = p.next()
            if num.kind == "num" and p.accept("]"):
                kind, n = "$IN", int(float(num.text))
        elif t.kind == "id" and t.upper in self.signals and self.signals[t.upper][0] == "$IN":
            kind, n = self.signals[t.upper]
            name = t.text
        value = not neg
        if kind and p.accept("=="):
            lit = p.next()
            if lit.upper not in ("TRUE", "FALSE"):
                kind = ""
            value = (lit.upper == "TRUE") != neg
        if kind and p.tok.kind in ("nl", "eof"):
            p.end_line()
            return kind, n, name, value
        p.i = start
        return None

    def condition(self) -> Fn:
        return self.ex.parse()

    def if_(self, code: Code, exit_label: str | None) -> None:
        p = self.p
        t = p.next()
        cond = self.condition()
        p.expect("THEN")
        p.end_line()
        other, done = code.new_label(), code.new_label()
        code.unless(t.loc, cond, other)
        self.block(code, {"ELSE", "ENDIF"}, exit_label)
        if p.accept("ELSE"):
            p.end_line()
            code.jump(t.loc, done)
            code.place(other)
            self.block(code, {"ENDIF"}, exit_label)
        else:
            code.place(other)
        p.expect("ENDIF")
        p.end_line()
        code.place(done)

    def for_(self, code: Code) -> None:
        p = self.p
        t = p.next()
        var = p.expect_kind("id", "the loop variable").upper
        p.expect("=")
        start = self.ex.parse()
        p.expect("TO")
        stop = self.ex.parse()
        step: Fn = lambda vm: 1  # noqa: E731
        if p.accept("STEP"):
            step_tok = p.tok
            step = self.ex.parse()
            if step_tok.kind not in ("num", "op"):
                raise error(step_tok.loc, "STEP must be a constant")
        p.end_line()

        def get(vm: VM) -> Any:
            return vm.vars[var]

        def put(vm: VM, v: float) -> None:
            vm.vars[var] = int(v)

        head = code.for_open(t.loc, get, put, start, stop, step)
        self.block(code, {"ENDFOR"}, head[2])
        end = p.next()
        p.end_line()
        code.for_close(end.loc, get, put, head)

    def bas(self, code: Code) -> None:
        p = self.p
        t = p.next()
        p.expect("(")
        what = p.expect_kind("enum", "a BAS action (#INITMOV, #VEL_PTP, ...)").upper
        arg: Fn = lambda vm: 0  # noqa: E731
        if p.accept(","):
            arg = self.ex.parse()
        p.expect(")")
        p.end_line()
        known = {"#INITMOV", "#VEL_PTP", "#ACC_PTP", "#VEL_CP", "#ACC_CP", "#TOOL", "#BASE",
                 "#PTP_PARAMS", "#CP_PARAMS"}  # fmt: skip
        if what not in known:
            raise p.unsupported(f"BAS({what})", t)
        code.do(t.loc, lambda vm: _bas(vm, what, arg(vm)))

    # ------------------------------------------------------------------ expressions
    def primary(self) -> Fn:
        p = self.p
        t = p.next()
        if t.kind == "num":
            v = float(t.text) if any(c in t.text for c in ".eE") else int(t.text)
            return self.postfix(lambda vm: v)
        if t.kind == "bits":
            base = 2 if t.text[1] in "Bb" else 16
            v = int(t.text[2:-1], base)
            return lambda vm: v
        if t.kind == "str":
            s = t.text[1:-1]
            return lambda vm: s
        if t.kind == "enum":
            e = t.upper
            return lambda vm: e
        if t.text == "(":
            inner = self.ex.parse()
            p.expect(")")
            return self.postfix(inner)
        if t.text == "{":
            return self.postfix(self.aggregate(t))
        if t.kind == "sys":
            return self.postfix(self.system(t))
        if t.kind == "id":
            u = t.upper
            if u in ("TRUE", "FALSE"):
                return lambda vm: u == "TRUE"
            if u in self.signals:
                kind, n = self.signals[u]
                return lambda vm: _io_read(vm, kind, n, t.text)
            if u in ("TOOL_DATA", "BASE_DATA") and u not in self.types:
                p.expect("[")
                self.ex.parse()
                p.expect("]")
                return lambda vm: None  # the controller's tables: the robot's own tool/base
            if p.at("("):
                raise p.unsupported(f"the function {t.text}()", t)

            def var(vm: VM) -> Any:
                if u not in vm.vars:
                    raise error(t.loc, f"{t.text} is not declared")
                if vm.vars[u] is None:
                    raise error(t.loc, f"{t.text} is used before it has a value")
                return vm.vars[u]

            return self.postfix(var)
        raise p.fail("expected a value", t)

    def postfix(self, base: Fn) -> Fn:
        p = self.p
        while True:
            t = p.tok
            if t.text == "[":
                p.next()
                idx = self.ex.parse()
                p.expect("]")
                base = _element_of(base, idx, t)
            elif t.text == ".":
                p.next()
                f = p.expect_kind("id", "a field name")
                base = _field_of(base, f)
            else:
                return base

    def aggregate(self, open_tok: Token) -> Fn:
        p = self.p
        typ = None
        if p.tok.kind == "id" and p.peek().text == ":":
            typ = p.next().upper
            p.next()
        items: list[tuple[str, Fn]] = []
        while not p.at("}"):
            f = p.expect_kind("id", "a field name").upper
            value = self.aggregate(p.next()) if p.at("{") else self.ex.parse()
            items.append((f, value))
            if not p.accept(","):
                break
        p.expect("}")
        del typ

        def build(vm: VM) -> dict[str, Any]:
            return {f: v(vm) for f, v in items}

        return build

    def system(self, t: Token) -> Fn:
        p = self.p
        name = t.upper
        if name in ("$IN", "$OUT"):
            p.expect("[")
            idx = self.ex.parse()
            p.expect("]")
            return lambda vm: _io_read(vm, name, int(number(idx(vm))), "")
        if name == "$POS_ACT":
            return lambda vm: {**pose_dict(vm.motion.program_pose(vm.motion.joints())),
                               **_st(vm)}  # fmt: skip
        if name == "$AXIS_ACT":
            return lambda vm: {
                f"A{i + 1}": math.degrees(v) for i, v in enumerate(vm.motion.joints())
            }
        full = name
        save = p.i
        if p.accept("."):
            full += "." + p.expect_kind("id", "a field").upper
        if full in SETTINGS:
            key = SETTINGS[full]
            return lambda vm: vm.lang[key]
        p.i = save
        raise error(t.loc, f"reading {full} is not supported by workcell's KRL reader")


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


def _seconds(v: Any) -> float:
    s = number(v, "WAIT SEC's seconds")
    if s < 0:
        raise ProgramError(f"WAIT SEC needs seconds >= 0, got {s:g}")
    return s


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


def read(path: Path, outputs: dict[int, str], inputs: dict[int, str]) -> RobotProgram:
    """Read a KRL ``.src`` (and the ``.dat`` beside it) as a :class:`RobotProgram`."""
    r = KrlReader(str(path))
    dat = next(
        (s for s in path.parent.glob("*") if s.stem.lower() == path.stem.lower()
         and s.suffix.lower() == ".dat" and s != path),
        None,
    )  # fmt: skip
    if dat is not None:
        r.read_file(dat)
    r.read_file(path)
    if r.main is None:
        raise error(Loc(str(path), 1, 1), "no DEF routine in the file")
    for name, (kind, n) in r.signals.items():
        (outputs if kind == "$OUT" else inputs).setdefault(n, name.lower())
    routines = {k: c.finish() for k, c in r.routines.items()}
    check_calls(routines, "KRL")
    return RobotProgram(str(path), "krl", routines, r.main, r.setup, inputs, outputs)
