"""A viser server that only serves the holder of its token, from its own page.

viser 1.1 has no authentication and no Origin check: any page in the user's browser may
open a websocket to a server on localhost, and anyone who can reach the port gets the
page. :func:`start_server` starts a :class:`viser.ViserServer` whose HTTP and websocket
handshakes first pass :class:`Guard`:

- the page lives at ``/<token>`` (a random token, part of the URL the viewer prints);
  every other path answers 403 Forbidden. viser's page opens its websocket at its own
  path, so the websocket carries the token the same way;
- a websocket handshake must also come from the page itself: its ``Origin`` header must be
  ``http://`` + its ``Host`` header (a page of another site, or a client sending no
  Origin, is refused with 403); on a loopback server the Host must be a loopback name
  (no DNS rebinding).

viser builds its websockets server inside its constructor and offers no hook before it
listens; the guard is put in front of viser's own request handler by giving viser's
server module, for the length of the constructor call (under a lock), a view of the
``websockets`` package whose ``serve`` wraps ``process_request``. Nothing else in the
process is affected. viser also moves silently to the next port when one is taken:
asked for a port that is in use, :func:`start_server` stops and raises ``ViewError``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import http
import io
import logging
import secrets
import threading
from collections.abc import Callable
from typing import Any

import viser
import websockets
from viser.infra import _infra
from websockets.asyncio.server import ServerConnection
from websockets.http11 import Request

from workcell.errors import ViewError

__all__ = ["LOOPBACK", "Guard", "new_token", "start_server"]

LOOPBACK = ("127.0.0.1", "localhost", "::1", "[::1]")
_LOCK = threading.Lock()
_Handler = Callable[[ServerConnection, Request], Any]


def new_token() -> str:
    """A random URL-safe token (128 bits)."""
    return secrets.token_urlsafe(16)


@dataclasses.dataclass
class Guard:
    """The checks in front of viser's request handler (module doc). ``loopback``: the
    server listens on a loopback address only. ``refused`` counts refused handshakes."""

    token: str
    loopback: bool = True
    refused: int = 0

    def check(self, connection: ServerConnection, request: Request) -> str | None:
        """Why this request is refused, or None when it may pass."""
        path = request.path.partition("?")[0].rstrip("/")
        if not secrets.compare_digest(path.encode(), f"/{self.token}".encode()):
            return "this page needs the token of the URL the viewer printed"
        host = request.headers.get("Host", "")
        if self.loopback and _hostname(host) not in LOOPBACK:
            return f"unknown host {host!r}"
        if request.headers.get("Upgrade", "").lower() == "websocket":
            origin = request.headers.get("Origin")
            if origin != f"http://{host}":
                return f"websocket from another origin ({origin or 'none given'})"
        return None

    def wrap(self, inner: _Handler | None) -> _Handler:
        """viser's ``process_request`` behind the checks; the page's path becomes ``/``."""

        def process_request(connection: ServerConnection, request: Request) -> Any:
            why = self.check(connection, request)
            if why is not None:
                self.refused += 1
                return connection.respond(http.HTTPStatus.FORBIDDEN, f"workcell view: {why}\n")
            if inner is None:
                return None
            return inner(connection, dataclasses.replace(request, path="/"))

        return process_request


def _hostname(host: str) -> str:
    """The name part of a Host header (``[::1]:8080`` -> ``[::1]``)."""
    if host.startswith("["):
        return host.partition("]")[0] + "]"
    return host.rpartition(":")[0] if ":" in host else host


class _View:
    """An attribute view of a module with some attributes replaced."""

    def __init__(self, real: Any, **over: Any) -> None:
        self._real = real
        self.__dict__.update(over)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._real, name)


def start_server(host: str, port: int, guard: Guard) -> viser.ViserServer:
    """A started ViserServer on ``host``:``port`` (0: any free port) behind ``guard``;
    its console output is kept off the terminal. ViewError when ``port`` is taken."""
    real_serve = websockets.asyncio.server.serve

    def serve(*args: Any, **kwargs: Any) -> Any:
        kwargs["process_request"] = guard.wrap(kwargs.get("process_request"))
        return real_serve(*args, **kwargs)

    view = _View(
        websockets,
        asyncio=_View(websockets.asyncio, server=_View(websockets.asyncio.server, serve=serve)),
    )
    logging.getLogger("websockets.server").setLevel(logging.WARNING)  # no line per listen
    with _LOCK, contextlib.redirect_stdout(io.StringIO()):
        saved = _infra.websockets
        _infra.websockets = view
        try:
            server = viser.ViserServer(host=host, port=port, verbose=False)
        finally:
            _infra.websockets = saved
    if port and server.get_port() != port:
        stop_quietly(server)
        raise ViewError(
            f"port {port} is in use on {host}; give another with --port, or 0 for any free port"
        )
    return server


def stop_quietly(server: viser.ViserServer) -> None:
    """Stop a server without its console messages."""
    with contextlib.redirect_stdout(io.StringIO()):
        server.stop()
