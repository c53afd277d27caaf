"""A client's link to a workcell server (protocol v1): :class:`ServerLink` connects,
checks the server's hello, says its own (with the token) and sends one request at a time,
turning an error reply into the WorkcellError subclass the server names.
:class:`~workcell.client.Client` is the Simulator-like API on top of it.
"""

from __future__ import annotations

import json
import os
import socket
from typing import Any, Self

from workcell.errors import ProtocolError
from workcell.program.protocol import (
    DEFAULT_PORT,
    MAX_MESSAGE_BYTES,
    PROTOCOL,
    VERSION,
    encode,
    error_class,
)

__all__ = ["ServerLink"]


class ServerLink:
    """A connection to a workcell server (module doc); ``token`` and ``timeout`` as for
    :class:`~workcell.client.Client`."""

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = DEFAULT_PORT,
        *,
        token: str | None = None,
        timeout: float | None = None,
    ) -> None:
        try:
            self._sock = socket.create_connection((host, port), timeout=timeout)
        except OSError as exc:
            raise ProtocolError(f"cannot connect to {host}:{port}: {exc.strerror or exc}") from exc
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._r = self._sock.makefile("rb")
        self._next_id = 0
        self.server_hello = self._read()
        err = self.server_hello.get("error")
        if isinstance(err, dict):  # refused at once (busy): say why
            self.close()
            raise error_class(err.get("type"))(str(err.get("message")))
        if self.server_hello.get("protocol") != PROTOCOL:
            self.close()
            raise ProtocolError(f"{host}:{port} does not speak the workcell protocol")
        if self.server_hello.get("version") != VERSION:
            self.close()
            raise ProtocolError(
                f"server speaks protocol version {self.server_hello.get('version')}, "
                f"this client {VERSION}"
            )
        if token is None and self.server_hello.get("token_required"):
            token = _local_token(host, port)
            if token is None:
                self.close()
                raise ProtocolError(
                    f"the server at {host}:{port} needs a token: pass token=..., set "
                    "WORKCELL_TOKEN, or run on the server's machine as its user (token file)"
                )
        self._request("hello", {"version": VERSION, "token": token})  # before any command

    def _read(self) -> dict[str, Any]:
        line = self._r.readline(MAX_MESSAGE_BYTES + 1)
        if not line:
            raise ProtocolError("the server closed the connection")
        if len(line) > MAX_MESSAGE_BYTES:
            self.close()
            raise ProtocolError(f"the server sent a message over {MAX_MESSAGE_BYTES} bytes")
        try:
            msg = json.loads(line)
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise ProtocolError(f"the server sent malformed JSON: {exc}") from exc
        if not isinstance(msg, dict):
            raise ProtocolError("the server sent something other than a JSON object")
        return msg

    def _request(self, command: str, args: list[Any] | dict[str, Any]) -> Any:
        """Send ``command`` with its ``args`` (in order or by name) and return its result;
        the WorkcellError subclass the server names on an error reply."""
        self._next_id += 1
        rid = self._next_id
        data = encode({"id": rid, "command": command, "args": args})
        if len(data) > MAX_MESSAGE_BYTES:
            raise ProtocolError(
                f"request of {len(data)} bytes is over the {MAX_MESSAGE_BYTES} limit"
            )
        try:
            self._sock.sendall(data)
        except OSError as exc:
            raise ProtocolError(f"connection lost: {exc}") from exc
        reply = self._read()
        if "error" in reply:
            err = reply["error"] if isinstance(reply["error"], dict) else {}
            raise error_class(err.get("type"))(str(err.get("message", "error without a message")))
        if reply.get("id") != rid:
            raise ProtocolError(f"reply to request {reply.get('id')!r}, expected {rid}")
        return reply.get("result")

    def close(self) -> None:
        """Close the connection (idempotent)."""
        try:
            self._r.close()
            self._sock.close()
        except OSError:
            pass

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _local_token(host: str, port: int) -> str | None:
    """WORKCELL_TOKEN, else the token file of a server on this machine (never sent to
    another machine's server)."""
    from workcell.program.tokens import is_loopback, read_token_file

    env = os.environ.get("WORKCELL_TOKEN")
    if env:
        return env
    return read_token_file(port) if is_loopback(host) else None
