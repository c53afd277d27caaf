"""Native geometry work in child processes: a crash there is an error here, never the end.

Some native libraries abort the whole process on inputs they cannot take: CoACD ends in
``std::length_error`` on a needle-thin cylinder and in ``std::bad_alloc`` after eating
3 GB on a 490,000-facet torus, and nothing in Python can catch that. So such work runs in
child processes (:func:`run`): each job is a call of a function of this package with
plain arguments (numpy arrays, numbers), sent to a child Python over a pipe, and its
result comes back the same way. The child

- may use at most ``max_native_bytes`` of address space (``RLIMIT_AS``) and each job at
  most ``max_native_seconds`` of wall time (:mod:`workcell.limits`; the parent kills it
  then);
- dies with its parent (``PR_SET_PDEATHSIG``), is killed at once on Ctrl-C in the parent
  and on any error, and runs one BLAS / OpenMP thread;
- writes nothing on this process's stdout (its own stdout goes to its stderr, whose last
  lines are kept for the error message).

A child that dies (a signal, an abort, out of memory) gives a
:class:`~workcell.errors.NativeCrashError`, a :class:`~workcell.errors.ModelError` naming the job's label and what the child said last;
a job over its time a :class:`~workcell.errors.LimitError`; a
:class:`~workcell.errors.WorkcellError` raised in the child is raised here as the same
class. Several jobs run on ``workers`` children at once; ``on_done(i, label, seconds)``
is called in the parent as each one finishes (for progress bars). A child costs about
0.3 s to start (a fresh interpreter importing numpy).

Only functions of the ``workcell`` package can be called (``"workcell.module:function"``).
"""

from __future__ import annotations

import contextlib
import importlib
import os
import pickle
import selectors
import signal
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from workcell import errors, limits
from workcell.errors import ModelError, NativeCrashError, WorkcellError
from workcell.tempfiles import process_alive

__all__ = ["Job", "die_with_parent", "run"]

_HEADER = struct.Struct("<Q")
_TAIL = 2000  # characters of the child's stderr kept for an error message
_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
_PACKAGE = __name__.split(".")[0] + "."  # "workcell.": only its functions run in children
_PACKAGE_ROOT = str(Path(__file__).resolve().parent.parent)


@dataclass(frozen=True)
class Job:
    """One call in a child: ``function`` ("workcell.module:name") with ``args``; ``label``
    names the work in messages ("link 'forearm' (CoACD)")."""

    function: str
    args: tuple = ()
    label: str = "native geometry work"


# ---------------------------------------------------------------------- the parent
def run(
    jobs: Sequence[Job],
    *,
    workers: int | None = None,
    on_done: Callable[[int, str, float], None] | None = None,
) -> list[Any]:
    """Run ``jobs`` in child processes; their results in order (module doc).

    ``workers``: children at once (default: the cores, at most the jobs). Raises
    NativeCrashError, LimitError (a job over ``max_native_seconds``) or the child's
    WorkcellError; every child is gone when this returns or raises, Ctrl-C included.
    """
    for job in jobs:
        if not job.function.startswith(_PACKAGE) or ":" not in job.function:
            raise ValueError(f"native jobs call workcell functions only, got {job.function!r}")
    if not jobs:
        return []
    lim = limits.current()
    n = max(1, min(workers or os.cpu_count() or 1, len(jobs)))
    pool = _Pool(n, int(lim.max_native_bytes), float(lim.max_native_seconds))
    try:
        return pool.run(list(jobs), on_done)
    finally:
        pool.close()


class _Child:
    def __init__(self, memory: int) -> None:
        env = dict(os.environ)
        env.update(dict.fromkeys(_THREAD_VARS, "1"))
        env["PYTHONPATH"] = os.pathsep.join(
            p for p in (_PACKAGE_ROOT, env.get("PYTHONPATH", "")) if p
        )
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "workcell.native", str(memory), str(os.getpid())],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            env=env,
            start_new_session=True,  # Ctrl-C reaches the parent only; it kills the child
        )
        self.inbox = b""
        self.tail = ""
        self.job: int | None = None
        self.started = 0.0
        for f in (self.proc.stdout, self.proc.stderr):
            os.set_blocking(f.fileno(), False)

    def send(self, index: int, job: Job) -> None:
        data = pickle.dumps((job.function, job.args), protocol=pickle.HIGHEST_PROTOCOL)
        self.job, self.started = index, time.monotonic()
        try:
            self.proc.stdin.write(_HEADER.pack(len(data)) + data)
            self.proc.stdin.flush()
        except (BrokenPipeError, OSError):
            pass  # the child is gone: its EOF on stdout reports it

    def message(self) -> tuple | None:
        if len(self.inbox) < _HEADER.size:
            return None
        (size,) = _HEADER.unpack_from(self.inbox)
        if len(self.inbox) < _HEADER.size + size:
            return None
        body = self.inbox[_HEADER.size : _HEADER.size + size]
        self.inbox = self.inbox[_HEADER.size + size :]
        return pickle.loads(body)

    def kill(self) -> None:
        with contextlib.suppress(OSError):
            self.proc.kill()
        for f in (self.proc.stdin, self.proc.stdout, self.proc.stderr):
            with contextlib.suppress(OSError):
                f.close()
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(timeout=5)


