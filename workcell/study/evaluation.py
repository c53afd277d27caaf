"""Evaluate candidates: run the program on each cell variant, headless, and measure it.

A row (one candidate) holds ``candidate``, one column per parameter, and:

- ``feasible``: every command succeeded and nothing collided (the simulator stops at the
  first collision; robot bases overlapping a static part or another base count too);
- ``cycle_time_s``: the simulated clock at the end of the program (null when infeasible);
- ``min_clearance_m``, ``clearance_bound_m``, ``clearance_pair``, ``reach_margin_m``,
  ``joint_limit_margin_deg``: see :mod:`workcell.study.metrics` (null when infeasible);
- ``error_type`` and ``error`` ("Type: message"): why not, empty when feasible.

An exception in a candidate (a WorkcellError, or any other) becomes its error row; only
KeyboardInterrupt and the like get through. Nothing in a row depends on the wall clock,
on which process computed it or on what that process computed before: a worker keeps
one :class:`Evaluator` per study (cells compiled once per robot choice, see
:mod:`workcell.study.variants`) and every candidate starts from the same compiled state,
so rows are bit for bit the same whatever the backend and worker count.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell import limits
from workcell.cell.workcell import Workcell
from workcell.errors import CollisionError
from workcell.limits import DEFAULTS, Limits
from workcell.sim.contacts import DEFAULT_TOLERANCE
from workcell.sim.simulator import Simulator
from workcell.study import metrics
from workcell.study.candidates import Candidate
from workcell.study.program import Program
from workcell.study.spec import Parameter
from workcell.study.variants import Template, moved

__all__ = [
    "RESULT_COLUMNS",
    "Evaluator",
    "Setup",
    "StudySimulator",
    "error_row",
    "evaluate_batch",
    "evaluator",
]

Array = NDArray[np.float64]
RESULT_COLUMNS = (
    "feasible",
    "cycle_time_s",
    "min_clearance_m",
    "clearance_bound_m",
    "clearance_pair",
    "reach_margin_m",
    "joint_limit_margin_deg",
    "error_type",
    "error",
)


class StudySimulator(Simulator):
    """The simulator a candidate runs on: per robot, the speed (``speeds``, rad/s) and the
    speed override (``overrides``, 0 < f <= 1, see :meth:`Simulator.set_override`) pinned:
    the program's own ``set_speed`` and ``set_override`` for that robot take the study's
    value instead; every Cartesian target kept in ``targets`` (robot, world pose,
    arm/elbow configuration) for the reach margin."""

    def __init__(
        self,
        cell: Workcell,
        mode: str = "path",
        dt: float = 0.01,
        *,
        speeds: Mapping[str, float] | None = None,
        overrides: Mapping[str, float] | None = None,
        **options: Any,
    ) -> None:
        self._pinned = dict(speeds or {})
        self._factor = dict(overrides or {})
        super().__init__(cell, mode, dt, **options)
        self.targets: list[tuple[str, Array, str | None]] = []
        for robot in sorted(self._pinned):
            self.set_speed(robot, self._pinned[robot])
        for robot in sorted(self._factor):
            self.set_override(robot, self._factor[robot])

    def set_speed(self, robot: str, speed: float) -> None:
        """As :meth:`Simulator.set_speed`, at the study's speed for a pinned robot."""
        super().set_speed(robot, self._pinned.get(robot, speed))

    def set_override(self, robot: str, override: float) -> None:
        """As :meth:`Simulator.set_override`, at the study's override for a pinned robot."""
        super().set_override(robot, self._factor.get(robot, override))

    def _keep(self, robot: str, T: ArrayLike) -> None:
        q = self.joints(robot)
        config = metrics.target_config(self.cell.robots[robot], q)
        self.targets.append((robot, np.array(T, dtype=np.float64), config))

    def move_end_effector(self, robot: str, T: ArrayLike, *args: Any, **kw: Any) -> None:
        """As :meth:`Simulator.move_end_effector`; the target is kept."""
        super().move_end_effector(robot, T, *args, **kw)
        self._keep(robot, T)

    def move_straight_line(self, robot: str, T: ArrayLike, *args: Any, **kw: Any) -> None:
        """As :meth:`Simulator.move_straight_line`; the target is kept."""
        super().move_straight_line(robot, T, *args, **kw)
        self._keep(robot, T)

    def move_linear(self, robot: str, T: ArrayLike, **kw: Any) -> None:
        """As :meth:`Simulator.move_linear`; the target is kept."""
        super().move_linear(robot, T, **kw)
        self._keep(robot, T)

    def move_circular(self, robot: str, via: ArrayLike, T: ArrayLike, **kw: Any) -> None:
        """As :meth:`Simulator.move_circular`; the target is kept."""
        super().move_circular(robot, via, T, **kw)
        self._keep(robot, T)


