"""Work limits: one budget that every front end (Python, the language, the server) obeys.

A command that would eat the machine (a sphere of 10^8 facets, a move sampled every
nanosecond, a wait of 10^300 s) is refused *before* the work starts, with a
:class:`~workcell.errors.LimitError` that names the limit and says how to raise it.
The defaults fit a 2-core, 24 GB machine with room to spare (several sessions at once):

==========================  =============  ==================================================
limit                       default        what it bounds
==========================  =============  ==================================================
``max_facets``              500,000        triangles of one solid or one mesh (~1.7 KB each
                                           while meshing: ~0.85 GB)
``max_frames_per_command``  2,000,000      frames one command adds to the timeline
``max_frames``              20,000,000     frames of one simulation
``max_spill_bytes``         4 GiB          the timeline's spill file on disk
``max_sim_time``            1e7 s          the simulated clock (~116 days; at most 9.2e9 s:
                                           recordings store int64 nanoseconds)
``max_file_bytes``          256 MiB        a model, cell or script file read
``max_coordinate``          1e6 m          any coordinate, length or translation given, and
                                           any entry of a transform's 3x3 part
``max_path_samples``        100,000        poses one Cartesian command solves IK for (a line
                                           or arc at a tiny step; ~40 us and ~1.3 KB each)
``max_candidates``          1,000,000      candidates of one study (a grid or a sample)
``max_workers``             64             worker processes one study starts on this machine
``max_images``              100,000        pictures one command renders (video frames,
                                           recorded images, contact-sheet tiles; ~10 ms each)
``max_pixels``              50,000,000     pixels of one picture (a contact sheet whole;
                                           3 bytes each: 150 MB)
``max_line_chars``          65,536         characters of one command-language line (the
                                           parser takes ~5 us each)
``max_native_seconds``      120 s          wall time of one native geometry job in a child
                                           process (a convex decomposition)
``max_native_bytes``        3 GiB          address space of such a child process
``max_program_steps``       1,000,000      statements one robot program (KRL, RAPID, ...)
                                           runs (its loops and jumps included)
==========================  =============  ==================================================

Raise (or lower) them for a block of code, in this thread only::

    from workcell import limits

    with limits.using(max_facets=5_000_000):
        solids.sphere(model, "fine", radius=1.0, m=1000, n=1000)

or for the whole process with :func:`set_limits` (``workcell --limit max_facets=5e6 ...`` on
the command line does that). New commands check their own work with :func:`check`::

    limits.check("max_frames_per_command", n_frames, f"move_linear '{robot}'")
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import math
from collections.abc import Iterator
from dataclasses import dataclass, field

from workcell.errors import LimitError

__all__ = [
    "DEFAULTS",
    "MAX_SIM_TIME",
    "Limits",
    "check",
    "current",
    "exceeded",
    "parse_limit",
    "set_limits",
    "using",
]


MAX_SIM_TIME = 9.2e9  # s: int64 nanoseconds (rerun's time type) end at 9.22e9 s


def _limit(default: float, unit: str, doc: str) -> float:
    return field(default=default, metadata={"unit": unit, "doc": doc})


@dataclass(frozen=True)
class Limits:
    """The work budget (see the module doc for what each field bounds); every value > 0."""

    max_facets: int = _limit(500_000, "facets", "triangles of one solid or mesh")
    max_frames_per_command: int = _limit(2_000_000, "frames", "frames added by one command")
    max_frames: int = _limit(20_000_000, "frames", "frames of one simulation")
    max_spill_bytes: int = _limit(4 << 30, "bytes", "the timeline's spill file")
    max_sim_time: float = _limit(1e7, "s", "the simulated clock")
    max_file_bytes: int = _limit(256 << 20, "bytes", "a file read (model, cell, script)")
    max_coordinate: float = _limit(1e6, "m", "a coordinate, length or transform entry")
    max_path_samples: int = _limit(100_000, "samples", "IK samples of one Cartesian command")
    max_candidates: int = _limit(1_000_000, "candidates", "candidates of one study")
    max_workers: int = _limit(64, "workers", "worker processes one study starts here")
    max_images: int = _limit(100_000, "pictures", "pictures rendered by one command")
    max_pixels: int = _limit(50_000_000, "pixels", "pixels of one picture")
    max_line_chars: int = _limit(65_536, "characters", "one command-language line")
    max_native_seconds: float = _limit(120.0, "s", "one native geometry job (child process)")
    max_native_bytes: int = _limit(3 << 30, "bytes", "a native geometry child's memory")
    max_program_steps: int = _limit(1_000_000, "steps", "statements a robot program runs")

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            ok = isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0
            if not (ok and math.isfinite(v)):
                raise LimitError(f"limit {f.name} must be a finite number > 0, got {v!r}")
            if isinstance(f.default, int) and v != int(v):
                raise LimitError(f"limit {f.name} must be a whole number, got {v!r}")
            object.__setattr__(self, f.name, type(f.default)(v))
        if self.max_sim_time > MAX_SIM_TIME:
            raise LimitError(
                f"limit max_sim_time must be at most {MAX_SIM_TIME:.3g} s (recordings keep "
                f"times as int64 nanoseconds), got {self.max_sim_time!r}"
            )


DEFAULTS = Limits()
_process = DEFAULTS
_local: contextvars.ContextVar[Limits | None] = contextvars.ContextVar(
    "workcell_limits", default=None
)


def current() -> Limits:
    """The limits in force here: those of the innermost :func:`using` block, else the
    process's (:func:`set_limits`), else :data:`DEFAULTS`."""
    return _local.get() or _process


