"""Run a study: candidates, resume, backend, progress, results, plots, the best run.

:func:`run` is the Python entry point (it returns the results as a pyarrow Table;
``table.to_pandas()`` gives a DataFrame when pandas is installed); :func:`execute` does
the same and also returns what the command line reports (counts, times, files).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pyarrow as pa
from tqdm import tqdm

from workcell.errors import StudyError
from workcell.study.backends import Backend
from workcell.study.backends import backend as make_backend
from workcell.study.candidates import Candidate, candidates
from workcell.study.evaluation import Evaluator, Setup
from workcell.study.prepare import prepare
from workcell.study.results import ResultStore, best_rows, schema
from workcell.study.spec import Study

__all__ = ["Outcome", "execute", "record_best", "run"]


@dataclass
class Outcome:
    """A finished (or resumed) study: the ``table``; how many candidates were already
    done (``resumed``) and ran now (``evaluated``); the ``wall_s`` of this run; the
    ``backend`` used; the files written (``files``: plots, recording)."""

    table: pa.Table
    setup: Setup
    resumed: int
    evaluated: int
    wall_s: float
    backend: Backend
    out: Path | None = None
    files: dict[str, Path] = field(default_factory=dict)

    @property
    def throughput(self) -> float:
        """Candidates evaluated per second of this run's wall time."""
        return self.evaluated / self.wall_s if self.wall_s > 0 else 0.0


class _Bar(tqdm):
    """tqdm without its monitor thread (a parent with no other thread forks its workers)."""

    monitor_interval = 0


def _best_text(best: dict[str, Any] | None) -> str:
    if best is None:
        return "best: none feasible yet"
    return f"best {best['cycle_time_s']:.3f} s (#{best['candidate']})"


def execute(
    study: Study,
    out: str | os.PathLike | None = None,
    *,
    backend_name: str = "process",
    workers: int | None = None,
    address: str | None = None,
    batch_size: int | None = None,
    retries: int = 2,
    progress: bool | None = None,
    plots: bool = True,
    record: str | os.PathLike | None = None,
) -> Outcome:
    """Run ``study`` (see :func:`run`) and return the :class:`Outcome`."""
    setup, info = prepare(study)
    runner = make_backend(
        backend_name, workers=workers, address=address, batch_size=batch_size, retries=retries
    )
    every = candidates(study)
    store = ResultStore(out, schema(setup.parameters), info, setup.key)
    resumed = store.count
    todo = [c for c in every if c.id not in store.finished]
    best = next(iter(best_rows(store.table(), 1)), None)
    show = (os.isatty(2) if progress is None else progress) and bool(todo)
    t0 = time.perf_counter()
    with _Bar(
        total=len(every), initial=resumed, unit="cand", desc="study", disable=not show, leave=True
    ) as bar:
        bar.set_postfix_str(_best_text(best))
        try:
            for row in runner.run(setup, todo):
                store.add([row])
                bar.update(1)
                if row["feasible"] and (
                    best is None
                    or (row["cycle_time_s"], row["candidate"])
                    < (best["cycle_time_s"], best["candidate"])
                ):
                    best = row
                    bar.set_postfix_str(_best_text(best))
        finally:  # also on Ctrl-C: what is done stays done
            table = store.merge()
    wall = time.perf_counter() - t0
    result = Outcome(table, setup, resumed, store.count - resumed, wall, runner, store.out)
    if out is not None and plots:
        from workcell.study.plots import plot_study

        result.files.update(plot_study(table, setup.parameters, Path(out)))
    if record is not None:
        result.files["recording"] = record_best(setup, table, record)
    return result


def record_best(setup: Setup, table: pa.Table, path: str | os.PathLike) -> Path:
    """Run the best candidate of ``table`` again and record it to ``path`` (.rrd)."""
    from workcell.record import record

    best = best_rows(table, 1)
    if not best:
        raise StudyError("no feasible candidate to record")
    row = best[0]
    candidate = Candidate(row["candidate"], tuple(row[p.name] for p in setup.parameters))
    sim = Evaluator(setup).run(candidate)
    return Path(record(sim, path).path)


def run(
    study: Study,
    out: str | os.PathLike | None = None,
    *,
    backend: str = "process",
    workers: int | None = None,
    address: str | None = None,
    batch_size: int | None = None,
    retries: int = 2,
    progress: bool | None = None,
    plots: bool = True,
    record: str | os.PathLike | None = None,
) -> pa.Table:
    """Run ``study`` and return its results, one row per candidate, sorted by candidate.

    ``out``: the output folder (``results.parquet``, ``study.json``, plots); a study run
    again into the same folder skips the candidates done (None: nothing written, nothing
    resumed). ``backend``: "serial", "process" (``workers`` processes, default one per
    core) or "ray" (``address`` None: a local Ray of ``workers`` CPUs; "auto" or
    "HOST:PORT": a running cluster). ``batch_size``: candidates per task (default: about
    a quarter of a worker's share, at most 16 for processes and 32 for Ray);
    ``retries``: how often a candidate that kills its worker is retried before its row
    says ``WorkerCrashed``; ``progress``: a progress bar with the running best on stderr
    (None: when stderr is a terminal); ``plots``: write the PNGs into ``out``;
    ``record``: record the best candidate's run to this ``.rrd`` file.
    """
    return execute(
        study,
        out,
        backend_name=backend,
        workers=workers,
        address=address,
        batch_size=batch_size,
        retries=retries,
        progress=progress,
        plots=plots,
        record=record,
    ).table
