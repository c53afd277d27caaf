"""KRL expressions and system variables (a mixin of
:class:`~workcell.robotprog.read_krl.KrlReader`): values, names, fields, elements,
aggregates, ``$IN``/``$OUT``, ``$POS_ACT``/``$AXIS_ACT`` and the settings it reads, and
what an assignment to a system variable does.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from workcell.errors import ProgramError
from workcell.robotprog.exprs import ExprParser, Fn, boolean, number
from workcell.robotprog.krl_run import (
    _element_of,
    _field_of,
    _index,
    _io_name,
    _io_read,
    _st,
)
from workcell.robotprog.kuka_values import (
    frame_matrix,
    pose_dict,
    tcp_of_tool,
)
from workcell.robotprog.runtime import VM
from workcell.robotprog.source import Parser, Token, error

__all__ = ["IGNORED", "SETTINGS", "KrlExpressions"]

SETTINGS = {
    "$VEL.CP": "vel_cp", "$ACC.CP": "acc_cp", "$OV_PRO": "ov", "$APO.CDIS": "cdis",
    "$APO.CPTP": "cptp",
}  # fmt: skip
IGNORED = {"$VEL.ORI1", "$VEL.ORI2", "$ACC.ORI1", "$ACC.ORI2", "$ADVANCE", "$BWDSTART"}


class KrlExpressions:
    """Expressions and system-variable assignments of the KRL reader."""

    p: Parser
    ex: ExprParser
    types: dict[str, str]
    signals: dict[str, tuple[str, int]]

    def _system_setter(self, t: Token, name: str, index: Fn | None, fields: list[str]) -> Any:
        full = name + "".join("." + f for f in fields)
        if full in IGNORED:
            return lambda vm, v: None
        if full in SETTINGS:
            key = SETTINGS[full]

            def set_number(vm: VM, v: Any) -> None:
                x = number(v, full)
                if x < 0 or (key == "ov" and not 0 < x <= 100):
                    valid = "in (0, 100] %" if key == "ov" else ">= 0"
                    raise ProgramError(f"{full} = {x:g} is out of range: it must be {valid}")
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
