"""FANUC TP as ASCII (``.ls``): the reader.

Read: ``/PROG``, ``/ATTR`` and ``/APPL`` (their contents are the editor's: not run),
``/MN`` with numbered lines and ``:`` continuation lines, ``/POS`` (Cartesian positions
X, Y, Z mm, W, P, R deg with UF, UT and CONFIG; joint positions J1..J6 deg, the
controller's J3), ``/END``; statements: ``!`` remarks and ``//`` commented lines,
``J``/``L`` to ``P[n]`` or ``PR[n]`` at ``n%`` (J), ``mm/sec``, ``cm/min``, ``inch/min``
(L, C) with ``FINE`` or ``CNTn`` and the options ``ACCn`` and ``Offset,PR[n]``, ``C P[via]``
with the end on the next line, ``DO[n]=ON|OFF`` and ``RO[n]``, ``WAIT s(sec)``, ``WAIT
DI[n]=ON|OFF``, ``R[n]=`` and ``PR[n,i]=`` arithmetic, ``PR[n]=P[m]|PR[m]|LPOS|JPOS``,
``LBL[n]``, ``JMP LBL[n]``, ``IF <cond>,JMP LBL[n]``, ``IF (cond) THEN``/``ELSE``/``ENDIF``,
``FOR R[n]=a TO|DOWNTO b``/``ENDFOR``, ``UFRAME_NUM=n``, ``UTOOL_NUM=n``,
``UFRAME[n]=PR[m]``, ``UTOOL[n]=PR[m]``, ``OVERRIDE=n%``, ``END``.

Semantics: ``J ... n%`` runs at n % of each joint's limits x ``OVERRIDE``; ``CNTn`` is a
zone of n mm (CNT has no length); ``ACCn`` is n % of 1.2 m/s^2 for L and C (not simulated
for J); ``Offset,PR[n]`` moves the target by PR[n]'s frame in the user frame. UF 0 is
the robot's base, UT 0 the faceplate; a frame number the file does not set is the
robot's base, a tool number the robot's own TCP. A position taught in another UF or UT
than the active one is a ProgramError (as on the controller). ``CALL`` (other programs),
``SELECT``, timers, ``PAUSE``/``ABORT``, ``CR``, ``Wjnt``, ``INC``, ``Tool_Offset``, speeds
in sec or deg/sec, and everything else stop with a ProgramError at their place.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from workcell.robotprog.exprs import Fn, number
from workcell.robotprog.fanuc_file import positions, ref, sections, statements
from workcell.robotprog.fanuc_run import (
    BINARY,
    UNARY,
    Position,
    _constant,
    _current,
    _define_frame,
    _io,
    _move,
    _name,
    _override,
    _pr,
    _pr_element,
    _r,
    _set_frame_number,
    _set_pr,
    _set_pr_element,
    _set_r,
)
from workcell.robotprog.reading import Reader
from workcell.robotprog.runtime import VM, Code, RobotProgram
from workcell.robotprog.source import Loc, Token, error

__all__ = ["read"]


class FanucReader(Reader):
    """Reads one LS program (module doc)."""

    language, binary, unary = "FANUC TP", BINARY, UNARY

    def __init__(self, path: str) -> None:
        super().__init__(path)
        self.code = self.routines["MAIN"] = Code("MAIN")

    def read(self, text: str) -> None:
        parts = sections(text, self.path)
        self.positions = positions(parts.get("/POS", []), self.path)
        self.stack: list[tuple[str, Any]] = []
        for toks in statements(parts["/MN"], self.path):
            end = Loc(self.path, toks[-1].loc.line, toks[-1].loc.col + len(toks[-1].text))
            self.parse([*toks, Token("eof", "", end)])
            self.statement()
        if self.stack:
            kind, loc = self.stack[-1]
            raise error(loc, f"{kind} without its end")

    # ------------------------------------------------------------------ statements
    def statement(self) -> None:
        p, code = self.p, self.code
        t = p.tok
        u = t.upper
        if u in ("J", "L", "C"):
            self.motion()
        elif u == "WAIT":
            p.next()
            if p.at("DI", "RI"):
                io = p.next()
                n, name = ref(p.expect_kind("ref", "an I/O number [n]"))
                p.expect("=")
                v = p.expect_kind("id", "ON or OFF").upper
                if v not in ("ON", "OFF"):
                    raise p.fail("expected ON or OFF")
                if p.tok.kind != "eof":
                    raise p.unsupported("WAIT with TIMEOUT")
                code.do(
                    t.loc,
                    lambda vm: vm.motion.wait_input(n, name or _name(vm, n, io.upper), v == "ON"),
                )
            else:
                secs = self.ex.parse()
                if p.tok.kind == "unit" and p.tok.text == "sec":
                    p.next()
                elif p.accept("("):
                    p.expect("sec")
                    p.expect(")")
                self.done()
                code.do(t.loc, lambda vm: vm.motion.dwell(secs(vm), "WAIT"))
        elif u in ("DO", "RO"):
            p.next()
            n, name = ref(p.expect_kind("ref", "an output number [n]"))
            p.expect("=")
            vt = p.expect_kind("id", "ON or OFF")
            v = vt.upper
            if v not in ("ON", "OFF"):
                raise p.unsupported(f"{u}[...]={vt.text}", vt)
            self.done()
            code.do(
                t.loc, lambda vm: vm.motion.set_output(n, name or _name(vm, n, "DO"), v == "ON")
            )
        elif u == "LBL":
            p.next()
            n, _ = ref(p.expect_kind("ref", "a label number"))
            self.done()
            code.place(f"LBL{n}", t.loc)
        elif u == "JMP":
            p.next()
            p.expect("LBL")
            n, _ = ref(p.expect_kind("ref", "a label number"))
            self.done()
            code.jump(t.loc, f"LBL{n}")
        elif u == "IF":
            self.if_()
        elif u == "ELSE":
            p.next()
            self.done()
            _kind, data = self.pop("IF", t)
            other, done = data
            code.jump(t.loc, done)
            code.place(other)
            self.stack.append(("ELSE", (None, done)))
        elif u == "ENDIF":
            p.next()
            self.done()
            _, (other, done) = self.pop(("IF", "ELSE"), t)
            if other is not None:
                code.place(other)
            code.place(done)
        elif u == "FOR":
            self.for_()
        elif u == "ENDFOR":
            p.next()
            self.done()
            _, (get, put, head) = self.pop("FOR", t)
            code.for_close(t.loc, get, put, head)
        elif u in ("UFRAME_NUM", "UTOOL_NUM"):
            p.next()
            p.expect("=")
            v = self.ex.parse()
            self.done()
            key = "uf" if u == "UFRAME_NUM" else "ut"
            code.do(t.loc, lambda vm: _set_frame_number(vm, key, v(vm)))
        elif u in ("UFRAME", "UTOOL") and p.peek().kind == "ref":
            p.next()
            n, _ = ref(p.next())
            p.expect("=")
            src = self.primary()
            self.done()
            key = "uframes" if u == "UFRAME" else "utools"
            code.do(t.loc, lambda vm: _define_frame(vm, key, n, src(vm)))
        elif u == "OVERRIDE":
            p.next()
            p.expect("=")
            v = self.ex.parse()
            p.expect("%")
            self.done()
            code.do(t.loc, lambda vm: _override(vm, v(vm)))
        elif u in ("R", "PR") and p.peek().kind in ("ref", "ref2"):
            self.assignment()
        elif u == "END":
            p.next()
            self.done()
            code.ret(t.loc)
        else:
            raise p.unsupported(f"the statement {t.text}")

    def done(self) -> None:
        if self.p.tok.kind != "eof":
            raise self.p.fail("expected the end of the statement")

    def pop(self, kinds: Any, t: Token) -> tuple[str, Any]:
        kinds = (kinds,) if isinstance(kinds, str) else kinds
        if not self.stack or self.stack[-1][0] not in kinds:
            raise error(t.loc, f"{t.text} without {' or '.join(kinds)}")
        return self.stack.pop()

    def assignment(self) -> None:
        p = self.p
        t = p.next()
        r = p.next()
        p.expect("=")
        value = self.ex.parse()
        self.done()
        if t.upper == "R":
            n, _ = ref(r)
            if r.kind == "ref2":
                raise error(r.loc, "R[n,i] is not a register")
            self.code.do(t.loc, lambda vm: _set_r(vm, n, number(value(vm), "R[...]")))
        elif r.kind == "ref2":
            n, i = (int(x) for x in r.text[1:-1].split(","))
            self.code.do(t.loc, lambda vm: _set_pr_element(vm, n, i, value(vm)))
        else:
            n, _ = ref(r)
            self.code.do(t.loc, lambda vm: _set_pr(vm, n, value(vm)))

    def if_(self) -> None:
        p, code = self.p, self.code
        t = p.next()
        if p.at("(") and self._then():
            cond = self.ex.parse()
            p.expect("THEN")
            self.done()
            other, done = code.new_label(), code.new_label()
            code.unless(t.loc, cond, other)
            self.stack.append(("IF", (other, done)))
            return
        cond = self.ex.parse()
        p.expect(",", "',' and JMP LBL[n]")
        if p.accept("JMP"):
            p.expect("LBL")
            n, _ = ref(p.expect_kind("ref", "a label number"))
            self.done()
            skip = code.new_label()
            code.unless(t.loc, cond, skip)
            code.jump(t.loc, f"LBL{n}")
            code.place(skip)
            return
        raise p.unsupported("IF ..., <action> other than JMP LBL[n]")

    def _then(self) -> bool:
        return any(tok.upper == "THEN" for tok in self.p.toks)

    def for_(self) -> None:
        p, code = self.p, self.code
        t = p.next()
        p.expect("R")
        reg, _ = ref(p.expect_kind("ref", "a register R[n]"))
        p.expect("=")
        start = self.ex.parse()
        d = p.next()
        if d.upper not in ("TO", "DOWNTO"):
            raise p.fail("expected TO or DOWNTO", d)
        stop = self.ex.parse()
        self.done()
        step = 1 if d.upper == "TO" else -1

        def get(vm: VM) -> float:
            return _r(vm, reg)

        def put(vm: VM, v: float) -> None:
            _set_r(vm, reg, v)

        head = code.for_open(t.loc, get, put, start, stop, lambda vm: step)
        self.stack.append(("FOR", (get, put, head)))

    def motion(self) -> None:
        p = self.p
        t = p.next()
        kind = t.upper
        via = None
        target = self.target()
        if kind == "C":
            via, target = target, self.target()
        speed: Fn = self.ex.parse()
        unit = p.tok
        if unit.text == "%":
            p.next()
            unit_text = "%"
        elif unit.kind == "unit":
            p.next()
            unit_text = unit.text
        else:
            raise p.fail("expected a speed unit (%, mm/sec, cm/min, inch/min)")
        if (kind == "J") != (unit_text == "%") or unit_text in ("sec", "msec", "deg/sec"):
            raise p.unsupported(f"{kind} at a speed in {unit_text}", unit)
        term = p.next()
        if term.upper == "FINE":
            cnt: Fn = lambda vm: 0.0  # noqa: E731
        elif term.upper.startswith("CNT"):
            rest = term.text[3:]
            if rest:
                v = float(rest)
                cnt = lambda vm: v  # noqa: E731
            else:
                cnt = self.ex.parse()
        else:
            raise p.unsupported(f"the termination {term.text}", term)
        acc: Fn | None = None
        offset: Fn | None = None
        while p.tok.kind != "eof":
            o = p.next()
            if o.upper.startswith("ACC"):
                rest = o.text[3:]
                acc = _constant(float(rest)) if rest else self.ex.parse()
            elif o.upper == "OFFSET":
                p.expect(",", "',PR[n]'")
                offset = self.primary()
            else:
                raise p.unsupported(f"the motion option {o.text}", o)
        self.code.do(
            t.loc, lambda vm: _move(vm, kind, target, via, speed, unit_text, cnt, acc, offset)
        )

    def target(self) -> Any:
        p = self.p
        t = p.next()
        if t.upper not in ("P", "PR") or p.tok.kind != "ref":
            raise p.fail("expected P[n] or PR[n]", t)
        n, _ = ref(p.next())
        if t.upper == "P":
            if n not in self.positions:
                raise error(t.loc, f"P[{n}] is not in /POS")
            pos = self.positions[n]
            return ("P", n, pos)
        return ("PR", n, None)

    # ------------------------------------------------------------------ expressions
    def primary(self) -> Fn:
        p = self.p
        t = p.next()
        if t.kind == "num":
            v = float(t.text)
            return lambda vm: v
        if t.text == "(":
            inner = self.ex.parse()
            p.expect(")")
            return inner
        u = t.upper
        if u in ("ON", "OFF"):
            return lambda vm: u == "ON"
        if u == "R" and p.tok.kind == "ref":
            n, _ = ref(p.next())
            return lambda vm: _r(vm, n)
        if u == "PR" and p.tok.kind == "ref2":
            n, i = (int(x) for x in p.next().text[1:-1].split(","))
            return lambda vm: _pr_element(vm, n, i)
        if u == "PR" and p.tok.kind == "ref":
            n, _ = ref(p.next())
            return lambda vm: _pr(vm, n)
        if u == "P" and p.tok.kind == "ref":
            n, _ = ref(p.next())
            if n not in self.positions:
                raise error(t.loc, f"P[{n}] is not in /POS")
            pos = self.positions[n]
            return lambda vm: Position(pos)
        if u in ("DI", "RI", "DO", "RO") and p.tok.kind == "ref":
            n, name = ref(p.next())
            return lambda vm: _io(vm, u, n, name)
        if u in ("LPOS", "JPOS"):
            return lambda vm: _current(vm, u)
        raise p.fail("expected a value", t)


def read(path: Path, outputs: dict[int, str], inputs: dict[int, str]) -> RobotProgram:
    """Read an LS program as a :class:`RobotProgram`."""
    r = FanucReader(str(path))
    r.read(path.read_text(encoding="utf-8", errors="replace"))
    return r.program("fanuc_ls", "MAIN", [], inputs, outputs)