class _Pool:
    def __init__(self, n: int, memory: int, seconds: float) -> None:
        self.memory, self.seconds = memory, seconds
        self.children: list[_Child] = []
        self.sel = selectors.DefaultSelector()
        for _ in range(n):
            child = _Child(memory)
            self.children.append(child)
            self.sel.register(child.proc.stdout, selectors.EVENT_READ, (child, "out"))
            self.sel.register(child.proc.stderr, selectors.EVENT_READ, (child, "err"))

    def run(self, jobs: list[Job], on_done: Callable[[int, str, float], None] | None) -> list:
        results: list[Any] = [None] * len(jobs)
        todo = iter(range(len(jobs)))
        left = len(jobs)
        for child in self.children:
            i = next(todo, None)
            if i is not None:
                child.send(i, jobs[i])
        while left:
            busy = [c for c in self.children if c.job is not None]
            now = time.monotonic()
            wait = min(c.started + self.seconds for c in busy) - now
            for c in busy:
                if now - c.started > self.seconds:
                    raise limits.exceeded("max_native_seconds", now - c.started, jobs[c.job].label)
            for key, _ in self.sel.select(timeout=max(wait, 0.0)):
                child, which = key.data
                chunk = os.read(key.fd, 1 << 20)
                if which == "err":
                    if chunk:
                        child.tail = (child.tail + chunk.decode(errors="replace"))[-_TAIL:]
                    continue
                if not chunk:  # the child is gone
                    raise self._crashed(child, jobs)
                child.inbox += chunk
                while (msg := child.message()) is not None:
                    i = child.job
                    seconds = time.monotonic() - child.started
                    results[i] = self._result(msg, jobs[i])
                    left -= 1
                    child.job = None
                    if on_done is not None:
                        on_done(i, jobs[i].label, seconds)
                    nxt = next(todo, None)
                    if nxt is not None:
                        child.send(nxt, jobs[nxt])
        return results

    def _result(self, msg: tuple, job: Job) -> Any:
        if msg[0] == "ok":
            return msg[1]
        _, kind, text = msg
        cls = getattr(errors, kind, None)
        if cls is NativeCrashError:
            raise NativeCrashError(f"{job.label}: {text}; nothing was changed")
        if isinstance(cls, type) and issubclass(cls, WorkcellError):
            raise cls(text)
        raise ModelError(f"{job.label}: {kind}: {text}")

    def _crashed(self, child: _Child, jobs: list[Job]) -> NativeCrashError:
        child.kill()
        with contextlib.suppress(OSError):  # the last words on stderr
            rest = child.proc.stderr.read() if not child.proc.stderr.closed else b""
            child.tail = (child.tail + (rest or b"").decode(errors="replace"))[-_TAIL:]
        code = child.proc.returncode
        how = f"exit code {code}"
        if code is not None and code < 0:
            with contextlib.suppress(ValueError):
                how = f"signal {signal.Signals(-code).name}"
        said = " / ".join(ln.strip() for ln in child.tail.strip().splitlines()[-3:] if ln.strip())
        label = jobs[child.job].label if child.job is not None else "a native geometry job"
        gib = self.memory / (1 << 30)
        return NativeCrashError(
            f"{label}: the native code crashed ({how}{': ' + said if said else ''}); "
            f"the input is degenerate or too large for it (it may use at most {gib:.3g} GiB: "
            f"limit max_native_bytes); nothing was changed"
        )

    def close(self) -> None:
        self.sel.close()
        for child in self.children:
            if child.job is None and child.proc.poll() is None:
                with contextlib.suppress(OSError):
                    child.proc.stdin.close()  # an idle child ends on EOF
                with contextlib.suppress(subprocess.TimeoutExpired):
                    child.proc.wait(timeout=2)
            child.kill()


# ---------------------------------------------------------------------- the child
def die_with_parent(parent: int) -> None:
    """End this process when process ``parent`` dies, however it dies (kill -9 included).

    When ``parent`` forked this process, on Linux: the kernel's parent-death signal
    (``PR_SET_PDEATHSIG``), at once. Otherwise (another OS, or a process started by a fork
    server for ``parent``): a daemon thread that checks every second whether ``parent``
    still runs."""
    if os.getppid() == parent and sys.platform == "linux":
        armed = False
        with contextlib.suppress(Exception):
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            armed = libc.prctl(1, signal.SIGKILL) == 0  # PR_SET_PDEATHSIG
        if os.getppid() != parent:  # the parent died before prctl
            os._exit(1)
        if armed:
            return
    elif not process_alive(parent):
        os._exit(1)

    def watch() -> None:
        while process_alive(parent):
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, name="workcell-parent-watch", daemon=True).start()


def _child_main(memory: int, parent: int) -> None:
    die_with_parent(parent)
    import resource

    with contextlib.suppress(ValueError, OSError):
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    out = os.fdopen(os.dup(1), "wb")  # the protocol's channel; fd 1 now goes to stderr
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    inp = sys.stdin.buffer
    while True:
        head = inp.read(_HEADER.size)
        if len(head) < _HEADER.size:
            return  # the parent closed the pipe: done
        (size,) = _HEADER.unpack(head)
        function, args = pickle.loads(inp.read(size))
        try:
            module, _, name = function.partition(":")
            reply: tuple = ("ok", getattr(importlib.import_module(module), name)(*args))
        except MemoryError:
            reply = ("err", "NativeCrashError", "out of memory (limit max_native_bytes)")
        except Exception as exc:  # reported to the parent, which raises it
            reply = ("err", type(exc).__name__, str(exc))
        data = pickle.dumps(reply, protocol=pickle.HIGHEST_PROTOCOL)
        out.write(_HEADER.pack(len(data)) + data)
        out.flush()


if __name__ == "__main__":
    _child_main(int(sys.argv[1]), int(sys.argv[2]))
