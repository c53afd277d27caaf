"""Server tokens: made at start, kept in a user-only file that local clients read.

Jupyter's model: ``workcell serve`` makes a random token (unless one is given), prints
where it is and writes ``server-PORT.json`` (``{"port", "host", "token", "pid"}``, mode
0600, in a folder of mode 0700) into the runtime folder: ``$WORKCELL_RUNTIME_DIR``, else
``$XDG_RUNTIME_DIR/workcell``, else ``~/.local/share/workcell/runtime``. A client on the
same machine, run by the same user, reads it (:func:`read_token_file`) and sends the
token in its hello; other users cannot read it. The file is removed when the server
stops; the files of servers that died without removing theirs (kill -9, a crash) are
removed when the next server starts (:func:`remove_stale_token_files`).

A token the user chooses (:func:`given_token`) comes from a file (``--token-file``) or
the environment (``WORKCELL_TOKEN``); ``--token TOKEN`` still works but puts the token
on the command line, where every user of the machine sees it (``ps``).
"""

from __future__ import annotations

import contextlib
import ipaddress
import json
import os
import secrets
import socket
import threading
import time
from pathlib import Path

from workcell import limits
from workcell.errors import ProgramError, WorkcellError
from workcell.files import atomic_write_text, read_text
from workcell.tempfiles import process_alive

__all__ = [
    "Throttle",
    "given_token",
    "is_loopback",
    "new_token",
    "read_token_file",
    "remove_stale_token_files",
    "remove_token_file",
    "runtime_dir",
    "token_file",
    "write_token_file",
]


def is_loopback(host: str) -> bool:
    """True when every address ``host`` resolves to is a loopback address."""
    try:
        infos = socket.getaddrinfo(host, None)
    except OSError:
        return False
    addrs = {info[4][0] for info in infos}
    return bool(addrs) and all(ipaddress.ip_address(a.split("%")[0]).is_loopback for a in addrs)


def runtime_dir() -> Path:
    """The folder of the token files (see the module doc)."""
    env = os.environ.get("WORKCELL_RUNTIME_DIR")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_RUNTIME_DIR")
    if xdg:
        return Path(xdg) / "workcell"
    return Path.home() / ".local" / "share" / "workcell" / "runtime"


def token_file(port: int) -> Path:
    """The token file of the server on ``port``."""
    return runtime_dir() / f"server-{int(port)}.json"


def new_token() -> str:
    """A fresh random token (32 random bytes, URL-safe text)."""
    return secrets.token_urlsafe(32)


def write_token_file(port: int, host: str, token: str) -> Path:
    """Write the token file of the server on ``host:port`` (user-only); return its path."""
    folder = runtime_dir()
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        if folder.stat().st_uid == os.getuid():
            os.chmod(folder, 0o700)
    except OSError as exc:
        raise ProgramError(f"cannot create the token folder '{folder}': {exc.strerror}") from exc
    remove_stale_token_files()
    path = token_file(port)
    data = {
        "port": int(port),
        "host": host,
        "token": token,
        "pid": os.getpid(),
        "machine": socket.gethostname(),
    }
    atomic_write_text(path, json.dumps(data), error=ProgramError, mode=0o600)
    return path


def _read(path: Path) -> dict | None:
    try:
        with limits.using(max_file_bytes=65536):
            data = json.loads(read_text(path, what="token file", error=ProgramError))
    except (WorkcellError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def read_token_file(port: int) -> str | None:
    """The token of the local server on ``port``, from its token file (None when there is
    no readable token file)."""
    data = _read(token_file(port))
    token = None if data is None else data.get("token")
    return token if isinstance(token, str) else None


def remove_stale_token_files() -> list[Path]:
    """Remove the token files of this machine's servers that are no longer running (their
    process died without removing its file: kill -9, a crash); return the files removed.
    Files of live servers, of other machines (a home folder shared over the network) and
    files that are not token files are left alone."""
    removed = []
    try:
        paths = sorted(runtime_dir().glob("server-*.json"))
    except OSError:
        return removed
    for path in paths:
        data = _read(path)
        pid = None if data is None else data.get("pid")
        if data is None or data.get("machine") != socket.gethostname():
            continue
        if not isinstance(pid, int) or isinstance(pid, bool) or pid <= 0 or process_alive(pid):
            continue
        with contextlib.suppress(OSError):
            path.unlink()
            removed.append(path)
    return removed


def given_token(
    token: str | None, token_file: str | None, environ: dict[str, str] | None = None
) -> tuple[str | None, str | None]:
    """The token the user chose for a server, and a warning to print (or None).

    ``token_file``: a file whose first line is the token (its other lines are ignored);
    else ``token`` (the ``--token`` option: every user of the machine sees it in the
    process list, hence the warning); else ``WORKCELL_TOKEN`` from ``environ`` (default:
    the process's); None when none is given (the server makes one). ProgramError for an
    unreadable file or an empty token."""
    env = os.environ if environ is None else environ
    if token_file is not None and token is not None:
        raise ProgramError("give the token by --token-file or --token, not both")
    warning = None
    if token_file is not None:
        with limits.using(max_file_bytes=65536):
            text = read_text(token_file, what="token file", error=ProgramError)
        token = (text.splitlines() or [""])[0].strip()
        if not token:
            raise ProgramError(
                f"the token file '{token_file}' is empty; its first line is the token"
            )
        st = os.stat(token_file)
        if st.st_mode & 0o077:
            warning = (
                f"warning: the token file '{token_file}' can be read by other users "
                f"(mode {st.st_mode & 0o777:o}); chmod 600 it"
            )
    elif token is not None:
        warning = (
            "warning: --token puts the token on the command line, where every user of this "
            "machine can read it (ps); give it with --token-file FILE or the WORKCELL_TOKEN "
            "environment variable instead"
        )
    else:
        token = env.get("WORKCELL_TOKEN") or None
    return token, warning


def remove_token_file(port: int, token: str) -> None:
    """Remove the token file of ``port`` if it still holds ``token`` (not a newer server's)."""
    if read_token_file(port) == token:
        with contextlib.suppress(OSError):
            token_file(port).unlink()


_MAX_DELAY = 8.0  # s: the longest wait for one wrong token


class Throttle:
    """Answers to wrong tokens from one address come ever later: ``delay`` (s) for the
    first, doubling up to 8 s; attempts on parallel connections queue behind each
    other; a right token resets the count."""

    def __init__(self, delay: float) -> None:
        self.delay = delay
        self._lock = threading.Lock()
        self._state: dict[str, tuple[int, float]] = {}  # address -> (failures, next answer)

    def failed(self, addr: str, cancel: threading.Event | None = None) -> float:
        """Sleep as long as this failure earns (or until ``cancel`` is set: the
        connection was closed meanwhile); return the seconds waited."""
        with self._lock:
            n, ready = self._state.get(addr, (0, 0.0))
            now = time.monotonic()
            ready = max(ready, now) + min(self.delay * 2.0 ** min(n, 30), _MAX_DELAY)
            self._state[addr] = (n + 1, ready)
        wait = ready - now
        if wait > 0:
            (cancel or threading.Event()).wait(wait)
        return wait

    def succeeded(self, addr: str) -> None:
        """A right token from ``addr``: its count starts again."""
        with self._lock:
            self._state.pop(addr, None)
