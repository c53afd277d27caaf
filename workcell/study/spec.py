"""What a study varies: its parameters, their values, and the study itself.

A parameter is named ``THING.FIELD`` after a robot or a part of the cell:

=====================  =======  =====================================================
``ROBOT.base.x|y|z``   m        the robot's base position in the world
``ROBOT.base.yaw``     deg      the base's rotation about the world's vertical
``ROBOT.robot``        name     which robot stands there (a name ``Workcell.add_robot``
                                takes: puma260, puma560, and the library's robots)
``ROBOT.speed``        rad/s    the robot's speed, pinned: the program's own
                                ``set_speed`` calls for this robot are overridden
``ROBOT.override``     0..1     the robot's speed override (``Simulator.set_override``:
                                speeds x f, accelerations x f^2, jerks x f^3), pinned
``PART.x|y|z``         m        a static or movable part's frame position in the world
``PART.yaw``           deg      the part's rotation about the world's vertical
=====================  =======  =====================================================

Values are written ``LO:HI:N`` (N evenly spaced values, a grid axis), ``LO:HI`` (a
continuous range, for random samples only) or ``A,B,C`` (a list; robot names are lists).
In Python a value spec may also be a ``(lo, hi, n)`` or ``(lo, hi)`` tuple or a list.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from workcell import limits
from workcell.checks import is_finite_number
from workcell.errors import StudyError

if TYPE_CHECKING:
    from workcell.cell.workcell import Workcell
    from workcell.sim.simulator import Simulator
    from workcell.study.candidates import Candidate

__all__ = [
    "PART_FIELDS",
    "ROBOT_FIELDS",
    "Parameter",
    "Study",
    "parameter",
    "parse_vary",
]

ROBOT_FIELDS: Mapping[str, str] = {
    "base.x": "m",
    "base.y": "m",
    "base.z": "m",
    "base.yaw": "deg",
    "robot": "name",
    "speed": "rad/s",
    "override": "factor",
}
PART_FIELDS: Mapping[str, str] = {"x": "m", "y": "m", "z": "m", "yaw": "deg"}
FIELDS_HELP = (
    f"robots: {', '.join(f'ROBOT.{f}' for f in ROBOT_FIELDS)}; "
    f"parts: {', '.join(f'PART.{f}' for f in PART_FIELDS)}"
)
VALUES_HELP = "LO:HI:N (N values from LO to HI), LO:HI (a range, with --sample) or A,B,C (a list)"


def _nice(v: float) -> float:
    """``v`` to 12 decimals and 12 significant digits (0.30000000000000004 -> 0.3,
    -0.18 + 6 * 0.03 -> 0.0, never -0.0)."""
    return float(f"{round(v, 12):.12g}") + 0.0


@dataclass(frozen=True)
class Parameter:
    """One varied parameter: discrete ``values`` (a grid axis or a list), or a continuous
    range ``low``..``high`` (sampled uniformly with ``Study.sample``)."""

    name: str
    values: tuple[float | str, ...] = ()
    low: float | None = None
    high: float | None = None

    @property
    def target(self) -> str:
        """The robot or part the parameter belongs to."""
        return self.name.split(".", 1)[0]

    @property
    def field(self) -> str:
        """What of the robot or part varies ("base.x", "speed", "x", ...)."""
        return self.name.split(".", 1)[1]

    @property
    def discrete(self) -> bool:
        """True for a list or grid axis, False for a continuous range."""
        return bool(self.values)

    @property
    def text(self) -> bool:
        """True when the values are names (robot choice), not numbers."""
        return self.field == "robot"

    @property
    def unit(self) -> str:
        """The values' unit ("m", "deg", "rad/s", "factor", "name")."""
        return {**PART_FIELDS, **ROBOT_FIELDS}[self.field]

    def to_dict(self) -> dict[str, Any]:
        """JSON-able description (for the study file and its fingerprint)."""
        if self.discrete:
            return {"name": self.name, "values": list(self.values)}
        return {"name": self.name, "low": self.low, "high": self.high}

    def __str__(self) -> str:
        if self.discrete:
            return f"{self.name}={','.join(map(str, self.values))}"
        return f"{self.name}={self.low}:{self.high}"


def _check_name(name: object) -> str:
    if not isinstance(name, str) or "." not in name:
        raise StudyError(f"parameter name must be THING.FIELD, got {name!r}; {FIELDS_HELP}")
    _, fld = name.split(".", 1)
    if fld not in ROBOT_FIELDS and fld not in PART_FIELDS:
        raise StudyError(f"parameter {name!r}: unknown field {fld!r}; {FIELDS_HELP}")
    return name


