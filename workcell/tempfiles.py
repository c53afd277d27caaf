"""Temp files of the atomic writer (:mod:`workcell.files`): their names, and their cleanup.

A temp file is made beside its target as ``.NAME.HOST-PID-RANDOM SUFFIX`` (mode 0600),
tracked before it exists and removed when its write ends (renamed over the target, or
deleted on any error, on Ctrl-C, at exit and on SIGTERM once
:func:`install_sigterm_cleanup` has run). Nothing runs on SIGKILL or a power cut: the next
write of the same file removes the temp files this machine's dead processes left (its
name says whose it is; another machine's or a live process's are left alone). Also the
wording of file-system failures shared by the readers and writers.
"""

from __future__ import annotations

import atexit
import contextlib
import errno
import hashlib
import os
import re
import secrets
import signal
import socket
import stat
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from workcell.errors import WorkcellError

__all__ = ["install_sigterm_cleanup", "kind", "process_alive", "reason", "temp_file"]

Error = type[WorkcellError]

_REASONS = {
    errno.ENOENT: "no such file or folder",
    errno.ENOTDIR: "a part of the path is not a folder",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
    errno.EROFS: "read-only file system",
    errno.ENAMETOOLONG: "file name too long",
    errno.ENOSPC: "no space left on device",
    errno.EDQUOT: "disk quota exceeded",
    errno.EISDIR: "it is a folder",
    errno.ELOOP: "too many levels of symbolic links",
    errno.EEXIST: "it exists and is not a folder",
}


def reason(exc: OSError) -> str:
    """A short wording of a file-system failure."""
    return _REASONS.get(exc.errno or 0) or exc.strerror or str(exc)


# ------------------------------------------------------------------ SIGTERM cleanup
_live: set[str] = set()
_live_lock = threading.Lock()
_previous: Any = None
_installed = False


def _remove_live() -> None:
    """Remove the temp files of writes still in progress (a signal, or the interpreter
    leaving while daemon threads write)."""
    with _live_lock:
        tmps = list(_live)
    for tmp in tmps:
        with contextlib.suppress(OSError):
            os.unlink(tmp)


atexit.register(_remove_live)


def _on_sigterm(signum: int, frame: Any) -> None:
    _remove_live()
    if callable(_previous):
        _previous(signum, frame)
        return
    signal.signal(signum, signal.SIG_DFL)  # die of the signal, as without us
    os.kill(os.getpid(), signum)


def install_sigterm_cleanup() -> bool:
    """Make SIGTERM remove the temp files of writes in progress (then act as before).

    Needs the main thread: :func:`atomic_path` calls it when it runs there; servers call
    it at start for their worker threads. Returns whether the handler is installed.
    """
    global _previous, _installed
    if _installed:
        return True
    if threading.current_thread() is not threading.main_thread():
        return False
    prev = signal.getsignal(signal.SIGTERM)
    if prev is signal.SIG_IGN:
        return False
    _previous = prev if callable(prev) else None
    signal.signal(signal.SIGTERM, _on_sigterm)
    _installed = True
    return True


def kind(mode: int) -> str:
    """What a file of ``mode`` is, when it is not a regular file (\"a FIFO\" ...)."""
    for test, kind in (
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return kind
    return "not a regular file"


_HOST = hashlib.sha256(socket.gethostname().encode()).hexdigest()[:6]
_TEMP = re.compile(r"\.(?P<host>[0-9a-f]{6})-(?P<pid>\d{1,10})-[0-9a-f]{8}")


def _temp_name(p: Path, suffix: str) -> str:
    """``.NAME.HOST-PID-RANDOM SUFFIX`` beside ``p``: whose it is, so a later write can
    tell a temp file whose writer died (kill -9) from one being written now."""
    return os.path.join(
        p.parent, f".{p.name[:80]}.{_HOST}-{os.getpid()}-{secrets.token_hex(4)}{suffix}"
    )


def _remove_stale_temps(p: Path) -> None:
    """Remove the temp files of earlier writes of ``p`` whose writer is gone: made on this
    machine by a process that no longer runs (killed with SIGKILL mid-write, or a power
    cut), or by this process and no longer in use. Others' (another machine's, a live
    process's) are left alone."""
    head = f".{p.name[:80]}"
    try:
        names = [e.name for e in os.scandir(p.parent) if e.name.startswith(head)]
    except OSError:
        return
    for name in names:
        m = _TEMP.match(name, len(head))
        if m is None or m.group("host") != _HOST:
            continue
        pid = int(m.group("pid"))
        full = os.path.join(p.parent, name)
        if pid == os.getpid():
            with _live_lock:
                if full in _live:
                    continue
        elif process_alive(pid):
            continue
        with contextlib.suppress(OSError):
            st = os.lstat(full)
            if stat.S_ISREG(st.st_mode) and st.st_uid == os.getuid():
                os.unlink(full)


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` of this machine runs (another user's counts as running)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True  # another user's process: alive
    return True


@contextlib.contextmanager
def temp_file(p: Path, suffix: str, path: object, error: Error, doing: str) -> Iterator[str]:
    """A new empty file (mode 0600) beside ``p``, removed when the block ends (unless it
    was renamed away). Its name is chosen and tracked before it exists, so no Ctrl-C or
    SIGTERM between creating and removing it can leave it behind; the temp files of
    earlier writes of ``p`` whose writer died (kill -9) are removed first."""
    _remove_stale_temps(p)
    tmp = _temp_name(p, suffix)
    with _live_lock:
        _live.add(tmp)
    not_ours = False
    try:
        try:
            os.close(os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY | os.O_CLOEXEC, 0o600))
        except OSError as exc:
            not_ours = isinstance(exc, FileExistsError)
            raise error(f"cannot {doing} '{path}': {reason(exc)}") from exc
        yield tmp
    finally:
        if not not_ours:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        with _live_lock:
            _live.discard(tmp)
