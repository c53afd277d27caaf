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

from pathlib import Path
from typing import Any

from workcell.errors import ProgramError
from workcell.robotprog.exprs import ExprParser, Fn, boolean, number
from workcell.robotprog.krl_exprs import KrlExpressions
from workcell.robotprog.krl_run import (
    BINARY,
    DEF_ACC_CP,
    DEF_VEL_CP,
    UNARY,
    _bas,
    _convert,
    _index,
    _io_name,
    _move,
    _wait_for,
)
from workcell.robotprog.kuka_values import (
    SIMPLE_TYPES,
    STRUCT_TYPES,
)
from workcell.robotprog.runtime import VM, Code, RobotProgram, check_calls
from workcell.robotprog.source import Loc, Parser, error, tokenize

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

ENDS = {"END", "ENDIF", "ELSE", "ENDFOR", "ENDWHILE", "UNTIL", "ENDLOOP", "ENDDAT"}


def _setup(vm: VM) -> None:
    vm.lang.update(
        vel_cp=DEF_VEL_CP, acc_cp=DEF_ACC_CP, ov=100.0, cdis=0.0, cptp=0.0,
        vel_axis=[100.0] * 6, acc_axis=[100.0] * 6, ori="#VAR", circ="#BASE",
    )  # fmt: skip


class KrlReader(KrlExpressions):
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
            code.do(t.loc, lambda vm: vm.motion.dwell(secs(vm), "WAIT SEC"))
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
