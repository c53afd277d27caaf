"""Running a robot program read from a file: the code, the interpreter and the motions.

A reader compiles each routine (KRL ``DEF``, RAPID ``PROC``, a URScript ``def``, a TP
program) into a flat list of :class:`Op` (a statement as a function of the :class:`VM`,
jumps for loops and ifs, calls) with the place it came from; :class:`RobotProgram` holds
them. :meth:`RobotProgram.run` executes the main routine in a simulator through
:class:`Executor`, which turns the language's motions into the simulator's commands with
the same semantics as a program written against the simulator:

- targets are the program's tool centre point (``tcp``; None: the robot's own) in the
  program's base frame (``base``, in the robot's base frame); they become the robot's
  own tool poses in the world;
- joint moves run under profile "jerk" at each joint's limits x (override x the joint
  speed fraction), or, for URScript's ``movej``, under profile "trapezoid" with the
  leading axis's speed and acceleration; the simulator's settings change only when the
  program's do (a setting between two moves ends a zone, as in the simulator);
- linear and circular moves: ``move_linear``/``move_circular`` at the tool speed and
  acceleration x the override, with the zone;
- Cartesian joint targets: the solution the vendor's configuration names
  (:func:`~workcell.robotprog.configs.select`);
- outputs: the one named ``gripper`` closes (True) and opens the robot's gripper; others
  set the cell's signal of that name when the simulator has signals (else they are only
  kept in :attr:`VM.outputs`); input waits need the cell's signals: without them an
  input is False, and waiting for one to be True is a ProgramError saying so.

Every error names the file, line and column of the statement that failed. The work is
bounded: ``limits.max_program_steps`` statements, routine calls 64 deep.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell import limits
from workcell.errors import ProgramError, WorkcellError
from workcell.robotprog.configs import letters, select, solutions
from workcell.robotprog.instructions import GRIPPER, tcp_of
from workcell.robotprog.source import Loc, error
from workcell.spatial import invert

__all__ = ["VM", "Code", "Executor", "Op", "RobotProgram", "Routine"]

Array = NDArray[np.float64]
Fn = Callable[["VM"], Any]
MAX_DEPTH = 64


@dataclass
class Op:
    """One step: ``kind`` "do" (run ``fn``), "jump" (to ``target``), "unless" (jump to
    ``target`` when ``fn`` is false), "call" (the routine named ``target``) or "return"."""

    loc: Loc
    kind: str
    fn: Fn | None = None
    target: Any = None


@dataclass
class Routine:
    """A routine's ops (jump targets resolved to indices)."""

    name: str
    ops: list[Op]


