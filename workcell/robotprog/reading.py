"""What the four readers share (:mod:`.read_krl`, :mod:`.read_rapid`, :mod:`.read_urscript`,
:mod:`.read_fanuc`): the reader of one file and the loops every language compiles alike.

- :class:`Reader`: a file's routines as they are read, the parser and the expression
  parser over its tokens (:meth:`Reader.parse`), a routine defined once
  (:meth:`Reader.define`), the statements of a block (:meth:`Reader.block`), lists of
  expressions (:meth:`Reader.items`) and the :class:`~workcell.robotprog.runtime.RobotProgram`
  it reads (:meth:`Reader.program`);
- :func:`while_loop`, :func:`variable_loop`, :func:`branch`: the ops of a WHILE (or an
  endless LOOP), of a FOR over a program variable and of one branch of an IF chain.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Any

from workcell.robotprog.exprs import ExprParser, Fn
from workcell.robotprog.runtime import VM, Code, RobotProgram, check_calls
from workcell.robotprog.source import Loc, Parser, Token, error

__all__ = ["Reader", "branch", "variable_loop", "while_loop"]


class Reader(ABC):
    """Reads one program file at ``path``: :attr:`routines` (:class:`Code` by name, in the
    order defined) and :attr:`first`, the first one's name. A language's reader sets
    :attr:`language` (its name in messages), :attr:`binary` and :attr:`unary` (its
    operators, :class:`~workcell.robotprog.exprs.ExprParser`), :attr:`case_sensitive`,
    and defines ``primary()`` (an operand) and ``statement(code, ...)``."""

    language = ""
    binary: dict[str, Any] = {}  # noqa: RUF012 - each language's table, never changed
    unary: dict[str, Any] = {}  # noqa: RUF012
    case_sensitive = False  # block ends compare the words' text, else their upper case
    p: Parser
    ex: ExprParser

    def __init__(self, path: str) -> None:
        self.path = path
        self.routines: dict[str, Code] = {}
        self.first: str | None = None

    def parse(self, tokens: list[Token]) -> Parser:
        """Read ``tokens`` from now on: :attr:`p` over them, :attr:`ex` for expressions."""
        self.p = Parser(tokens, self.language)
        self.ex = ExprParser(self.p, self.binary, self.unary, self.primary)
        return self.p

    @abstractmethod
    def primary(self) -> Fn:
        """An operand of an expression (each language's own)."""

    @abstractmethod
    def statement(self, code: Code, *context: Any) -> None:
        """Read one statement into ``code`` (each language's own)."""

    def define(self, name: Token, key: str, what: str) -> Code:
        """The code of a new routine ``key`` (its name as the language compares names)
        named by token ``name``; ``what`` ("routine", "procedure", ...) names it in the
        ProgramError when it is defined twice."""
        if key in self.routines:
            raise error(name.loc, f"{what} {name.text} is defined twice")
        code = self.routines[key] = Code(key)
        self.first = self.first or key
        return code

    def block(self, code: Code, until: set[str], *context: Any) -> None:
        """Statements into ``code`` up to one of the words ``until`` (not read); line ends
        between them are skipped; ``context`` goes to each ``statement``."""
        p = self.p
        p.skip_nl()
        while not (
            p.tok.kind == "id" and (p.tok.text if self.case_sensitive else p.tok.upper) in until
        ):
            if p.tok.kind == "eof":
                raise p.fail(f"expected {' or '.join(sorted(until))}")
            self.statement(code, *context)
            p.skip_nl()

    def items(self, close: str) -> list[Fn]:
        """Expressions separated by commas up to ``close``, which is read too."""
        p = self.p
        out = []
        while not p.at(close):
            out.append(self.ex.parse())
            if not p.accept(","):
                break
        p.expect(close)
        return out

    def program(
        self,
        language: str,
        main: str,
        setup: list[Callable[[VM], None]],
        inputs: dict[int, str],
        outputs: dict[int, str],
    ) -> RobotProgram:
        """The program read: its routines finished and every call checked (a ProgramError
        at a jump to no label or a call of no routine); ``language`` is its id ("krl")."""
        routines = {k: c.finish() for k, c in self.routines.items()}
        check_calls(routines, self.language)
        return RobotProgram(self.path, language, routines, main, setup, inputs, outputs)


def while_loop(code: Code, loc: Loc, cond: Fn | None, body: Callable[[str], object]) -> None:
    """A loop at ``loc`` whose ``body`` (a function that reads its statements and its end,
    given the label after the loop: where an EXIT jumps) runs while ``cond`` holds, or
    for ever (``cond`` None: until an EXIT)."""
    top, done = code.new_label(), code.new_label()
    code.place(top)
    if cond is not None:
        code.unless(loc, cond, done)
    body(done)
    code.jump(loc, top)
    code.place(done)


def variable_loop(
    code: Code,
    loc: Loc,
    var: str,
    start: Fn,
    stop: Fn,
    step: Fn,
    body: Callable[[str], Loc],
    *,
    whole: bool = False,
) -> None:
    """A FOR at ``loc`` over the program variable ``var`` (``whole``: kept a whole number)
    from ``start`` to ``stop`` by ``step`` (:meth:`Code.for_open`): ``body`` reads the
    statements and the loop's end, given the label after the loop, and returns the end's
    place."""

    def get(vm: VM) -> Any:
        return vm.vars[var]

    def put(vm: VM, v: float) -> None:
        vm.vars[var] = int(v) if whole else v

    head = code.for_open(loc, get, put, start, stop, step)
    code.for_close(body(head[2]), get, put, head)


def branch(code: Code, loc: Loc, cond: Fn, body: Callable[[], object], done: str) -> None:
    """One branch of an IF ... ELSEIF ... chain at ``loc``: ``body`` (a function that reads
    its statements) runs when ``cond`` holds and the chain goes on at label ``done``;
    otherwise the next branch."""
    other = code.new_label()
    code.unless(loc, cond, other)
    body()
    code.jump(loc, done)
    code.place(other)
