"""``workcell serve``: the remote program interface (thesis §4.6.2) over TCP.

A threaded server speaking :mod:`workcell.program.protocol`: on connection it sends a
hello line; then it reads requests one line at a time and answers each (in order) with
the result or the error of the command (:data:`workcell.program.base.COMMANDS`), plus
the protocol's own commands ``hello`` (version and token), ``commands`` (what there is)
and ``bye``. Whatever a client sends (bad JSON, unknown commands, wrong arguments,
oversized lines, a dropped connection), the server answers or closes that connection
and goes on serving the others.

Sessions: by default each connection gets its own :class:`Session` (its own model, cell
and simulator, made by ``session_factory``), so clients cannot disturb each other;
with ``shared=True`` all connections use one session and their commands are serialised
(one at a time, each whole). Binding to anything but a loopback address requires a
token, which clients must send in ``hello`` before any other command.
"""

from __future__ import annotations

import hmac
import ipaddress
import socket
import socketserver
import sys
import threading
import traceback
from collections.abc import Callable
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
)
from workcell.program.session import Session

__all__ = ["Server", "describe_commands", "is_loopback"]


def is_loopback(host: str) -> bool:
    """True when every address ``host`` resolves to is a loopback address."""
    try:
        infos = socket.getaddrinfo(host, None)
    except OSError:
        return False
    addrs = {info[4][0] for info in infos}
    return bool(addrs) and all(ipaddress.ip_address(a.split("%")[0]).is_loopback for a in addrs)


def describe_commands() -> list[dict[str, Any]]:
    """Every command with its arguments (name, required, default, type, unit), for
    the protocol's ``commands``."""
    import dataclasses

    from workcell.program.protocol import to_jsonable

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


class _Handler(socketserver.StreamRequestHandler):
    server: Server

    def setup(self) -> None:
        super().setup()
        self.connection.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def handle(self) -> None:
        srv = self.server
        self.authenticated = srv.token is None
        try:
            self.session = srv.shared_session or srv.session_factory()
        except Exception as exc:  # a broken session factory: tell the client, keep serving
            self._send(error_reply(None, exc))
            return
        self._send(srv.hello())
        while True:
            line = self.rfile.readline(MAX_MESSAGE_BYTES + 1)
            if not line:
                return  # the client went away
            if len(line) > MAX_MESSAGE_BYTES or (
                len(line) == MAX_MESSAGE_BYTES + 1 and not line.endswith(b"\n")
            ):
                self._discard_rest(line)
                self._send(
                    error_reply(
                        None,
                        ProtocolError(
                            f"message longer than {MAX_MESSAGE_BYTES} bytes refused "
                            "(the limit includes the newline)"
                        ),
                    )
                )
                continue
            if not line.strip():
                continue
            reply, close = self._answer(line)
            if not self._send(reply) or close:
                return

    def _discard_rest(self, line: bytes) -> None:
        while line and not line.endswith(b"\n"):
            line = self.rfile.readline(65536)

    def _send(self, message: dict[str, Any]) -> bool:
        try:
            data = encode(message)
        except (ProtocolError, ValueError, TypeError) as exc:
            data = encode(
                error_reply(message.get("id"), ProtocolError(f"result not sendable: {exc}"))
            )
        try:
            self.wfile.write(data)
            self.wfile.flush()
        except OSError:
            return False
        return True

    def _answer(self, line: bytes) -> tuple[dict[str, Any], bool]:
        rid = None
        try:
            req = decode_request(line)
            rid = req.id
            if req.command == "hello":
                return {"id": rid, "result": self._hello(req.args)}, False
            if not self.authenticated:
                raise ProtocolError(
                    'this server needs a token: send {"command": "hello", "args": {"token": ...}} first'
                )
            if req.command == "bye":
                return {"id": rid, "result": None}, True
            if req.command == "commands":
                return {"id": rid, "result": describe_commands()}, False
            command = command_class(req.command).from_args(req.args)
            return {"id": rid, "result": self.session.execute(command)}, False
        except WorkcellError as exc:
            rid = getattr(exc, "request_id", rid)
            close = isinstance(exc, _TokenRefusedError)
            return error_reply(rid, exc), close
        except Exception as exc:  # our bug: report it, keep serving
            traceback.print_exc(file=sys.stderr)
            return error_reply(rid, exc), False

    def _hello(self, args: Any) -> dict[str, Any]:
        srv = self.server
        if not isinstance(args, dict):
            raise ProtocolError('hello takes an object: {"version": 1, "token": "..."}')
        version = args.get("version", VERSION)
        if version != VERSION:
            raise ProtocolError(
                f"protocol version {version!r} unknown; this server speaks {VERSION}"
            )
        if srv.token is not None:
            token = args.get("token")
            if not isinstance(token, str) or not hmac.compare_digest(
                token.encode(), srv.token.encode()
            ):
                raise _TokenRefusedError("wrong or missing token; the connection is closed")
            self.authenticated = True
        return srv.hello()


class _TokenRefusedError(ProtocolError):
    """A wrong token: the reply is sent, then the connection is closed."""


class Server(socketserver.ThreadingTCPServer):
    """The protocol server on ``(host, port)`` (port 0: any free port; see :attr:`port`).

    ``session_factory`` makes each connection's session (default: an empty Session);
    ``shared``: one session for all, commands serialised; ``token``: required from
    clients, and required when ``host`` is not a loopback address.
    """

    daemon_threads = True
    block_on_close = False
    allow_reuse_address = True

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 0,
        *,
        token: str | None = None,
        shared: bool = False,
        session_factory: Callable[[], Session] = Session,
    ) -> None:
        if token is not None and (not isinstance(token, str) or len(token) < 8):
            raise ProgramError("a token must be a string of at least 8 characters")
        if token is None and not is_loopback(host):
            raise ProgramError(
                f"refusing to serve on '{host}' without a token: anything but a loopback "
                "address (127.0.0.1, ::1, localhost) needs --token (or WORKCELL_TOKEN)"
            )
        if ":" in host:
            self.address_family = socket.AF_INET6
        self.token = token
        self.session_factory = session_factory
        self.shared_session = session_factory() if shared else None
        self.connections = 0
        self._count_lock = threading.Lock()
        try:
            super().__init__((host, port), _Handler)
        except OSError as exc:
            raise ProgramError(f"cannot listen on {host}:{port}: {exc.strerror or exc}") from exc

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
        }

    def process_request(self, request: Any, client_address: Any) -> None:
        with self._count_lock:
            self.connections += 1
        super().process_request(request, client_address)

    def serve_in_thread(self) -> threading.Thread:
        """Start serving in a daemon thread (tests, benchmarks); stop with :meth:`stop`."""
        t = threading.Thread(target=self.serve_forever, name="workcell-server", daemon=True)
        t.start()
        return t

    def stop(self) -> None:
        """Stop serving and close the listening socket."""
        self.shutdown()
        self.server_close()
