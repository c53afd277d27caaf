"""A local pool of worker processes that streams rows back and survives worker crashes.

How a worker starts: on Linux, from a parent that runs no other Python thread (the
command line), it is a fork of the parent, which has the simulator imported already: it
is ready in milliseconds. Otherwise (a notebook's kernel has threads; forking a process
with threads can copy a lock some thread held) it is a fork of a *fork server*: a fresh,
single-threaded process that imports the simulator once (~1-2 s, once per process), so
later workers (after a crash, in the next study) are ready in milliseconds too; ``spawn``
where neither exists. Workers get the parent's current environment (a fork server's
would be that of when it started), run with one thread for numpy's and OpenMP's pools
and ignore SIGINT (Ctrl-C is the parent's to handle); a worker ends when the study's
process dies, however it dies (kill -9 included; :func:`workcell.native.die_with_parent`:
the kernel's parent-death signal when the study forked it on Linux, else a thread that
watches the study's process every second). Each receives the study's setup
once, compiles the cell, then evaluates batches of candidates, sending each row back as
soon as it is done. The parent hands a batch to each idle worker and waits on every worker's
pipe and process at once.

When a worker dies (a crash in native code, ``os._exit``, the OOM killer), the candidate
it was on is known exactly: the first of its batch without a row. That candidate goes
back to the front of the queue and is retried (on a new worker) up to ``retries`` times,
then gets an error row (``WorkerCrashed``); the rest of the batch goes back to the queue
untouched, and a new worker takes the dead one's place. Workers that die before they
are ready (a broken setup) stop the study with a StudyError after a few attempts.
"""

from __future__ import annotations

import collections
import contextlib
import multiprocessing as mp
import os
import pickle
import signal
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from multiprocessing.connection import Connection, wait
from typing import Any

from workcell.errors import StudyError
from workcell.native import die_with_parent

__all__ = ["CRASH_MESSAGE", "ProcessPool", "peak_rss_mb", "stop_fork_server"]

CRASH_MESSAGE = "a worker process died while evaluating this candidate; retried {} time(s)"
_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
_MAX_START_FAILURES = 3


def peak_rss_mb() -> float:
    """This process's peak resident memory (MB)."""
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _worker(conn: Connection, setup_bytes: bytes, environ: dict[str, str], parent: int) -> None:
    """A worker's life: set up, then evaluate batches until told to stop (module doc).

    ``environ``: the parent's environment when it started the worker (a fork server's
    children would otherwise see the environment of when the fork server started);
    ``parent``: the study's process id (the worker ends when it dies)."""
    die_with_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.environ.clear()
    os.environ.update(environ)
    import threading

    from tqdm import tqdm

    # workers draw no progress bars: a thread lock for tqdm, not its default
    # multiprocessing one (a semaphore a stopped worker would leave behind)
    tqdm.set_lock(threading.RLock())
    from workcell.study.evaluation import evaluator

    ev = evaluator(pickle.loads(setup_bytes))
    ev.template({})  # compile the cell before the first batch
    conn.send(("ready", os.getpid(), peak_rss_mb(), time.process_time()))
    while True:
        try:
            batch = conn.recv()
        except EOFError:  # the parent is gone
            return
        if batch is None:
            return
        for candidate in batch:
            conn.send(("row", ev.evaluate(candidate)))
        conn.send(("idle", os.getpid(), peak_rss_mb(), time.process_time()))


@contextlib.contextmanager
def _single_threaded() -> Iterator[None]:
    """Environment of the processes started in the block: one thread per numeric pool."""
    saved = {k: os.environ.get(k) for k in _THREAD_VARS}
    os.environ.update(dict.fromkeys(_THREAD_VARS, "1"))
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def stop_fork_server() -> None:
    """Stop this process's fork server and remove its socket folder (``pymp-*`` in the
    temporary folder), which Python otherwise keeps until the process exits; the next
    pool starts a new one. For long-lived processes that want them gone (test suites)."""
    import multiprocessing.forkserver
    import multiprocessing.util

    multiprocessing.forkserver._forkserver._stop()  # as Python's own tests stop it
    for finalizer in list(multiprocessing.util._finalizer_registry.values()):
        if finalizer._callback is multiprocessing.util._remove_temp_dir:
            finalizer()  # what would run at exit: remove the folder, forget it


def _only_thread() -> bool:
    """True when this process runs no Python thread but the main one, after stopping
    tqdm's monitor thread (any tqdm bar, even a hidden one, starts it; a new bar starts
    it again)."""
    from tqdm import tqdm

    monitor = tqdm.monitor
    if monitor is not None and threading.active_count() == 2:
        monitor.exit()
        tqdm.monitor = None
    return threading.active_count() == 1


def _context() -> Any:
    """Fork from a single-threaded parent on Linux, else the fork server's context
    (preloading the simulator), else spawn's (module doc)."""
    methods = mp.get_all_start_methods()
    if sys.platform == "linux" and "fork" in methods and _only_thread():
        return mp.get_context("fork")
    if "forkserver" in methods:
        ctx = mp.get_context("forkserver")
        ctx.set_forkserver_preload(["workcell.study.evaluation"])
        return ctx
    return mp.get_context("spawn")