class Code:
    """Builds a routine: ops appended in order, labels placed and jumped to by name."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.ops: list[Op] = []
        self.labels: dict[str, int] = {}
        self._label_locs: dict[str, Loc] = {}
        self._n = 0

    def do(self, loc: Loc, fn: Fn) -> None:
        self.ops.append(Op(loc, "do", fn))

    def jump(self, loc: Loc, label: str) -> None:
        self.ops.append(Op(loc, "jump", target=label))

    def unless(self, loc: Loc, cond: Fn, label: str) -> None:
        self.ops.append(Op(loc, "unless", cond, label))

    def call(self, loc: Loc, name: str) -> None:
        self.ops.append(Op(loc, "call", target=name))

    def ret(self, loc: Loc) -> None:
        self.ops.append(Op(loc, "return"))

    def new_label(self) -> str:
        self._n += 1
        return f"#{self._n}"

    def place(self, label: str, loc: Loc | None = None) -> None:
        if label in self.labels and loc is not None:
            raise error(loc, f"label {label} is defined twice")
        self.labels[label] = len(self.ops)
        if loc is not None:
            self._label_locs[label] = loc

    def for_open(self, loc: Loc, get: Fn, put: Callable[[VM, float], None], start: Fn, stop: Fn,
                 step: Fn) -> tuple[str, str, str]:  # fmt: skip
        """The head of a counted loop (FOR): the counter (``get``/``put``) from ``start``
        while it has not passed ``stop`` (checked before each pass) by ``step`` (not 0);
        returns what :meth:`for_close` needs (the body comes between the two)."""
        key, top, done = f"for:{loc}", self.new_label(), self.new_label()

        def init(vm: VM) -> None:
            st = _number(step(vm), "the loop's STEP")
            if st == 0:
                raise ProgramError("a loop with STEP 0 would never end")
            put(vm, _number(start(vm), "the loop's start"))
            vm.lang[key] = (_number(stop(vm), "the loop's end"), st)

        def test(vm: VM) -> bool:
            hi, st = vm.lang[key]
            v = _number(get(vm), "the loop's counter")
            return v <= hi if st > 0 else v >= hi

        self.do(loc, init)
        self.place(top)
        self.unless(loc, test, done)
        return key, top, done

    def for_close(self, loc: Loc, get: Fn, put: Callable[[VM, float], None],
                  head: tuple[str, str, str]) -> None:  # fmt: skip
        """The end of a counted loop: the next value, back to the test."""
        key, top, done = head
        self.do(loc, lambda vm: put(vm, _number(get(vm), "the loop's counter") + vm.lang[key][1]))
        self.jump(loc, top)
        self.place(done)

    def finish(self) -> Routine:
        """The routine; a jump to a label never placed is a ProgramError at the jump."""
        for op in self.ops:
            if op.kind in ("jump", "unless"):
                if op.target not in self.labels:
                    raise error(op.loc, f"jump to {op.target}, which is not defined")
                op.target = self.labels[op.target]
        return Routine(self.name, self.ops)


def check_calls(routines: dict[str, Routine], language: str) -> None:
    """Every call names a routine of the file: ProgramError at the call otherwise."""
    for r in routines.values():
        for op in r.ops:
            if op.kind == "call" and op.target not in routines:
                mine = ", ".join(k for k in sorted(routines) if not k.startswith("#")) or "none"
                raise error(
                    op.loc,
                    f"{op.target} is not supported by workcell's {language} reader and is not "
                    f"a routine of this file (its routines: {mine})",
                )


@dataclass
class RobotProgram:
    """A program read from ``path`` in ``language``: its ``routines`` by name (upper case
    for the case-insensitive languages), the ``main`` one, and ``setup`` (run first: the
    data declarations). :meth:`run` executes it."""

    path: str
    language: str
    routines: dict[str, Routine]
    main: str
    setup: list[Callable[[VM], None]] = field(default_factory=list)
    inputs: dict[int, str] = field(default_factory=dict)
    outputs: dict[int, str] = field(default_factory=dict)

    def run(self, sim: Any, robot: str) -> VM:
        """Execute the program on ``robot`` in simulator ``sim`` (module doc). Returns the
        interpreter (its variables and outputs) when it ends; the simulator's errors keep
        their type, with the statement's file:line:column in front."""
        vm = VM(self, Executor(sim, robot))
        for f in self.setup:
            f(vm)
        vm.call(self.main, Loc(self.path, 1, 1), 0)
        return vm


class VM:
    """The interpreter's state: ``vars`` (the program's variables, by name), ``outputs``
    (I/O number -> value), ``lang`` (what a reader keeps for its own statements), and the
    :class:`Executor` ``motion``."""

    def __init__(self, program: RobotProgram, motion: Executor) -> None:
        self.program = program
        self.motion = motion
        self.vars: dict[str, Any] = {}
        self.lang: dict[str, Any] = {}
        self.steps = 0
        self.budget = limits.current().max_program_steps

    def call(self, name: str, loc: Loc, depth: int) -> None:
        routine = self.program.routines.get(name)
        if routine is None:
            known = ", ".join(sorted(self.program.routines)) or "none"
            raise error(loc, f"no routine {name!r} in this file; routines: {known}")
        if depth >= MAX_DEPTH:
            raise error(loc, f"calls nested more than {MAX_DEPTH} deep (a recursion?)")
        ops = routine.ops
        pc = 0
        while pc < len(ops):
            op = ops[pc]
            self.steps += 1
            if self.steps > self.budget:
                raise error(
                    op.loc,
                    f"the program ran more than {self.budget} statements (limit "
                    "max_program_steps): a loop that does not end?",
                )
            pc += 1
            if op.kind == "do":
                _guard(op, lambda op=op: op.fn(self))  # type: ignore[misc]
            elif op.kind == "jump":
                pc = op.target
            elif op.kind == "unless":
                if not _guard(op, lambda op=op: _truth(op, op.fn(self))):  # type: ignore[misc]
                    pc = op.target
            elif op.kind == "call":
                self.call(op.target, op.loc, depth + 1)
            else:
                return


