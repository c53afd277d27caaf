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

from workcell.robotprog.exprs import Fn
from workcell.robotprog.krl_data import KrlData
from workcell.robotprog.krl_exprs import KrlExpressions
from workcell.robotprog.krl_run import (
    BINARY,
    DEF_ACC_CP,
    DEF_VEL_CP,
    UNARY,
    _bas,
    _io_name,
    _move,
    _wait_for,
)
from workcell.robotprog.reading import Reader, variable_loop, while_loop
from workcell.robotprog.runtime import VM, Code, RobotProgram
from workcell.robotprog.source import NUMBER, Loc, error, tokenize

__all__ = ["read"]

RULES = [
    ("_ws", r"[ \t\r\f]+"),
    ("_comment", r";[^\n]*"),
    ("_attr", r"&[^\n]*"),
    ("nl", r"\n"),
    ("bits", r"'[BbHh][0-9A-Fa-f]+'"),
    ("num", NUMBER),
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


class KrlReader(KrlData, KrlExpressions, Reader):
    """Reads one KRL program (module doc)."""

    language, binary, unary = "KRL", BINARY, UNARY

    def __init__(self, path: str) -> None:
        super().__init__(path)
        self.types: dict[str, str] = {}
        self.signals: dict[str, tuple[str, int]] = {}
        self.setup: list[Any] = [_setup]

    # ------------------------------------------------------------------ files
    def read_file(self, path: Path) -> None:
        text = path.read_text(encoding="utf-8", errors="replace")
        p = self.parse(tokenize(text, str(path), RULES))
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

    def routine(self) -> None:
        p = self.p
        p.next()
        name_tok = p.expect_kind("id", "the routine's name")
        code = self.define(name_tok, name_tok.upper, "routine")
        p.expect("(")
        if not p.at(")"):
            raise p.unsupported("a routine with parameters")
        p.next()
        p.end_line()
        self.block(code, {"END"}, None)
        p.next()
        p.end_line()

    # ------------------------------------------------------------------ statements
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
        elif u in ("WHILE", "LOOP"):
            p.next()
            cond = self.condition() if u == "WHILE" else None
            p.end_line()
            while_loop(code, t.loc, cond, lambda done: self._to_end(code, "END" + u, done))
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

    def _to_end(self, code: Code, end: str, exit_label: str | None) -> Loc:
        """The statements of a loop's body and its ``end`` line; the end's place."""
        self.block(code, {end}, exit_label)
        t = self.p.next()
        self.p.end_line()
        return t.loc

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
            negative = p.accept("-") is not None
            if not negative:
                p.accept("+")
            if p.tok.kind != "num":
                raise error(step_tok.loc, "STEP must be a constant number (e.g. STEP -2)")
            step = self.ex.parse()
            if negative:
                k = step
                step = lambda vm: -k(vm)  # noqa: E731
        p.end_line()
        body = lambda done: self._to_end(code, "ENDFOR", done)  # noqa: E731
        variable_loop(code, t.loc, var, start, stop, step, body, whole=True)

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
    if r.first is None:
        raise error(Loc(str(path), 1, 1), "no DEF routine in the file")
    for name, (kind, n) in r.signals.items():
        (outputs if kind == "$OUT" else inputs).setdefault(n, name.lower())
    return r.program("krl", r.first, r.setup, inputs, outputs)
