"""``workcell serve``: the remote program interface (thesis §4.6.2) over TCP.

A threaded server speaking :mod:`workcell.program.protocol`: on connection it sends a
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
``root`` folder; at most ``max_connections`` at once (more are refused with an error
line); a connection without its hello after ``hello_timeout`` s, or without a request
for ``idle_timeout`` s, is closed; replies are bounded like requests (1 MiB). The log
(logger ``workcell.server``) has one line per connection and per error.

Sessions: by default each connection gets its own :class:`Session` (made by
``session_factory`` after the hello), so clients cannot disturb each other; with
``shared=True`` all connections use one session and their commands are serialised.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hmac
import logging
import socket
import socketserver
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from workcell.errors import ProgramError, ProtocolError, WorkcellError
from workcell.program.args import label
from workcell.program.base import COMMANDS, command_class
from workcell.program.protocol import (
    MAX_MESSAGE_BYTES,
    PROTOCOL,
    VERSION,
    decode_request,
    encode,
    error_reply,
    error_type,
    to_jsonable,
)
from workcell.program.session import Session
from workcell.program.tokens import is_loopback, new_token, remove_token_file, write_token_file

__all__ = ["Server", "describe_commands", "is_loopback"]

log = logging.getLogger("workcell.server")

MAX_CONNECTIONS = 16  # connections served at once; more are refused with an error line
IDLE_TIMEOUT = 300.0  # s without a request (or without reading a reply) before closing
HELLO_TIMEOUT = 10.0  # s a new connection has to complete its hello
BAD_TOKEN_DELAY = 0.5  # s before answering a first wrong token; doubles up to 8 s
_BAD_TOKEN_MAX_DELAY = 8.0


def describe_commands() -> list[dict[str, Any]]:
    """Every command with its arguments (name, required, default, type, unit), for
    the protocol's ``commands``."""
    out = []
    for name in sorted(COMMANDS):
        cls = COMMANDS[name]
        args = []
        for f in dataclasses.fields(cls):  # type: ignore[arg-type]
            required = f.default is dataclasses.MISSING
            default = None if required else f.default
            try:
                default = to_jsonable(default)
            except ProtocolError:
                default = None
            args.append(
                {
                    "name": f.name,
                    "required": required,
                    "default": default,
                    "type": label(f.metadata["convert"]),
                    "unit": f.metadata.get("doc", ""),
                }
            )
        out.append({"name": name, "doc": (cls.__doc__ or "").strip(), "args": args})
    return out


def _clean(text: object, limit: int = 300) -> str:
    """One log-safe line: control characters escaped, at most ``limit`` characters."""
    s = str(text)
    s = "".join(c if c.isprintable() else repr(c)[1:-1] for c in s[: limit + 1])
    return s if len(s) <= limit else s[: limit - 3] + "..."


class _Throttle:
    """Answers to wrong tokens from one address come ever later (delays double, and
    attempts on parallel connections queue behind each other)."""

    def __init__(self, delay: float) -> None:
        self.delay = delay
        self._lock = threading.Lock()
        self._state: dict[str, tuple[int, float]] = {}  # address -> (failures, next answer)

    def failed(self, addr: str) -> float:
        """Sleep as long as this failure earns; return the seconds slept."""
        with self._lock:
            n, ready = self._state.get(addr, (0, 0.0))
            now = time.monotonic()
            ready = max(ready, now) + min(self.delay * 2**n, _BAD_TOKEN_MAX_DELAY)
            self._state[addr] = (n + 1, ready)
        wait = ready - now
        if wait > 0:
            time.sleep(wait)
        return wait

    def succeeded(self, addr: str) -> None:
        with self._lock:
            self._state.pop(addr, None)


class _Closing(Exception):  # noqa: N818 - control flow, not an error
    """Reply (if any) then close the connection; ``why`` goes to the log."""

    def __init__(self, reply: dict[str, Any] | None, why: str) -> None:
        super().__init__(why)
        self.reply, self.why = reply, why


