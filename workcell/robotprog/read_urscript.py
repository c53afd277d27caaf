"""Universal Robots URScript: the reader (``.script``).

Read: ``#`` comments, ``def name():`` ... ``end`` (the statements outside any ``def`` run,
else the file's only or first ``def``), assignments (``global``/``local`` too) with
arithmetic, lists, poses ``p[x, y, z, rx, ry, rz]`` and indexing, ``if``/``elif``/``else``,
``while`` (bounded by the work budget; ``while not <input>: sync() end`` is an input
wait), calls of the file's functions, ``return``; ``movej`` (joints, or a pose solved
near the current joints), ``movel``, ``movec`` (``mode=0``), ``set_tcp``,
``set_standard_digital_out``/``set_digital_out``, ``get_standard_digital_in``/
``get_digital_in``, ``sleep``, ``sync`` (2 ms, one controller cycle), ``textmsg`` (nothing to
show), ``pose_trans``, ``pose_add``, ``pose_inv``, ``get_inverse_kin(p, qnear=q)``,
``get_actual_joint_positions()``, ``get_actual_tcp_pose()``, ``d2r``, ``r2d``, ``sqrt``,
``sin``, ``cos``, ``norm``.

Semantics: ``movej``'s ``v`` and ``a`` are the leading axis's speed (rad/s) and
acceleration (rad/s^2): the simulator's "trapezoid" profile; ``movel``/``movec`` run at
``v`` m/s and ``a`` m/s^2; ``r`` is the zone (m). Defaults as UR's: movej a=1.4, v=1.05;
movel/movec a=1.2, v=0.25. Moves by time (``t=``), ``movec`` ``mode=1``, ``movep``,
``servoj``, ``speedj``/``speedl``, threads and everything else stop with a ProgramError.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from workcell.errors import ProgramError
from workcell.robotprog.exprs import Fn, number
from workcell.robotprog.reading import Reader, branch, while_loop
from workcell.robotprog.runtime import VM, Code, RobotProgram
from workcell.robotprog.source import NUMBER, Loc, Token, error, tokenize
from workcell.robotprog.urscript_run import (
    BINARY,
    BUILTINS,
    UNARY,
    Pose,
    _builtin,
    _index_of,
    _name,
)

__all__ = ["Pose", "read"]

RULES = [
    ("_ws", r"[ \t\r\f]+"),
    ("_cont", r"\\\n"),
    ("_comment", r"#[^\n]*"),
    ("nl", r"\n"),
    ("num", NUMBER),
    ("str", r'"[^"\n]*"|\'[^\'\n]*\''),
    ("pose", r"p\["),
    ("id", r"[A-Za-z_][A-Za-z0-9_]*"),
    ("op", r"==|!=|>=|<=|[-+*/%()\[\],:=<>]"),
]


class UrReader(Reader):
    """Reads one URScript file (module doc)."""

    language, binary, unary, case_sensitive = "URScript", BINARY, UNARY, True

    def read(self, text: str) -> str:
        p = self.parse(tokenize(text, self.path, RULES))
        top = Code("#TOP")
        p.skip_nl()
        while p.tok.kind != "eof":
            if p.at("def"):
                self.function()
            else:
                self.statement(top, None)
            p.skip_nl()
        if top.ops:
            self.routines["#TOP"] = top
            return "#TOP"
        if self.first is None:
            raise error(Loc(self.path, 1, 1), "no statements and no def in the file")
        return self.first

    def function(self) -> None:
        p = self.p
        p.next()
        name = p.expect_kind("id", "the function's name")
        p.expect("(")
        if not p.at(")"):
            raise p.unsupported("a function with parameters")
        p.next()
        p.expect(":", "':'")
        p.end_line()
        code = self.define(name, name.text, "function")
        self.block(code, {"end"}, None)
        p.next()
        p.end_line()

    def statement(self, code: Code, loop_end: str | None) -> None:
        p = self.p
        t = p.tok
        if t.kind != "id":
            raise p.fail("expected a statement")
        w = t.text
        if w == "if":
            self.if_(code, loop_end)
        elif w == "while":
            self.while_(code)
        elif w == "return":
            p.next()
            p.end_line()
            code.ret(t.loc)
        elif w in ("global", "local"):
            p.next()
            self.assignment(code)
        elif w in ("thread", "run", "join", "kill", "halt", "break", "continue", "enter_critical",
                   "exit_critical", "def", "for"):  # fmt: skip
            raise p.unsupported(f"'{w}'")
        elif p.peek().text == "=" or (p.peek().text == "[" and self._indexed_assignment()):
            self.assignment(code)
        elif p.peek().text == "(" and w not in BUILTINS:
            p.next()
            p.next()
            if not p.accept(")"):
                raise p.unsupported("a call with arguments")
            p.end_line()
            code.call(t.loc, w)
        elif p.peek().text == "(":
            call = self.call_expr(p.next())
            p.end_line()
            code.do(t.loc, lambda vm: call(vm))
        else:
            raise p.fail("expected an assignment or a call")

    def _indexed_assignment(self) -> bool:
        p = self.p
        depth, i = 0, p.i + 1
        while i < len(p.toks) and p.toks[i].kind not in ("nl", "eof"):
            if p.toks[i].text == "[":
                depth += 1
            elif p.toks[i].text == "]":
                depth -= 1
                if depth == 0:
                    return p.toks[i + 1].text == "="
            i += 1
        return False

    def assignment(self, code: Code) -> None:
        p = self.p
        t = p.expect_kind("id", "a variable name")
        index = None
        if p.accept("["):
            index = self.ex.parse()
            p.expect("]")
        p.expect("=", "'='")
        value = self.ex.parse()
        p.end_line()

        def run(vm: VM) -> None:
            v = value(vm)
            if index is None:
                vm.vars[t.text] = v
                return
            target = vm.vars.get(t.text)
            if not isinstance(target, list):
                raise ProgramError(f"{t.text} is not a list")
            i = int(number(index(vm), "an index"))
            if not 0 <= i < len(target):
                raise ProgramError(f"{t.text}[{i}] is outside the list (0 to {len(target) - 1})")
            target[i] = v

        code.do(t.loc, run)

    def if_(self, code: Code, loop_end: str | None) -> None:
        p = self.p
        t = p.next()
        done = code.new_label()
        cond = self.ex.parse()
        while True:
            p.expect(":", "':'")
            p.end_line()
            branch(
                code, t.loc, cond, lambda: self.block(code, {"elif", "else", "end"}, loop_end), done
            )
            if p.at("elif"):
                t = p.next()
                cond = self.ex.parse()
                continue
            if p.accept("else"):
                p.expect(":", "':'")
                p.end_line()
                self.block(code, {"end"}, loop_end)
            p.expect("end")
            p.end_line()
            break
        code.place(done)

    def while_(self, code: Code) -> None:
        p = self.p
        t = p.next()
        start = p.i
        wait = self._input_wait()
        if wait is not None:
            n, value = wait
            code.do(t.loc, lambda vm: vm.motion.wait_input(n, _name(vm, n), value))
            return
        p.i = start
        cond = self.ex.parse()
        p.expect(":", "':'")
        p.end_line()

        def body(done: str) -> None:
            self.block(code, {"end"}, done)
            p.next()
            p.end_line()

        while_loop(code, t.loc, cond, body)

    def _input_wait(self) -> tuple[int, bool] | None:
        """``[not] get_(standard_)digital_in(n) [== True|False]: sync()|sleep(x) ... end``:
        (input number, value waited for); None for other loops (the cursor moved)."""
        p = self.p
        neg = bool(p.accept("not"))
        paren = bool(p.accept("("))
        fn = p.next()
        if fn.text not in ("get_standard_digital_in", "get_digital_in") or not p.accept("("):
            return None
        num = p.next()
        if num.kind != "num" or not p.accept(")"):
            return None
        value = True
        if p.accept("=="):
            lit = p.next()
            if lit.text not in ("True", "False"):
                return None
            value = lit.text == "True"
        if paren and not p.accept(")"):
            return None
        if not p.accept(":"):
            return None
        # the loop runs while the condition holds: it waits for its negation
        waited = value if neg else not value
        p.skip_nl()
        while not p.at("end"):
            t = p.next()
            if t.text not in ("sync", "sleep") or not p.accept("("):
                return None
            while not p.accept(")"):
                if p.tok.kind in ("nl", "eof"):
                    return None
                p.next()
            p.skip_nl()
        p.next()
        p.end_line()
        return int(float(num.text)), waited

    # ------------------------------------------------------------------ expressions
    def primary(self) -> Fn:
        p = self.p
        t = p.tok
        if t.kind == "num":
            p.next()
            v = float(t.text) if any(c in t.text for c in ".eE") else int(t.text)
            return self.postfix(lambda vm: v)
        if t.kind == "str":
            p.next()
            s = t.text[1:-1]
            return lambda vm: s
        if t.text == "(":
            p.next()
            inner = self.ex.parse()
            p.expect(")")
            return self.postfix(inner)
        if t.kind == "pose" or t.text == "[":
            p.next()
            items = self.items("]")
            if t.kind == "pose":
                if len(items) != 6:
                    raise error(t.loc, f"a pose has 6 numbers, got {len(items)}")
                return self.postfix(
                    lambda vm: Pose(number(f(vm), "a pose's number") for f in items)
                )
            return self.postfix(lambda vm: [f(vm) for f in items])
        if t.kind == "id":
            p.next()
            if t.text in ("True", "False"):
                return lambda vm: t.text == "True"
            if p.at("("):
                return self.postfix(self.call_expr(t))

            def var(vm: VM) -> Any:
                if t.text not in vm.vars:
                    raise error(t.loc, f"{t.text} has no value")
                return vm.vars[t.text]

            return self.postfix(var)
        raise p.fail("expected a value")

    def postfix(self, base: Fn) -> Fn:
        p = self.p
        while p.at("["):
            t = p.next()
            idx = self.ex.parse()
            p.expect("]")
            base = _index_of(base, idx, t)
        return base

    def call_expr(self, t: Token) -> Fn:
        p = self.p
        p.expect("(")
        args: list[Fn] = []
        kw: dict[str, Fn] = {}
        while not p.at(")"):
            if p.tok.kind == "id" and p.peek().text == "=":
                k = p.next().text
                p.next()
                kw[k] = self.ex.parse()
            else:
                if kw:
                    raise p.fail("a positional argument after a named one")
                args.append(self.ex.parse())
            if not p.accept(","):
                break
        p.expect(")")
        name = t.text
        if name in BUILTINS:
            spec = BUILTINS[name]
            return lambda vm: _builtin(
                vm, name, spec, [f(vm) for f in args], {k: f(vm) for k, f in kw.items()}
            )
        raise error(
            t.loc,
            f"{name}(...) as a value is not supported by workcell's URScript reader "
            "(the file's functions are called as statements)",
        )


def read(path: Path, outputs: dict[int, str], inputs: dict[int, str]) -> RobotProgram:
    """Read a URScript file as a :class:`RobotProgram`."""
    r = UrReader(str(path))
    main = r.read(path.read_text(encoding="utf-8", errors="replace"))
    return r.program("urscript", main, [], inputs, outputs)
