"""KRL data (a mixin of :class:`~workcell.robotprog.read_krl.KrlReader`): declarations
(``DECL``, the typed ones, arrays of one dimension, ``SIGNAL name $OUT[n]``), data lists
(``DEFDAT`` ... ``ENDDAT``) and assignments to variables, elements, fields, output
signals and system variables (:mod:`workcell.robotprog.krl_exprs`).
"""

from __future__ import annotations

from typing import Any

from workcell.errors import ProgramError
from workcell.robotprog.exprs import ExprParser, Fn, boolean, number
from workcell.robotprog.krl_run import _convert, _index
from workcell.robotprog.kuka_values import SIMPLE_TYPES, STRUCT_TYPES
from workcell.robotprog.runtime import VM, Code
from workcell.robotprog.source import Loc, Parser, Token, error

__all__ = ["KrlData"]


class KrlData:
    """Declarations, data lists and assignments of the KRL reader."""

    p: Parser
    ex: ExprParser
    path: str
    types: dict[str, str]
    signals: dict[str, tuple[str, int]]
    setup: list[Any]
    _system_setter: Any  # KrlExpressions': the setter of a system variable

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
        t: Token = p.next()
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
                raise ProgramError(
                    f"{t.text} has no fields: it is a {type(holder).__name__} value, not a "
                    "structure (E6POS, FRAME, ...)"
                )
            holder[fields[-1]] = v

        return set_var