@dataclass(frozen=True)
class Setup:
    """What a worker needs to evaluate a study's candidates (sent once per worker):
    ``key`` the study's fingerprint, the ``cell``, the ``program``, the ``parameters``,
    the simulation ``mode`` and ``dt`` (s), the clearance settings, and the work
    ``limits`` in force where the study was set up (every worker applies them)."""

    key: str
    cell: Workcell
    program: Program
    parameters: tuple[Parameter, ...]
    mode: str = "path"
    dt: float = 0.01
    clearance_cutoff: float = 0.1
    clearance_tolerance: float = 0.0005
    limits: Limits = DEFAULTS

    def columns(self) -> tuple[str, ...]:
        """The result columns: candidate, the parameters, then :data:`RESULT_COLUMNS`."""
        return ("candidate", *(p.name for p in self.parameters), *RESULT_COLUMNS)


def _empty_row(setup: Setup, candidate: Candidate) -> dict[str, Any]:
    row: dict[str, Any] = {"candidate": candidate.id}
    row.update(candidate.as_dict(setup.parameters))
    row.update(dict.fromkeys(RESULT_COLUMNS))
    row.update(feasible=False, error_type="", error="", clearance_pair="")
    return row


def error_row(setup: Setup, candidate: Candidate, error_type: str, message: str) -> dict[str, Any]:
    """The row of a candidate that failed with ``error_type`` and ``message``."""
    row = _empty_row(setup, candidate)
    row.update(error_type=error_type, error=f"{error_type}: {message}")
    return row


