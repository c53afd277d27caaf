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

from pathlib import Path
from typing import Any

from workcell.errors import ProgramError
from workcell.robotprog.exprs import Fn, number
from workcell.robotprog.rapid_exprs import RapidExpressions
from workcell.robotprog.rapid_run import (
    ATOMS,
    BINARY,
    INSTRUCTIONS,
    PREDEFINED,
    RECORDS,
    UNARY,
    _array_index,
    _component,
    _instruction,
    _run_data,
    _setup,
    record,
)
from workcell.robotprog.reading import Reader, branch, variable_loop, while_loop
from workcell.robotprog.runtime import VM, Code, RobotProgram
from workcell.robotprog.source import NUMBER, Loc, error, tokenize

__all__ = ["read"]

RULES = [
    ("_ws", r"[ \t\r\f\n]+"),
    ("_comment", r"![^\n]*"),
    ("num", NUMBER),
    ("str", r'"[^"\n]*"'),
    ("id", r"[A-Za-z_][A-Za-z0-9_]*"),
    ("op", r":=|<>|>=|<=|[-+*/(){}\[\],.:;=<>\\]"),
]


class RapidReader(RapidExpressions, Reader):
    """Reads one RAPID module (module doc)."""

    language, binary, unary = "RAPID", BINARY, UNARY

    def __init__(self, path: str) -> None:
        super().__init__(path)
        self.types: dict[str, str] = {k.upper(): t for k, (t, _) in PREDEFINED.items()}
        self.setup: list[Any] = [_setup]
        self.signals: set[str] = set()

    def read(self, text: str) -> None:
        p = self.parse(tokenize(text, self.path, RULES))
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
        code = self.define(name, name.upper, "procedure")
        while p.at("VAR", "PERS", "CONST", "LOCAL"):
            p.accept("LOCAL")
            self.declaration(code)
        self.block(code, {"ENDPROC"})
        p.next()

    # ------------------------------------------------------------------ statements
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
            cond = self.ex.parse()
            p.expect("DO")
            while_loop(code, t.loc, cond, lambda done: self._to_end(code, "ENDWHILE"))
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
            branch(code, t.loc, cond, lambda: self.block(code, {"ELSEIF", "ELSE", "ENDIF"}), done)
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
        body = lambda done: self._to_end(code, "ENDFOR")  # noqa: E731
        variable_loop(code, t.loc, var, start, stop, step, body)

    def _to_end(self, code: Code, end: str) -> Loc:
        """The statements of a loop's body and its ``end``; the end's place."""
        self.block(code, {end})
        return self.p.next().loc


def read(path: Path, outputs: dict[int, str], inputs: dict[int, str]) -> RobotProgram:
    """Read a RAPID module as a :class:`RobotProgram`."""
    r = RapidReader(str(path))
    r.signals = {s.lower() for s in (*outputs.values(), *inputs.values())}
    text = path.read_text(encoding="utf-8", errors="replace")
    r.read(text)
    if not r.routines:
        raise error(Loc(str(path), 1, 1), "no PROC in the module")
    main = "MAIN" if "MAIN" in r.routines else r.first
    return r.program("rapid", main or "", r.setup, inputs, outputs)
