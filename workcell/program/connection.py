"""One connection of ``workcell serve``: the hello first, then requests in order.

:class:`Connection` is the server's request handler (one thread per connection; see
:mod:`workcell.program.server` for the server and the rules it enforces). It sends the
server's hello, requires the client's hello (with the token) as the first message and
closes the connection at once on anything else, answers each request with its result or
error, bounds replies like requests, closes idle connections and those that never
finish their hello, and writes one log line per connection and per error (logger
``workcell.server``; client text escaped).
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
from typing import TYPE_CHECKING, Any

from workcell.errors import ProtocolError, WorkcellError
from workcell.program.args import label
from workcell.program.base import COMMANDS, command_class
from workcell.program.protocol import (
    MAX_MESSAGE_BYTES,
    VERSION,
    ReplyTooLargeError,
    decode_request,
    encode,
    encode_bounded,
    error_reply,
    error_type,
    to_jsonable,
)

if TYPE_CHECKING:
    from workcell.program.server import Server

__all__ = ["Connection", "clean_log_text", "describe_commands"]

log = logging.getLogger("workcell.server")


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


def clean_log_text(text: object, limit: int = 300) -> str:
    """One log-safe line: control characters escaped, at most ``limit`` characters."""
    s = str(text)
    s = "".join(c if c.isprintable() else repr(c)[1:-1] for c in s[: limit + 1])
    return s if len(s) <= limit else s[: limit - 3] + "..."


def _closing(exc: WorkcellError) -> ProtocolError:
    """``exc`` as the ProtocolError that closes a connection before its hello."""
    return ProtocolError(f"{exc}; the connection is closed")


class _Closing(Exception):  # noqa: N818 - control flow, not an error
    """Reply (if any) then close the connection; ``why`` goes to the log."""

    def __init__(self, reply: dict[str, Any] | None, why: str) -> None:
        super().__init__(why)
        self.reply, self.why = reply, why


class Connection(socketserver.StreamRequestHandler):
    """The handler of one connection (see the module doc)."""

    server: Server

    def setup(self) -> None:
        super().setup()
        self.connection.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.connection.settimeout(self.server.idle_timeout)
        self.evicted = self.server.eviction(self.request)  # set: make room, close

    def handle(self) -> None:
        srv = self.server
        self.cid = srv.next_connection_id()
        self.addr = str(self.client_address[0])
        self.requests, self.session, self.greeted, self.expired = 0, None, False, False
        t0 = time.monotonic()
        log.info("connection %d from %s:%s opened", self.cid, self.addr, self.client_address[1])
        self.timer = timer = threading.Timer(srv.hello_timeout, self._hello_expired)
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
            self._linger()
        except OSError as exc:  # reset, broken pipe, timeout while sending
            why = f"connection lost ({exc.__class__.__name__})"
        finally:
            timer.cancel()
            log.info(
                "connection %d closed: %s (%d requests, %.1f s)",
                self.cid, clean_log_text(why), self.requests, time.monotonic() - t0,
            )  # fmt: skip

    def _linger(self) -> None:
        """Close gently: no more sending, then drop what the client still sends (up to
        1 s, 2 MiB), so it reads the last reply instead of a connection reset."""
        deadline, dropped = time.monotonic() + 1.0, 0
        with contextlib.suppress(OSError):
            self.connection.shutdown(socket.SHUT_WR)
            while dropped < 2 << 20 and (left := deadline - time.monotonic()) > 0:
                self.connection.settimeout(left)
                data = self.connection.recv(65536)
                if not data:
                    break
                dropped += len(data)

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
            if not line or self.expired or self.evicted.is_set():
                if self.evicted.is_set() and not self.greeted:
                    raise _Closing(
                        error_reply(None, ProtocolError(
                            "closed before its hello to make room for a new connection"
                        )),
                        "closed before its hello: room made for a new connection",
                    )  # fmt: skip
                if self.expired:
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
            data = encode_bounded(message, MAX_MESSAGE_BYTES)  # stops at the bound
        except ReplyTooLargeError as exc:
            self._log_error(rid, "-", exc)
            data = encode(error_reply(rid, exc))
        except (ProtocolError, ValueError, TypeError) as exc:
            data = encode(error_reply(rid, ProtocolError(f"result not sendable: {exc}")))
        self.wfile.write(data)
        self.wfile.flush()

    def _not_a_hello(self, rid: Any, what: str) -> dict[str, Any]:
        exc = ProtocolError(
            f'the first message must be a hello: {{"id": 0, "command": "hello", "args": '
            f'{{"version": {VERSION}, "token": "..."}}}}; got {what}; the connection is closed'
        )
        log.warning("connection %d: %s", self.cid, clean_log_text(exc))
        return error_reply(rid, exc)

    def _first(self, line: bytes) -> dict[str, Any]:
        """The reply to the first line, which must be a good hello; anything else (a line
        that is not a request, another command, a hello refused for any reason) closes
        the connection with one reply and one short log line, running nothing."""
        try:
            req = decode_request(line)
        except ProtocolError as exc:  # an HTTP request, any text: never run a thing
            raise _Closing(
                self._not_a_hello(None, f"no protocol message ({exc})"), "not a hello"
            ) from None
        if req.command != "hello":
            what = f"command {clean_log_text(repr(req.command), 60)}"
            raise _Closing(self._not_a_hello(req.id, what), "not a hello")
        try:
            return {"id": req.id, "result": self._hello(req.id, req.args)}
        except _Closing:
            raise
        except WorkcellError as exc:
            log.warning("connection %d: hello refused: %s", self.cid, clean_log_text(exc))
            raise _Closing(error_reply(req.id, _closing(exc)), "hello refused") from None
        except Exception as exc:  # our bug: one line, no traceback for an unauthenticated client
            log.warning("connection %d: hello failed: %s", self.cid, type(exc).__name__)
            exc = ProtocolError("the hello could not be answered; the connection is closed")
            raise _Closing(error_reply(req.id, exc), "hello failed") from None

    def _answer(self, line: bytes) -> tuple[dict[str, Any], bool]:
        if not self.greeted:
            return self._first(line), False
        rid, command = None, "-"
        try:
            req = decode_request(line)
            rid, command = req.id, req.command
            if req.command == "hello":
                return {"id": rid, "result": self._hello(rid, req.args)}, False
            if req.command == "bye":
                return {"id": rid, "result": None}, True
            if req.command == "commands":
                return {"id": rid, "result": describe_commands()}, False
            cmd = command_class(req.command).from_args(req.args)
            if log.isEnabledFor(logging.DEBUG):
                log.debug("connection %d: request %s: %s", self.cid, clean_log_text(rid), cmd.wire)
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
                clean_log_text(rid),
                clean_log_text(command),
            )
            return error_reply(rid, exc), False

    def _log_error(self, rid: Any, command: str, exc: BaseException) -> None:
        log.info(
            "connection %d: request %s (%s): %s: %s",
            self.cid, clean_log_text(rid), clean_log_text(command, 60), error_type(exc), clean_log_text(exc),
        )  # fmt: skip

    def _hello(self, rid: Any, args: Any) -> dict[str, Any]:
        srv = self.server
        if not isinstance(args, dict):
            raise ProtocolError('hello takes an object: {"version": 1, "token": "..."}')
        version = args.get("version", VERSION)
        if version != VERSION:
            raise ProtocolError(
                f"protocol version {clean_log_text(repr(version), 40)} unknown; this server "
                f"speaks {VERSION}"
            )
        if srv.token is not None and not self.greeted:  # a later hello: version only
            token = args.get("token")
            given = token.encode("utf-8", "surrogatepass") if isinstance(token, str) else b""
            if not hmac.compare_digest(given, srv.token.encode()):
                slept = srv.throttle.failed(self.addr, self.evicted)
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
        self.timer.cancel()  # the hello came: making the session may take its time
        if not self.greeted:
            if not srv.admit(self.request):
                raise _Closing(error_reply(rid, srv.busy_error()), "server busy")
            self.session = srv.new_session()
            self.greeted = True
        return srv.hello()