def set_limits(limits: Limits | None = None, **changes: float) -> Limits:
    """Set the process-wide limits (every thread): ``limits`` (default: the current
    process-wide ones) with ``changes`` applied, e.g. ``set_limits(max_frames=10**8)``;
    ``set_limits(DEFAULTS)`` restores the defaults. Returns the new limits."""
    global _process
    _process = _changed(limits or _process, changes)
    return _process


@contextlib.contextmanager
def using(**changes: float) -> Iterator[Limits]:
    """Within the block (this thread or task only), the current limits with ``changes``."""
    token = _local.set(_changed(current(), changes))
    try:
        yield current()
    finally:
        _local.reset(token)


def _changed(base: Limits, changes: dict[str, float]) -> Limits:
    names = [f.name for f in dataclasses.fields(Limits)]
    unknown = sorted(set(changes) - set(names))
    if unknown:
        raise LimitError(f"unknown limit {', '.join(unknown)}; limits: {', '.join(names)}")
    return dataclasses.replace(base, **changes)


def parse_limit(text: str) -> tuple[str, float]:
    """``"NAME=VALUE"`` (the command line's ``--limit``) as (name, value); LimitError if bad."""
    name, sep, value = text.partition("=")
    names = [f.name for f in dataclasses.fields(Limits)]
    if not sep or name.strip() not in names:
        raise LimitError(
            f"--limit takes NAME=VALUE with NAME one of {', '.join(names)}; got {text!r}"
        )
    try:
        v = float(value)
    except ValueError:
        raise LimitError(f"--limit {name}: {value!r} is not a number") from None
    return name.strip(), v


def _fmt(v: float) -> str:
    if (isinstance(v, int) and abs(v) < 10**15) or (
        math.isfinite(v) and v == int(v) and abs(v) < 1e15
    ):
        return f"{int(v):,}"
    return f"{v:.4g}"


def check(name: str, amount: float, what: str) -> None:
    """Raise LimitError when ``amount`` is over limit ``name`` (a field of :class:`Limits`).

    ``what`` names the work, e.g. ``"sphere 's'"``. Call it before the work starts;
    ``amount`` may be a float estimate (inf and NaN are over every limit).
    """
    if amount <= getattr(current(), name):  # False for NaN
        return
    raise exceeded(name, amount, what)


def exceeded(name: str, amount: float, what: str) -> LimitError:
    """The LimitError saying that ``what`` needs ``amount`` of limit ``name``, over it
    (for work stopped when it reaches a limit, e.g. a child process out of time)."""
    bound = getattr(current(), name)
    unit = Limits.__dataclass_fields__[name].metadata["unit"]
    return LimitError(
        f"{what}: {_fmt(amount)} {unit} is over the limit {name} = {_fmt(bound)} {unit}; "
        f"raise it with workcell.limits.using({name}=...) in Python or "
        f"'workcell --limit {name}=N ...' on the command line"
    )
