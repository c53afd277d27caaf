"""Server tokens: made at start, kept in a user-only file that local clients read.

Jupyter's model: ``workcell serve`` makes a random token (unless one is given), prints
where it is and writes ``server-PORT.json`` (``{"port", "host", "token", "pid"}``, mode
0600, in a folder of mode 0700) into the runtime folder: ``$WORKCELL_RUNTIME_DIR``, else
``$XDG_RUNTIME_DIR/workcell``, else ``~/.local/share/workcell/runtime``. A client on the
same machine, run by the same user, reads it (:func:`read_token_file`) and sends the
token in its hello; other users cannot read it. The file is removed when the server
stops.
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

from workcell.errors import ProgramError
from workcell.files import atomic_write_text

__all__ = [
    "Throttle",
    "is_loopback",
    "new_token",
    "read_token_file",
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
    path = token_file(port)
    data = {"port": int(port), "host": host, "token": token, "pid": os.getpid()}
    atomic_write_text(path, json.dumps(data), error=ProgramError, mode=0o600)
    return path


def read_token_file(port: int) -> str | None:
    """The token of the local server on ``port``, from its token file (None when there is
    no readable token file)."""
    try:
        with open(token_file(port), encoding="utf-8") as f:
            data = json.loads(f.read(65536))
    except (OSError, ValueError):
        return None
    token = data.get("token") if isinstance(data, dict) else None
    return token if isinstance(token, str) else None


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