def _check_value(name: str, fld: str, v: float) -> float:
    if not is_finite_number(v):
        raise StudyError(f"parameter {name!r}: values must be finite numbers, got {v!r}")
    v = float(v)
    if fld == "speed" and not v > 0:
        raise StudyError(f"parameter {name!r}: a speed must be > 0 rad/s, got {v:g}")
    if fld == "override" and not 0 < v <= 1:
        raise StudyError(f"parameter {name!r}: an override must be in (0, 1], got {v:g}")
    return v


def _number(name: str, text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise StudyError(
            f"parameter {name!r}: {text!r} is not a number; values: {VALUES_HELP}"
        ) from None


def _grid(name: str, fld: str, lo: float, hi: float, n: object) -> Parameter:
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise StudyError(f"parameter {name!r}: the count N must be an integer >= 1, got {n!r}")
    lo, hi = _check_value(name, fld, lo), _check_value(name, fld, hi)
    if lo > hi:
        raise StudyError(f"parameter {name!r}: LO must be <= HI, got {lo:g}:{hi:g}")
    if n == 1:
        return Parameter(name, (lo,))
    step = (hi - lo) / (n - 1)
    return Parameter(name, tuple(_nice(lo + i * step) if i < n - 1 else hi for i in range(n)))


def parameter(name: str, spec: object) -> Parameter:
    """A parameter from its name and a value spec (module doc): ``"LO:HI:N"``,
    ``"LO:HI"``, ``"A,B,C"``, ``(lo, hi, n)``, ``(lo, hi)`` or a list of values."""
    name = _check_name(name)
    fld = name.split(".", 1)[1]
    if isinstance(spec, Parameter):
        return spec
    if fld == "robot":
        names = spec.split(",") if isinstance(spec, str) else spec
        if not isinstance(names, (list, tuple)) or not names:
            raise StudyError(f"parameter {name!r}: give robot names as A,B,C or a list")
        out = tuple(str(n).strip() for n in names)
        if not all(out):
            raise StudyError(f"parameter {name!r}: empty robot name in {spec!r}")
        return Parameter(name, out)
    if isinstance(spec, str):
        text = spec.strip()
        if ":" in text:
            parts = text.split(":")
            if len(parts) == 3:
                n_text = parts[2].strip()
                if not n_text.isdigit():
                    raise StudyError(
                        f"parameter {name!r}: the count N in LO:HI:N must be an integer >= 1, "
                        f"got {n_text!r}"
                    )
                return _grid(
                    name, fld, _number(name, parts[0]), _number(name, parts[1]), int(n_text)
                )
            if len(parts) == 2:
                spec = (_number(name, parts[0]), _number(name, parts[1]))
            else:
                raise StudyError(f"parameter {name!r}: cannot read {spec!r}; values: {VALUES_HELP}")
        else:
            spec = [_number(name, p) for p in text.split(",")]
    if isinstance(spec, tuple) and len(spec) == 3:
        return _grid(name, fld, spec[0], spec[1], spec[2])
    if isinstance(spec, tuple) and len(spec) == 2:
        lo, hi = _check_value(name, fld, spec[0]), _check_value(name, fld, spec[1])
        if not lo < hi:
            raise StudyError(f"parameter {name!r}: a range needs LO < HI, got {lo:g}:{hi:g}")
        return Parameter(name, (), lo, hi)
    if isinstance(spec, (list, tuple)) and spec:
        return Parameter(name, tuple(_check_value(name, fld, v) for v in spec))
    if is_finite_number(spec):
        return Parameter(name, (_check_value(name, fld, spec),))
    raise StudyError(f"parameter {name!r}: cannot read values {spec!r}; values: {VALUES_HELP}")


def parse_vary(text: str) -> Parameter:
    """A parameter from the command line's ``NAME=VALUES`` (e.g. ``puma.base.x=-0.1:0.1:5``)."""
    if "=" not in text:
        raise StudyError(f"--vary wants NAME=VALUES, got {text!r}; values: {VALUES_HELP}")
    name, spec = text.split("=", 1)
    return parameter(name.strip(), spec)


@dataclass(frozen=True)
class Study:
    """A study: a cell, a program and the parameters varied over it.

    ``cell``: an example name ("pick-place", ...), a cell file saved by
    ``Workcell.save``, a :class:`~workcell.Workcell`, or None when ``program`` is a
    ``.wcl`` script whose first lines (up to its ``simulate``) build the cell.
    ``program``: a ``.wcl`` command-language file, a function ``program(sim)`` (module
    level, so worker processes can import it), or None for the example's own program.
    ``vary``: parameter name -> values (see the module doc), or ``NAME=VALUES`` strings,
    or :class:`Parameter` objects. ``sample``: draw that many candidates at random
    (``seed``) instead of the full grid. ``mode`` and ``dt`` (s): the simulation (default:
    the script's ``simulate`` line, else "path" and 0.01). ``clearance_cutoff`` (m):
    clearances beyond it count as the cutoff; ``clearance_tolerance`` (m): how close the
    measured clearance comes to its guaranteed lower bound (see :mod:`workcell.study.metrics`).
    """

    cell: str | os.PathLike | Workcell | None = None
    program: str | os.PathLike | Callable[[Simulator], object] | None = None
    vary: Mapping[str, object] | Sequence[object] = ()
    sample: int | None = None
    seed: int = 0
    mode: str | None = None
    dt: float | None = None
    clearance_cutoff: float = 0.1
    clearance_tolerance: float = 0.0005
    parameters: tuple[Parameter, ...] = field(init=False, default=())

    def __post_init__(self) -> None:
        vary = self.vary
        if isinstance(vary, Mapping):
            params = [parameter(str(k), v) for k, v in vary.items()]
        elif isinstance(vary, (list, tuple)):
            params = [v if isinstance(v, Parameter) else parse_vary(str(v)) for v in vary]
        else:
            raise StudyError(f"vary must be a mapping NAME -> VALUES or a list, got {vary!r}")
        if not params:
            raise StudyError(f"a study varies at least one parameter; {FIELDS_HELP}")
        names = [p.name for p in params]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise StudyError(f"parameter(s) given twice: {', '.join(dup)}")
        if self.sample is not None and (
            isinstance(self.sample, bool) or not isinstance(self.sample, int) or self.sample < 1
        ):
            raise StudyError(f"sample must be an integer >= 1, got {self.sample!r}")
        if self.sample is not None:  # before anything is drawn (50 M: a MemoryError)
            limits.check("max_candidates", self.sample, f"a study of sample={self.sample}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int):
            raise StudyError(f"seed must be an integer, got {self.seed!r}")
        if self.sample is None:
            ranges = [p.name for p in params if not p.discrete]
            if ranges:
                raise StudyError(
                    f"{', '.join(ranges)}: a range LO:HI has no grid; give LO:HI:N, "
                    "or draw random candidates with sample=N (--sample N)"
                )
            size = math.prod(len(p.values) for p in params)
            limits.check(
                "max_candidates", size, "the full grid of the study (or draw a sample: --sample N)"
            )
        if self.dt is not None and not (is_finite_number(self.dt) and self.dt > 0):
            raise StudyError(f"dt must be a number of seconds > 0, got {self.dt!r}")
        if not (is_finite_number(self.clearance_cutoff) and self.clearance_cutoff > 0):
            raise StudyError(
                f"clearance_cutoff must be a number of metres > 0, got {self.clearance_cutoff!r}"
            )
        if not (is_finite_number(self.clearance_tolerance) and self.clearance_tolerance > 0):
            raise StudyError(
                f"clearance_tolerance must be a number of metres > 0, got {self.clearance_tolerance!r}"
            )
        if self.cell is None and self.program is None:
            raise StudyError("a study needs a cell (an example or a cell file) or a .wcl program")
        if isinstance(self.cell, (str, os.PathLike)) or self.cell is None:
            pass
        elif not hasattr(self.cell, "robots"):
            raise StudyError(
                f"cell must be an example name, a cell file or a Workcell, got {self.cell!r}"
            )
        if self.program is not None and not (
            isinstance(self.program, (str, os.PathLike)) or callable(self.program)
        ):
            raise StudyError(
                f"program must be a .wcl file or a function program(sim), got {self.program!r}"
            )
        object.__setattr__(self, "parameters", tuple(params))

    def candidates(self) -> list[Candidate]:
        """Every candidate, numbered from 0 (see :mod:`workcell.study.candidates`)."""
        from workcell.study.candidates import candidates

        return candidates(self)

    @property
    def size(self) -> int:
        """Number of candidates: the sample size, or the full grid's."""
        if self.sample is not None:
            return self.sample
        return math.prod(len(p.values) for p in self.parameters)
