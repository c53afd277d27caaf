"""Where candidates run: in this process, in a local process pool, or on a Ray cluster.

Every backend yields exactly one row per candidate it is given, in any order, and the
rows are the same whatever the backend (see :mod:`workcell.study.evaluation`).

- ``serial``: one :class:`~workcell.study.evaluation.Evaluator` in this process.
- ``process`` (the default): :class:`~workcell.study.pool.ProcessPool`, ``workers``
  processes (default: one per core this process may use).
- ``ray``: Ray tasks of ``batch_size`` candidates. With ``address`` None a local Ray
  instance of ``workers`` CPUs is started (and stopped at the end); ``"auto"`` or
  ``"HOST:PORT"`` joins a running cluster (``ray start --head``), whose machines need this
  package installed. A Ray already initialised by the caller is used as it is. The
  setup is put in Ray's object store once; each Ray worker process keeps its compiled
  cells between tasks. A task whose worker dies is retried by Ray (``max_retries``);
  when it still fails, its candidates run again one per task, and a candidate that kills
  its worker every time gets the ``WorkerCrashed`` error row. Ray is imported only here,
  from the optional extra ``workcell[cluster]``.
"""

from __future__ import annotations

import abc
import contextlib
import os
import pickle
import time
from collections.abc import Iterator
from typing import Any

from workcell import limits
from workcell.errors import StudyError
from workcell.study.candidates import Candidate
from workcell.study.evaluation import Setup, error_row, evaluate_batch
from workcell.study.pool import CRASH_MESSAGE, ProcessPool, peak_rss_mb

__all__ = ["BACKENDS", "Backend", "ProcessBackend", "RayBackend", "SerialBackend", "backend"]

BACKENDS = ("serial", "process", "ray")