class _Handler(socketserver.StreamRequestHandler):
    server: Server

    def setup(self) -> None:
        super().setup()
        self.connection.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.connection.settimeout(self.server.idle_timeout)

    def handle(self) -> None:
        srv = self.server
        self.cid = srv.next_connection_id()
        self.addr = str(self.client_address[0])
        self.requests, self.session, self.greeted = 0, None, False
        t0 = time.monotonic()
        log.info("connection %d from %s:%s opened", self.cid, self.addr, self.client_address[1])
        timer = threading.Timer(srv.hello_timeout, self._hello_expired)
        timer.daemon = True
        why = "the client went away"
        try:
            timer.start()
            self._send(srv.hello())
            why = self._serve()
        except _Closing as c:
            if c.reply is not None:
                self._send(c.reply)
            why = c.why
        except OSError as exc:  # reset, broken pipe, timeout while sending
            why = f"connection lost ({exc.__class__.__name__})"
        finally:
            timer.cancel()
            log.info(
                "connection %d closed: %s (%d requests, %.1f s)",
                self.cid, _clean(why), self.requests, time.monotonic() - t0,
            )  # fmt: skip

    def _hello_expired(self) -> None:
        if not self.greeted:
            self.expired = True
            with contextlib.suppress(OSError):
                self.connection.shutdown(socket.SHUT_RD)

    def _serve(self) -> str:
        while True:
            try:
                line = self.rfile.readline(MAX_MESSAGE_BYTES + 1)
            except TimeoutError:
                secs = self.server.idle_timeout
                raise _Closing(
                    error_reply(None, ProtocolError(f"closed after {secs:g} s without a request")),
                    f"idle for {secs:g} s",
                ) from None
            if not line:
                if getattr(self, "expired", False):
                    secs = self.server.hello_timeout
                    raise _Closing(
                        error_reply(None, ProtocolError(f"no hello within {secs:g} s: closed")),
                        f"no hello within {secs:g} s",
                    )
                return "the client went away"
            if len(line) > MAX_MESSAGE_BYTES:
                if not self.greeted:
                    raise _Closing(
                        self._not_a_hello(None, "an over-long first line"), "not a hello"
                    )
                self._discard_rest(line)
                exc = ProtocolError(
                    f"message longer than {MAX_MESSAGE_BYTES} bytes refused "
                    "(the limit includes the newline)"
                )
                self._log_error(None, "-", exc)
                self._send(error_reply(None, exc))
                continue
            if not line.strip():
                continue
            self.requests += 1
            reply, close = self._answer(line)
            self._send(reply)
            if close:
                return "bye"

    def _discard_rest(self, line: bytes) -> None:
        while line and not line.endswith(b"\n"):
            line = self.rfile.readline(65536)

    def _send(self, message: dict[str, Any]) -> None:
        rid = message.get("id")
        try:
            data = encode(message)
        except (ProtocolError, ValueError, TypeError) as exc:
            data = encode(error_reply(rid, ProtocolError(f"result not sendable: {exc}")))
        if len(data) > MAX_MESSAGE_BYTES:
            exc = ProtocolError(
                f"the reply is {len(data):,} bytes, over the {MAX_MESSAGE_BYTES:,}-byte bound "
                "(the command ran; ask for less)"
            )
            self._log_error(rid, "-", exc)
            data = encode(error_reply(rid, exc))
        self.wfile.write(data)
        self.wfile.flush()

    def _not_a_hello(self, rid: Any, what: str) -> dict[str, Any]:
        exc = ProtocolError(
            f'the first message must be a hello: {{"id": 0, "command": "hello", "args": '
            f'{{"version": {VERSION}, "token": "..."}}}}; got {what}; the connection is closed'
        )
        log.warning("connection %d: %s", self.cid, _clean(exc))
        return error_reply(rid, exc)

    def _answer(self, line: bytes) -> tuple[dict[str, Any], bool]:
        rid, command = None, "-"
        try:
            try:
                req = decode_request(line)
            except ProtocolError:
                if not self.greeted:  # an HTTP request, any text: never run a thing
                    raise _Closing(
                        self._not_a_hello(None, "no protocol message"), "not a hello"
                    ) from None
                raise
            rid, command = req.id, req.command
            if req.command == "hello":
                return {"id": rid, "result": self._hello(rid, req.args)}, False
            if not self.greeted:
                raise _Closing(self._not_a_hello(rid, f"command {req.command!r}"), "not a hello")
            if req.command == "bye":
                return {"id": rid, "result": None}, True
            if req.command == "commands":
                return {"id": rid, "result": describe_commands()}, False
            cmd = command_class(req.command).from_args(req.args)
            log.debug("connection %d: request %s: %s", self.cid, _clean(rid), cmd.wire)
            return {"id": rid, "result": self.session.execute(cmd)}, False
        except _Closing:
            raise
        except WorkcellError as exc:
            rid = getattr(exc, "request_id", rid)
            self._log_error(rid, command, exc)
            return error_reply(rid, exc), False
        except Exception as exc:  # our bug: report it, keep serving
            log.exception(
                "connection %d: request %s (%s): internal error",
                self.cid,
                _clean(rid),
                _clean(command),
            )
            return error_reply(rid, exc), False

    def _log_error(self, rid: Any, command: str, exc: BaseException) -> None:
        log.info(
            "connection %d: request %s (%s): %s: %s",
            self.cid, _clean(rid), _clean(command, 60), error_type(exc), _clean(exc),
        )  # fmt: skip

    def _hello(self, rid: Any, args: Any) -> dict[str, Any]:
        srv = self.server
        if not isinstance(args, dict):
            raise ProtocolError('hello takes an object: {"version": 1, "token": "..."}')
        version = args.get("version", VERSION)
        if version != VERSION:
            raise ProtocolError(
                f"protocol version {version!r} unknown; this server speaks {VERSION}"
            )
        if srv.token is not None and not self.greeted:  # a later hello: version only
            token = args.get("token")
            given = token.encode("utf-8", "surrogatepass") if isinstance(token, str) else b""
            if not hmac.compare_digest(given, srv.token.encode()):
                slept = srv.throttle.failed(self.addr)
                log.warning(
                    "connection %d: wrong or missing token (answered after %.1f s)", self.cid, slept
                )
                raise _Closing(
                    error_reply(
                        rid, ProtocolError("wrong or missing token; the connection is closed")
                    ),
                    "wrong or missing token",
                )
            srv.throttle.succeeded(self.addr)
        if not self.greeted:
            self.session = srv.new_session()
            self.greeted = True
        return srv.hello()


