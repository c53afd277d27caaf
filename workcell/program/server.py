"""``workcell serve``: the remote program interface (thesis §4.6.2) over TCP.

A threaded server speaking :mod:`workcell.program.protocol` (each connection is a
:class:`~workcell.program.connection.Connection`): on connection it sends a
hello line; the client's first message must be its own ``hello`` (with the token), else
the connection is closed at once without running anything (an HTTP request, or any
text that is not a protocol message, never reaches a command). Then it reads requests
one line at a time and answers each (in order) with the result or the error of the
command (:data:`workcell.program.base.COMMANDS`), plus the protocol's own ``hello``,
``commands`` and ``bye``. Whatever a client sends, the server answers or closes that
connection and goes on serving the others.

Security (docs/protocol.md, "Security"): a token is required by default, also on
loopback (made at start and kept in a user-only file that local clients read:
:mod:`workcell.program.tokens`); a wrong token closes the connection, and repeated wrong
tokens from one address are answered ever more slowly; file names resolve inside the
``root`` folder; at most ``max_connections`` served at once (more are refused with an error
line); connections that have not yet said hello have their own small pool
(``max_waiting``): when it is full, a new connection closes the one that has waited
longest, so connections without a token can never keep a token holder out; a connection
without its hello after ``hello_timeout`` s, or without a request for ``idle_timeout``
s, is closed; anything but a good hello as the first line closes the connection (one
reply, one short log line); replies are bounded like requests (1 MiB). The log (logger
``workcell.server``) has one line per connection and per error.

Sessions: by default each connection gets its own :class:`Session` (made by
``session_factory`` after the hello), so clients cannot disturb each other; with
``shared=True`` all connections use one session and their commands are serialised.
"""

from __future__ import annotations

import contextlib
import logging
import socket
import socketserver
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from workcell.errors import ProgramError, ProtocolError, WorkcellError
from workcell.program.connection import Connection, clean_log_text, describe_commands
from workcell.program.protocol import (
    MAX_MESSAGE_BYTES,
    PROTOCOL,
    VERSION,
    encode,
    error_reply,
)
from workcell.program.session import Session
from workcell.program.tokens import (
    Throttle,
    is_loopback,
    new_token,
    remove_token_file,
    write_token_file,
)

__all__ = ["Server", "describe_commands", "is_loopback"]

log = logging.getLogger("workcell.server")

MAX_CONNECTIONS = 16  # connections served at once; more are refused with an error line
MAX_WAITING = 8  # connections waiting for their hello; a new one closes the oldest
IDLE_TIMEOUT = 300.0  # s without a request (or without reading a reply) before closing
HELLO_TIMEOUT = 5.0  # s a new connection has to complete its hello
BAD_TOKEN_DELAY = 0.5  # s before answering a first wrong token; doubles up to 8 s