def default_workers() -> int:
    """One worker per core this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def _batch_size(n: int, workers: int, most: int) -> int:
    """Batches small enough that every worker gets ~4 of them, at most ``most``."""
    return max(1, min(most, n // (4 * max(1, workers))))


class Backend(abc.ABC):
    """Runs candidates; ``memory_mb`` maps worker process ids to their peak memory (MB),
    ``cpu_s`` to the CPU time they spent on candidates (s)."""

    name = ""

    def __init__(self) -> None:
        self.memory_mb: dict[int, float] = {}
        self.cpu_s: dict[int, float] = {}
        self.workers = 1

    @abc.abstractmethod
    def run(self, setup: Setup, todo: list[Candidate]) -> Iterator[dict[str, Any]]:
        """One row per candidate of ``todo``, as they finish."""


class SerialBackend(Backend):
    """Candidates one after another in this process."""

    name = "serial"

    def run(self, setup: Setup, todo: list[Candidate]) -> Iterator[dict[str, Any]]:
        cpu = 0.0
        for c in todo:  # CPU time of the evaluations only, not of the caller's work
            t0 = time.process_time()
            row = next(evaluate_batch(setup, [c]))
            cpu += time.process_time() - t0
            yield row
        self.memory_mb[os.getpid()] = peak_rss_mb()
        self.cpu_s[os.getpid()] = cpu


class ProcessBackend(Backend):
    """A local pool of ``workers`` processes (module doc)."""

    name = "process"

    def __init__(
        self, workers: int | None = None, batch_size: int | None = None, retries: int = 2
    ) -> None:
        super().__init__()
        self.workers = workers or default_workers()
        self.batch_size = batch_size
        self.retries = retries
        self.crashes = 0
        self.start_method = ""

    def run(self, setup: Setup, todo: list[Candidate]) -> Iterator[dict[str, Any]]:
        try:
            pool = ProcessPool(
                setup,
                self.workers,
                self.batch_size or _batch_size(len(todo), self.workers, 16),
                self.retries,
            )
        except (pickle.PicklingError, AttributeError, TypeError) as exc:
            raise StudyError(
                f"the study cannot be sent to worker processes ({exc}); a program function "
                "must be defined at module level (not a lambda or a nested function), "
                "or use backend 'serial'"
            ) from exc
        try:
            yield from pool.run(todo)
        finally:
            self.memory_mb.update(pool.memory_mb)
            self.cpu_s.update(pool.cpu_s)
            self.crashes = pool.crashes
            self.start_method = pool.start_method


def _ray_batch(
    setup: Setup, batch: list[Candidate]
) -> tuple[list[dict[str, Any]], int, float, float]:
    """A Ray task: the rows of ``batch``, this worker's pid, peak memory (MB) and the CPU
    time (s) the batch took."""
    t0 = time.process_time()
    rows = list(evaluate_batch(setup, batch))
    return rows, os.getpid(), peak_rss_mb(), time.process_time() - t0


def import_ray() -> Any:
    """The ``ray`` module, or a StudyError saying how to install it."""
    try:
        import ray
    except ImportError as exc:
        raise StudyError(
            "the ray backend needs Ray: pip install 'workcell[cluster]' "
            "(or use --backend process on this machine)"
        ) from exc
    return ray


class RayBackend(Backend):
    """Ray tasks, locally or on a cluster (module doc)."""

    name = "ray"

    def __init__(
        self,
        address: str | None = None,
        workers: int | None = None,
        batch_size: int | None = None,
        retries: int = 2,
    ) -> None:
        super().__init__()
        self.address = address
        self.workers = workers or default_workers()
        self.batch_size = batch_size
        self.retries = retries

    def _init(self, ray: Any) -> bool:
        """Start or join Ray unless the caller has; True when this backend started it."""
        if ray.is_initialized():
            return False
        os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
        kw: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False}
        if self.address is None:
            kw["num_cpus"] = self.workers
        else:
            kw["address"] = self.address
        try:
            ray.init(**kw)
        except (ConnectionError, RuntimeError, ValueError) as exc:
            where = self.address or "a local Ray instance"
            raise StudyError(f"cannot start or reach Ray at {where}: {exc}") from exc
        return True

    def run(self, setup: Setup, todo: list[Candidate]) -> Iterator[dict[str, Any]]:
        ray = import_ray()
        started = self._init(ray)
        pending: dict[Any, list[Candidate]] = {}
        try:
            cpus = int(ray.cluster_resources().get("CPU", self.workers))
            self.workers = cpus
            size = self.batch_size or _batch_size(len(todo), cpus, 32)
            task = ray.remote(num_cpus=1, max_retries=self.retries)(_ray_batch)
            ref = ray.put(setup)
            for i in range(0, len(todo), size):
                batch = todo[i : i + size]
                pending[task.remote(ref, batch)] = batch
            while pending:
                done, _ = ray.wait(list(pending), num_returns=1)
                for r in done:
                    batch = pending.pop(r)
                    try:
                        rows, pid, mb, cpu = ray.get(r)
                    except ray.exceptions.RayError:
                        if len(batch) > 1:  # find the candidate that kills its worker
                            for c in batch:
                                pending[task.remote(ref, [c])] = [c]
                        else:
                            yield error_row(
                                setup, batch[0], "WorkerCrashed", CRASH_MESSAGE.format(self.retries)
                            )
                        continue
                    self.memory_mb[pid] = max(mb, self.memory_mb.get(pid, 0.0))
                    self.cpu_s[pid] = self.cpu_s.get(pid, 0.0) + cpu
                    yield from rows
        finally:
            for r in list(pending):
                with contextlib.suppress(Exception):
                    ray.cancel(r)  # interrupted: drop what has not run
            if started:
                ray.shutdown()


def backend(
    name: str,
    *,
    workers: int | None = None,
    address: str | None = None,
    batch_size: int | None = None,
    retries: int = 2,
) -> Backend:
    """The backend called ``name`` ("serial", "process" or "ray")."""
    if name not in BACKENDS:
        raise StudyError(f"unknown backend {name!r}; valid: {', '.join(BACKENDS)}")
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
    ):
        raise StudyError(f"workers must be an integer >= 1, got {workers!r}")
    if workers is not None and (name == "process" or address is None):  # started here
        limits.check("max_workers", workers, f"a {name} backend of {workers} workers")
    if batch_size is not None and (not isinstance(batch_size, int) or batch_size < 1):
        raise StudyError(f"batch_size must be an integer >= 1, got {batch_size!r}")
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise StudyError(f"retries must be an integer >= 0, got {retries!r}")
    if address is not None and name != "ray":
        raise StudyError("address (--address) is for the ray backend")
    if name == "serial":
        return SerialBackend()
    if name == "process":
        return ProcessBackend(workers, batch_size, retries)
    return RayBackend(address, workers, batch_size, retries)