class Server(socketserver.ThreadingTCPServer):
    """The protocol server on ``(host, port)`` (port 0: any free port; see :attr:`port`).

    ``token``: the token clients must send in their hello (default: a new random one);
    ``require_token=False`` serves without one (loopback only). The token is written to a
    user-only token file that local clients read (:mod:`workcell.program.tokens`;
    ``token_path``), removed by :meth:`server_close`. ``root``: the folder file names of
    commands resolve in (default: the current folder). ``session_factory`` makes each
    connection's session (default: an empty Session); ``shared``: one session for all,
    commands serialised. ``max_connections``, ``idle_timeout``, ``hello_timeout`` (s) and
    ``bad_token_delay`` (s): see the module doc.
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
        if not (isinstance(max_connections, int) and max_connections >= 1):
            raise ProgramError(f"max_connections must be an integer >= 1, got {max_connections!r}")
        if ":" in host:
            self.address_family = socket.AF_INET6
        self.token = token if token is not None or not require_token else new_token()
        self.session_factory = session_factory
        self.shared_session = self._rooted(session_factory()) if shared else None
        self.max_connections = max_connections
        self.idle_timeout = float(idle_timeout)
        self.hello_timeout = float(hello_timeout)
        self.throttle = _Throttle(bad_token_delay)
        self.connections = 0  # accepted so far
        self.active = 0  # served now
        self._count_lock = threading.Lock()
        self.token_path: Path | None = None
        try:
            super().__init__((host, port), _Handler)
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

    def process_request(self, request: Any, client_address: Any) -> None:
        with self._count_lock:
            busy = self.active >= self.max_connections
            if not busy:
                self.active += 1
        if busy:  # refuse politely, here (no thread), never blocking the accept loop long
            log.warning("refused %s:%s: %d connections open", *client_address[:2], self.active)
            exc = ProtocolError(
                f"server busy: {self.max_connections} connections are open (the limit); "
                "try again later"
            )
            with contextlib.suppress(OSError):
                request.settimeout(1.0)
                request.sendall(encode(error_reply(None, exc)))
            self.shutdown_request(request)
            return
        try:
            super().process_request(request, client_address)
        except BaseException:
            self._release()
            raise

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        try:
            super().process_request_thread(request, client_address)
        finally:
            self._release()

    def _release(self) -> None:
        with self._count_lock:
            self.active -= 1

    def handle_error(self, request: Any, client_address: Any) -> None:
        """A connection's failure: one log line (a traceback only for a bug), never stderr."""
        import sys

        exc = sys.exc_info()[1]
        if isinstance(exc, OSError):
            log.info("connection from %s:%s lost: %s", *client_address[:2], _clean(exc))
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
