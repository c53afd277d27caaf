"""RAPID expressions (a mixin of :class:`~workcell.robotprog.read_rapid.RapidReader`):
numbers, strings, aggregates ``[...]``, data and their components and elements, the
signals the file's header lists, and the functions ``Offs``, ``RelTool``, ``CRobT``,
``CJointT``, ``DInput`` and ``Abs``, ``Sqrt``, ``Sin``, ``Cos``, ``Tan``, ``Round``,
``Trunc``.
"""

from __future__ import annotations

import math
from typing import Any

from workcell.robotprog.exprs import ExprParser, Fn, number
from workcell.robotprog.rapid_run import (
    MATH,
    PREDEFINED,
    _component_of,
    _crobt,
    _dinput,
    _element_of,
    _offs,
    _reltool,
)
from workcell.robotprog.runtime import VM
from workcell.robotprog.source import Parser, Token, error

__all__ = ["RapidExpressions"]


class RapidExpressions:
    """Expressions of the RAPID reader."""

    p: Parser
    ex: ExprParser
    types: dict[str, str]
    signals: set[str]
    items: Any  # Reader's: expressions separated by commas up to a closing bracket

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
            items = self.items("]")
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