class Evaluator:
    """Evaluates one study's candidates in this process (module doc)."""

    def __init__(self, setup: Setup) -> None:
        self.setup = setup
        self._templates: dict[
            tuple[tuple[str, str], ...], tuple[Template, metrics.ClearanceModel]
        ] = {}

    def template(self, choices: Mapping[str, str]) -> tuple[Template, metrics.ClearanceModel]:
        """The compiled cell for a robot choice (robot -> robot name), compiled on first use."""
        key = tuple(sorted(choices.items()))
        if key not in self._templates:
            from workcell.study.variants import rebuild

            cell = rebuild(self.setup.cell, robots=choices) if choices else self.setup.cell
            template = Template(cell)
            cm = metrics.ClearanceModel(template.compiled, self.setup.clearance_cutoff)
            self._templates[key] = (template, cm)
        return self._templates[key]

    def simulator(self, candidate: Candidate) -> tuple[StudySimulator, metrics.ClearanceModel]:
        """A simulator on the candidate's cell, before the program (raises when the cell
        itself is infeasible: an overlap at the start)."""
        choices: dict[str, str] = {}
        base: dict[str, dict[str, float]] = {}
        pose: dict[str, dict[str, float]] = {}
        speeds: dict[str, float] = {}
        overrides: dict[str, float] = {}
        for p, v in zip(self.setup.parameters, candidate.values, strict=True):
            fld = p.field
            if fld == "robot":
                choices[p.target] = str(v)
            elif fld == "speed":
                speeds[p.target] = float(v)
            elif fld == "override":
                overrides[p.target] = float(v)
            elif fld.startswith("base."):
                base.setdefault(p.target, {})[fld[5:]] = float(v)
            else:
                pose.setdefault(p.target, {})[fld] = float(v)
        template, cm = self.template(choices)
        cell = template.cell
        bases = {r: moved(cell.robots[r].base, **_xyz_yaw(f)) for r, f in base.items()}
        poses = {
            n: moved((cell.static_parts.get(n) or cell.movable_parts[n]).pose, **_xyz_yaw(f))
            for n, f in pose.items()
        }
        variant, compiled = template.place(bases, poses)
        sim = StudySimulator(
            variant,
            self.setup.mode,
            self.setup.dt,
            speeds=speeds,
            overrides=overrides,
            compiled=compiled,
            stop_on_collision=True,
            progress=False,
        )
        overlaps = metrics.base_overlaps(sim, DEFAULT_TOLERANCE)
        if overlaps:
            a, b, depth = overlaps[0]
            raise CollisionError(
                f"collision at t = 0 s: {a} with {b}: depth {depth * 1e3:.3g} mm "
                "(a robot's base overlaps it)"
            )
        first = next((e for e in sim.events if e.kind == "collision"), None)
        if first is not None:
            raise CollisionError(f"collision at t = 0 s: {first.detail}")
        return sim, cm

    def run(self, candidate: Candidate) -> StudySimulator:
        """The candidate's simulator after its program (raises the program's error)."""
        with limits.using(**dataclasses.asdict(self.setup.limits)):
            sim, _ = self.simulator(candidate)
            self.setup.program.run(sim)
        return sim

    def evaluate(self, candidate: Candidate) -> dict[str, Any]:
        """The candidate's row (module doc); never raises for a failing candidate."""
        with limits.using(**dataclasses.asdict(self.setup.limits)):
            return self._evaluate(candidate)

    def _evaluate(self, candidate: Candidate) -> dict[str, Any]:
        try:
            sim, cm = self.simulator(candidate)
            self.setup.program.run(sim)
            c = metrics.clearance(sim, cm, self.setup.clearance_tolerance)
            row = _empty_row(self.setup, candidate)
            row.update(
                feasible=True,
                cycle_time_s=float(sim.sim_time),
                min_clearance_m=c.minimum,
                clearance_bound_m=c.bound,
                clearance_pair=c.pair,
                reach_margin_m=metrics.reach_margin(sim, sim.targets),
                joint_limit_margin_deg=metrics.joint_limit_margin(sim),
            )
            return row
        except Exception as exc:  # a failing candidate never stops the study
            return error_row(self.setup, candidate, type(exc).__name__, str(exc))


def _xyz_yaw(fields: Mapping[str, float]) -> dict[str, float]:
    out = {k: v for k, v in fields.items() if k in ("x", "y", "z")}
    if "yaw" in fields:
        out["yaw"] = math.radians(fields["yaw"])
    return out


# one evaluator per study in each worker process (cells compiled once per worker)
_EVALUATORS: dict[str, Evaluator] = {}


def evaluator(setup: Setup) -> Evaluator:
    """This process's evaluator for ``setup`` (made on first use; the last two studies kept)."""
    ev = _EVALUATORS.get(setup.key)
    if ev is None:
        while len(_EVALUATORS) >= 2:
            _EVALUATORS.pop(next(iter(_EVALUATORS)))
        ev = _EVALUATORS[setup.key] = Evaluator(setup)
    return ev


def evaluate_batch(setup: Setup, batch: list[Candidate]) -> Iterator[dict[str, Any]]:
    """Rows of ``batch`` in order, on this process's evaluator."""
    ev = evaluator(setup)
    for c in batch:
        yield ev.evaluate(c)