def _number(v: Any, what: str) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ProgramError(f"{what} must be a number, got {v!r}")
    return float(v)


def _truth(op: Op, v: Any) -> bool:
    if isinstance(v, bool | np.bool_):
        return bool(v)
    if isinstance(v, int | float) and not isinstance(v, bool):
        return v != 0
    raise error(op.loc, f"a condition must be TRUE or FALSE, got {v!r}")


def _guard(op: Op, f: Callable[[], Any]) -> Any:
    """Run ``f``; an error without a place gets the op's."""
    try:
        return f()
    except WorkcellError as exc:
        msg = str(exc)
        if msg.startswith(op.loc.path + ":"):
            raise
        try:
            placed = type(exc)(f"{op.loc}: {msg}")
        except TypeError:  # an error type with other arguments
            placed = ProgramError(f"{op.loc}: {msg}")
        raise placed from exc
    except (ArithmeticError, ValueError, TypeError, IndexError, KeyError) as exc:
        raise error(op.loc, f"cannot evaluate: {exc}") from exc


class Executor:
    """The program's motions and I/O on robot ``robot`` of ``sim`` (module doc)."""

    def __init__(self, sim: Any, robot: str) -> None:
        name = sim._robot(robot)
        self.sim, self.robot = sim, name
        placement = sim.cell.robots[name]
        self.model = placement.robot
        self.world = placement.base
        self.own_tcp = tcp_of(self.model)
        self.tcp: Array | None = None  # the program's TCP in the flange frame
        self.base = np.eye(4)  # the program's base in the robot's base frame
        self.override = 1.0
        self.joint_fraction = 1.0
        self.trapezoid: tuple[float, float] | None = None  # URScript movej: (v, a)
        self.outputs: dict[int, bool] = {}

    # ------------------------------------------------------------------ frames
    def robot_pose(self, T: Array) -> Array:
        """The robot's own tool pose (its ``fk`` frame, robot base) for a program target
        ``T`` (the program's TCP in its base frame)."""
        F = self.base @ T if self.tcp is None else self.base @ T @ invert(self.tcp)
        return F if self.tcp is None else F @ self.own_tcp

    def program_pose(self, q: Array) -> Array:
        """The program's TCP pose in its base frame at joints q."""
        Tb = self.model.fk(q)
        F = Tb if self.tcp is None else Tb @ invert(self.own_tcp) @ self.tcp
        return invert(self.base) @ F

    def joints(self) -> Array:
        return self.sim.joints(self.robot)

    # ------------------------------------------------------------------ settings
    def _override(self, f: float) -> None:
        if not 0.0 < f <= 1.0 + 1e-12:
            raise ProgramError(f"the speed override must be in (0, 100] %, got {100 * f:.6g} %")
        f = min(f, 1.0)
        if abs(self.sim._override[self.robot] - f) > 1e-12:
            self.sim.set_override(self.robot, f)

    def _joint_timing(self) -> None:
        sim = self.sim
        if self.trapezoid is not None:
            v, a = self.trapezoid
            if sim.profile != "trapezoid" or abs(sim.acceleration - a) > 1e-12:
                sim.set_profile("trapezoid", a)
            if abs(sim.speed(self.robot) - v) > 1e-12:
                sim.set_speed(self.robot, v)
            self._override(1.0)
            return
        if sim.profile != "jerk":
            sim.set_profile("jerk")
        self._override(self.override * self.joint_fraction)

    # ------------------------------------------------------------------ motions
    def move_joints(self, q: Array, zone: float) -> None:
        self._joint_timing()
        self.sim.move_joints_absolute(self.robot, np.asarray(q, dtype=np.float64), zone=zone)

    def move_pose(
        self, T: Array, zone: float, key: Callable[[Any, Array], object] | None, wanted: object,
        what: str,
    ) -> None:  # fmt: skip
        """A joint move to program target T: the solution whose ``key(robot, q)`` is
        ``wanted`` (None: the nearest to the current joints)."""
        Tb = self.robot_pose(T)
        cur = self.joints()
        if key is None:
            sols = solutions(self.model, Tb, cur)
            if not sols:
                raise ProgramError(f"{what}: the pose is out of reach")
            q = min(sols, key=lambda s: float(np.abs(s - cur).max()))
        else:
            q = select(self.model, Tb, lambda v: key(self.model, v), wanted, cur, what)
        self.move_solution(q, Tb, zone)

    def move_solution(self, q: Array, Tb: Array, zone: float) -> None:
        """A joint move to solution q of robot pose Tb: ``move_end_effector`` when q is
        the nearest of its configuration (the simulator's own choice), else to q."""
        from workcell.sim.cartesian import pose_solutions

        self._joint_timing()
        c = letters(self.model, q)
        T_world = self.world @ Tb
        if c is not None:
            try:
                near = pose_solutions(self.sim.cell.robots[self.robot], T_world, self.joints(), c)
            except WorkcellError:
                near = []
            if near and np.allclose(near[0], q, atol=1e-9):
                self.sim.move_end_effector(self.robot, T_world, config=c, zone=zone)
                return
        self.sim.move_joints_absolute(self.robot, q, zone=zone)

    def move_linear(self, T: Array, speed: float, acceleration: float, zone: float) -> None:
        self._override(self.override)
        T_world = self.world @ self.robot_pose(T)
        self.sim.move_linear(self.robot, T_world, speed=speed, acceleration=acceleration, zone=zone)

    def move_circular(
        self, via: Array, T: Array, speed: float, acceleration: float, zone: float
    ) -> None:
        """Through ``via`` (a program pose; its position is used) to ``T``."""
        self._override(self.override)
        V = self.world @ self.robot_pose(via)
        T_world = self.world @ self.robot_pose(T)
        self.sim.move_circular(
            self.robot, V[:3, 3], T_world, speed=speed, acceleration=acceleration, zone=zone
        )

    # ------------------------------------------------------------------ time and I/O
    def dwell(self, seconds: Any, what: str = "a wait") -> None:
        """Let ``seconds`` (>= 0) pass; ``what`` names the statement in errors."""
        s = _number(seconds, f"{what}'s seconds")
        if s < 0:
            raise ProgramError(f"{what} needs seconds >= 0, got {s:g}")
        self.sim.wait(s)

    def set_output(self, number: int, name: str, value: bool) -> None:
        if name.lower() == GRIPPER:
            if value:
                self.sim.close_gripper(self.robot)
            else:
                self.sim.open_gripper(self.robot)
        elif hasattr(self.sim, "set_signal"):
            self.sim.set_signal(name, bool(value))
        self.outputs[number] = bool(value)

    def input(self, number: int, name: str) -> bool:
        if name and hasattr(self.sim, "signal"):
            try:
                return bool(self.sim.signal(name))
            except WorkcellError:
                return False
        return False

    def wait_input(self, number: int, name: str, value: bool) -> None:
        if self.input(number, name) == value:
            return
        if name and hasattr(self.sim, "wait_signal"):
            self.sim.wait_signal(name, value)
            return
        raise ProgramError(
            f"waits for input {number}{f' ({name})' if name else ''} to be {value}, but "
            "nothing in this cell can change it (the simulator has no signals for it)"
        )