@dataclass
class _Worker:
    process: Any
    conn: Connection
    ready: bool = False
    inflight: collections.deque = field(default_factory=collections.deque)


class ProcessPool:
    """``workers`` processes evaluating ``setup``'s candidates in batches of ``batch_size``
    (module doc); ``retries``: how often a candidate that kills its worker is retried."""

    def __init__(self, setup: Any, workers: int, batch_size: int, retries: int) -> None:
        self.setup = setup
        self.setup_bytes = pickle.dumps(setup)
        self.workers = workers
        self.batch_size = batch_size
        self.retries = retries
        self.memory_mb: dict[int, float] = {}  # worker pid -> peak resident memory
        self.cpu_s: dict[int, float] = {}  # worker pid -> CPU time on candidates (s)
        self._cpu0: dict[int, float] = {}
        self.crashes = 0
        self._ctx = _context()
        self.start_method: str = self._ctx.get_start_method()

    def _start(self) -> _Worker:
        parent, child = self._ctx.Pipe(duplex=True)
        with _single_threaded():
            env = dict(os.environ)
            p = self._ctx.Process(
                target=_worker, args=(child, self.setup_bytes, env, os.getpid()), daemon=True
            )
            p.start()
        child.close()
        return _Worker(p, parent)

    def run(self, todo: list[Any]) -> Iterator[dict[str, Any]]:
        """A row per candidate of ``todo``, as they finish (any order)."""
        self._queue = collections.deque(todo)
        self._attempts: collections.Counter[int] = collections.Counter()
        self._start_failures = 0
        pool: list[_Worker] = []
        finished = False
        try:
            try:
                for _ in range(min(self.workers, len(todo))):
                    pool.append(self._start())
            except (BrokenPipeError, EOFError, RuntimeError) as exc:
                raise StudyError(
                    f"worker processes could not start ({type(exc).__name__}); a script that "
                    'runs a study with worker processes must do so under "if __name__ == '
                    "'__main__':\" (Python starts each worker by importing the main script), "
                    "or use backend 'serial'"
                ) from exc
            while self._queue or any(w.inflight for w in pool):
                self._dispatch(pool)
                yield from self._receive(pool, None)
                if self._queue and len(pool) < self.workers:
                    pool.append(self._start())  # in place of a dead one
            for w in pool:  # done: let the workers end themselves
                with contextlib.suppress(OSError):
                    w.conn.send(None)
            finished = True
        finally:  # interrupted (or a worker that will not end): stopped
            for w in pool:
                w.process.join(timeout=5 if finished else 0)
                if w.process.is_alive():
                    w.process.terminate()
                    w.process.join()
                w.conn.close()

    def _dispatch(self, pool: list[_Worker]) -> None:
        """Give a batch to every ready, idle worker."""
        q = self._queue
        for w in pool:
            if w.ready and not w.inflight and q:
                batch = [q.popleft() for _ in range(min(self.batch_size, len(q)))]
                w.inflight.extend(batch)
                w.conn.send(batch)

    def _receive(self, pool: list[_Worker], timeout: float | None) -> Iterator[dict[str, Any]]:
        """Rows and messages from the workers (waiting up to ``timeout`` s, None: until
        something happens); dead workers are buried."""
        by_conn = {w.conn: w for w in pool}
        by_sentinel = {w.process.sentinel: w for w in pool}
        dead: list[_Worker] = []
        for obj in wait([*by_conn, *by_sentinel], timeout):
            w = by_conn.get(obj) or by_sentinel[obj]
            if w in dead:
                continue
            try:
                while w.conn.poll():
                    kind, *rest = w.conn.recv()
                    if kind == "row":
                        w.inflight.popleft()
                        yield rest[0]
                    else:  # "ready" or "idle": pid, memory (MB), CPU time (s)
                        w.ready = True
                        pid, mb, cpu = rest
                        self.memory_mb[pid] = mb
                        self.cpu_s[pid] = cpu - self._cpu0.setdefault(pid, cpu)
            except (EOFError, OSError):
                dead.append(w)
                continue
            if obj is w.process.sentinel:
                dead.append(w)
        for w in dead:
            pool.remove(w)
            yield from self._bury(w)

    def _bury(self, w: _Worker) -> Iterator[dict[str, Any]]:
        """A dead worker: its candidate is retried or gets its error row; the rest of its
        batch goes back to the queue."""
        from workcell.study.evaluation import error_row

        w.process.join()
        w.conn.close()
        if not w.ready:
            self._start_failures += 1
            if self._start_failures > _MAX_START_FAILURES:
                raise StudyError(
                    f"worker processes die before they start (exit code "
                    f"{w.process.exitcode}); run with backend 'serial' to see why"
                )
        if not w.inflight:
            return
        self.crashes += 1
        suspect = w.inflight.popleft()
        self._queue.extendleft(reversed(w.inflight))
        self._attempts[suspect.id] += 1
        if self._attempts[suspect.id] > self.retries:
            yield error_row(
                self.setup, suspect, "WorkerCrashed", CRASH_MESSAGE.format(self.retries)
            )
        else:
            self._queue.appendleft(suspect)