class Server(socketserver.ThreadingTCPServer):
    """The protocol server on ``(host, port)`` (port 0: any free port; see :attr:`port`).

    ``token``: the token clients must send in their hello (default: a new random one);
    ``require_token=False`` serves without one (loopback only). The token is written to a
    user-only token file that local clients read (:mod:`workcell.program.tokens`;
    ``token_path``), removed by :meth:`server_close`. ``root``: the folder file names of
    commands resolve in (default: the current folder). ``session_factory`` makes each
    connection's session (default: an empty Session); ``shared``: one session for all,
    commands serialised. ``max_connections``, ``max_waiting``, ``idle_timeout``,
    ``hello_timeout`` (s) and ``bad_token_delay`` (s): see the module doc.
    """

    daemon_threads = True
    block_on_close = False
    allow_reuse_address = True
    request_queue_size = 128  # the listen backlog

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 0,
        *,
        token: str | None = None,
        require_token: bool = True,
        shared: bool = False,
        session_factory: Callable[[], Session] = Session,
        root: str | Path = ".",
        max_connections: int = MAX_CONNECTIONS,
        max_waiting: int = MAX_WAITING,
        idle_timeout: float = IDLE_TIMEOUT,
        hello_timeout: float = HELLO_TIMEOUT,
        bad_token_delay: float = BAD_TOKEN_DELAY,
    ) -> None:
        if token is not None and (not isinstance(token, str) or len(token) < 8):
            raise ProgramError("a token must be a string of at least 8 characters")
        if not require_token and token is None and not is_loopback(host):
            raise ProgramError(
                f"refusing to serve on '{host}' without a token: anything but a loopback "
                "address (127.0.0.1, ::1, localhost) needs one"
            )
        self.root = Path(root).resolve()
        if not self.root.is_dir():
            raise ProgramError(f"the root folder '{root}' is not a folder")
        for what, v in (("idle_timeout", idle_timeout), ("hello_timeout", hello_timeout)):
            if not (isinstance(v, (int, float)) and v > 0):
                raise ProgramError(f"{what} must be a number of seconds > 0, got {v!r}")
        for what, n in (("max_connections", max_connections), ("max_waiting", max_waiting)):
            if not (isinstance(n, int) and not isinstance(n, bool) and n >= 1):
                raise ProgramError(f"{what} must be an integer >= 1, got {n!r}")
        if ":" in host:
            self.address_family = socket.AF_INET6
        self.token = token if token is not None or not require_token else new_token()
        self.session_factory = session_factory
        self.shared_session = self._rooted(session_factory()) if shared else None
        self.max_connections = max_connections
        self.max_waiting = max_waiting
        self._waiting: dict[Any, threading.Event] = {}  # socket -> its eviction, oldest first
        self._admitted: set[Any] = set()
        self.idle_timeout = float(idle_timeout)
        self.hello_timeout = float(hello_timeout)
        self.throttle = Throttle(bad_token_delay)
        self.connections = 0  # accepted so far
        self.active = 0  # served now
        self._count_lock = threading.Lock()
        self.token_path: Path | None = None
        try:
            super().__init__((host, port), Connection)
        except OSError as exc:
            raise ProgramError(f"cannot listen on {host}:{port}: {exc.strerror or exc}") from exc
        if self.token is not None:
            try:
                self.token_path = write_token_file(self.port, host, self.token)
            except WorkcellError:
                super().server_close()
                raise

    def _rooted(self, session: Session) -> Session:
        session.root = self.root
        session.reply_bytes = MAX_MESSAGE_BYTES
        return session

    def new_session(self) -> Session:
        """The session of a connection that said hello (the shared one, or a new one)."""
        if self.shared_session is not None:
            return self.shared_session
        return self._rooted(self.session_factory())

    def next_connection_id(self) -> int:
        with self._count_lock:
            self.connections += 1
            return self.connections

    @property
    def port(self) -> int:
        """The port the server listens on."""
        return int(self.server_address[1])

    def hello(self) -> dict[str, Any]:
        """The hello message (sent on connection and answered to ``hello``)."""
        from workcell import __version__

        return {
            "protocol": PROTOCOL,
            "version": VERSION,
            "server": f"workcell {__version__}",
            "max_message_bytes": MAX_MESSAGE_BYTES,
            "sessions": "shared" if self.shared_session is not None else "own",
            "token_required": self.token is not None,
            "idle_timeout_s": self.idle_timeout,
        }

    def busy_error(self) -> ProtocolError:
        return ProtocolError(
            f"server busy: {self.max_connections} connections are open (the limit); try again later"
        )

    def process_request(self, request: Any, client_address: Any) -> None:
        oldest = None
        with self._count_lock:
            busy = self.active >= self.max_connections
            if not busy:
                if len(self._waiting) >= self.max_waiting:  # make room: close the oldest
                    oldest = next(iter(self._waiting))
                    self._waiting.pop(oldest).set()
                self._waiting[request] = threading.Event()
        if oldest is not None:
            log.info("closing a connection that waited longest for its hello, to make room")
            with contextlib.suppress(OSError):
                oldest.shutdown(socket.SHUT_RD)
        if busy:  # refuse politely, here (no thread), never blocking the accept loop long
            log.warning("refused %s:%s: %d connections open", *client_address[:2], self.active)
            with contextlib.suppress(OSError):
                request.settimeout(1.0)
                request.sendall(encode(error_reply(None, self.busy_error())))
            self.shutdown_request(request)
            return
        try:
            super().process_request(request, client_address)
        except BaseException:
            self._release(request)
            raise

    def eviction(self, request: Any) -> threading.Event:
        """The event set when ``request`` (a connection still without its hello) is
        closed to make room (a fresh, unset one for a connection not in the pool)."""
        with self._count_lock:
            return self._waiting.get(request) or threading.Event()

    def admit(self, request: Any) -> bool:
        """Move a connection that said hello from the waiting pool to the served ones;
        False when ``max_connections`` are served already."""
        with self._count_lock:
            self._waiting.pop(request, None)
            if self.active >= self.max_connections:
                return False
            self.active += 1
            self._admitted.add(request)
            return True

    @property
    def waiting(self) -> int:
        """Connections that have not yet said hello."""
        return len(self._waiting)

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        try:
            super().process_request_thread(request, client_address)
        finally:
            self._release(request)

    def _release(self, request: Any) -> None:
        with self._count_lock:
            self._waiting.pop(request, None)
            if request in self._admitted:
                self._admitted.discard(request)
                self.active -= 1

    def handle_error(self, request: Any, client_address: Any) -> None:
        """A connection's failure: one log line (a traceback only for a bug), never stderr."""
        import sys

        exc = sys.exc_info()[1]
        if isinstance(exc, OSError):
            log.info("connection from %s:%s lost: %s", *client_address[:2], clean_log_text(exc))
        else:
            log.exception("connection from %s:%s: internal error", *client_address[:2])

    def serve_in_thread(self) -> threading.Thread:
        """Start serving in a daemon thread (tests, benchmarks); stop with :meth:`stop`."""
        t = threading.Thread(target=self.serve_forever, name="workcell-server", daemon=True)
        t.start()
        return t

    def server_close(self) -> None:
        """Close the listening socket and remove the token file."""
        super().server_close()
        if self.token is not None and self.token_path is not None:
            remove_token_file(self.port, self.token)

    def stop(self) -> None:
        """Stop serving and close the listening socket."""
        self.shutdown()
        self.server_close()
