"""Expressions of the robot languages: a precedence-climbing parser that compiles an
expression into a function of the interpreter (:class:`~workcell.robotprog.runtime.VM`).

A reader gives the operator tables (binary: text -> (precedence, function of two
values); unary: text -> function of one) and the primary expressions of its language
(numbers, names, aggregates, calls). Operands are checked: arithmetic on anything but
numbers is a ProgramError at the operator's place.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from typing import Any

from workcell.errors import ProgramError
from workcell.robotprog.source import Loc, Parser, error

__all__ = ["ARITH", "COMPARE", "ExprParser", "Fn", "number"]

Fn = Callable[[Any], Any]


def number(v: Any, what: str = "a number") -> float:
    """``v`` as a float when it is a number (not a bool); ProgramError otherwise."""
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ProgramError(f"expected {what}, got {_show(v)}")
    return float(v)


def _show(v: Any) -> str:
    if isinstance(v, bool):
        return "TRUE" if v else "FALSE"
    if isinstance(v, int | float):
        return f"{v:g}"
    if isinstance(v, str):
        return repr(v)
    return type(v).__name__.lower() if not isinstance(v, dict) else "a structure"


def _arith(f: Callable[[float, float], float], sym: str) -> Callable[[Any, Any], Any]:
    def op(a: Any, b: Any) -> Any:
        x, y = number(a, f"a number left of {sym}"), number(b, f"a number right of {sym}")
        r = f(x, y)
        if not math.isfinite(r):
            raise ProgramError(f"{x:g} {sym} {y:g} is not a finite number")
        return int(r) if isinstance(a, int) and isinstance(b, int) and sym != "/" else r

    return op


def _div(x: float, y: float) -> float:
    if y == 0:
        raise ProgramError("division by zero")
    return x / y


ARITH = {
    "+": _arith(operator.add, "+"),
    "-": _arith(operator.sub, "-"),
    "*": _arith(operator.mul, "*"),
    "/": _arith(_div, "/"),
}


def _cmp(f: Callable[[Any, Any], bool], sym: str) -> Callable[[Any, Any], bool]:
    def op(a: Any, b: Any) -> bool:
        if isinstance(a, bool) or isinstance(b, bool):
            equality = sym in ("==", "<>", "!=", "=")
            if not (equality and isinstance(a, bool) and isinstance(b, bool)):
                raise ProgramError(f"cannot compare {_show(a)} {sym} {_show(b)}")
            return bool(f(a, b))
        return bool(f(number(a), number(b)))

    return op


COMPARE = {
    "==": _cmp(operator.eq, "=="),
    "=": _cmp(operator.eq, "="),
    "<>": _cmp(operator.ne, "<>"),
    "!=": _cmp(operator.ne, "!="),
    "<": _cmp(operator.lt, "<"),
    ">": _cmp(operator.gt, ">"),
    "<=": _cmp(operator.le, "<="),
    ">=": _cmp(operator.ge, ">="),
}


def boolean(v: Any, what: str) -> bool:
    if isinstance(v, bool):
        return v
    raise ProgramError(f"{what} needs TRUE or FALSE, got {_show(v)}")


def _placed(loc: Loc, f: Callable[[], Any]) -> Any:
    try:
        return f()
    except ProgramError as exc:
        if str(exc).startswith(loc.path + ":"):
            raise
        raise error(loc, str(exc)) from exc


class ExprParser:
    """Parses expressions from ``p`` (module doc). ``binary`` maps an operator's
    upper-case text to (precedence, function); ``unary`` to (precedence, function);
    ``primary()`` parses an operand."""

    def __init__(
        self,
        p: Parser,
        binary: dict[str, tuple[int, Callable[[Any, Any], Any]]],
        unary: dict[str, tuple[int, Callable[[Any], Any]]],
        primary: Callable[[], Fn],
    ) -> None:
        self.p, self.binary, self.unary, self.primary = p, binary, unary, primary

    def parse(self, min_prec: int = 0) -> Fn:
        p = self.p
        t = p.tok
        if t.kind != "str" and t.upper in self.unary:
            prec, f = self.unary[t.upper]
            p.next()
            operand = self.parse(prec)
            loc = t.loc

            def left(vm: Any, operand: Fn = operand, f: Callable = f) -> Any:
                return _placed(loc, lambda: f(operand(vm)))

        else:
            left = self.primary()
        while True:
            t = p.tok
            if t.kind in ("str", "nl", "eof") or t.upper not in self.binary:
                return left
            prec, f = self.binary[t.upper]
            if prec < min_prec:
                return left
            p.next()
            right = self.parse(prec + 1)
            loc = t.loc

            def combined(
                vm: Any, a: Fn = left, b: Fn = right, f: Callable = f, loc: Loc = loc
            ) -> Any:
                x, y = a(vm), b(vm)
                return _placed(loc, lambda: f(x, y))

            left = combined
