"""The live view's page and websocket need the token, and a websocket must come from the
page itself (its Origin): checked with a raw websocket client and plain HTTP requests."""

from __future__ import annotations

import urllib.error
import urllib.request

import pytest
import viser
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from workcell import Workcell
from workcell.errors import ViewError
from workcell.sim import Simulator
from workcell.view import Viewer
from workcell.view.guard import Guard, start_server, stop_quietly

PROTOCOL = f"viser-v{viser.__version__}"


@pytest.fixture(scope="module")
def viewer():
    cell = Workcell("empty")
    with Viewer(Simulator(cell), speed=None) as v:
        yield v


def _ws(url: str, origin: str | None):
    headers = {"Origin": origin} if origin is not None else {}
    return connect(url, subprotocols=[PROTOCOL], additional_headers=headers, origin=None,
                   open_timeout=10)  # fmt: skip


def _status(url: str) -> int:
    try:
        with urllib.request.urlopen(url, timeout=10) as r:
            return r.status
    except urllib.error.HTTPError as exc:
        return exc.code


def test_url_is_loopback_with_a_random_token(viewer):
    assert viewer.url.startswith("http://127.0.0.1:")
    token = viewer.url.rsplit("/", 1)[1]
    assert len(token) >= 22  # 128 bits, URL-safe base64
    other = Viewer(None, speed=None)
    try:
        assert other.url.rsplit("/", 1)[1] != token
    finally:
        other.close()


def test_page_needs_the_token(viewer):
    base = viewer.url.rsplit("/", 1)[0]
    assert _status(viewer.url) == 200
    assert _status(base + "/") == 403
    assert _status(base + "/index.html") == 403
    assert _status(base + "/" + viewer.guard.token + "x") == 403


@pytest.mark.parametrize(
    ("path", "origin"),
    [
        ("", "self"),  # no token
        ("/not-the-token", "self"),
        ("/TOKEN", None),  # a client that sends no Origin
        ("/TOKEN", "http://evil.example"),  # a page of another site
        ("/TOKEN", "http://127.0.0.1:1"),  # another local port
    ],
)
def test_websocket_refused(viewer, path, origin):
    host = viewer.url.split("/")[2]
    own = f"http://{host}"
    url = f"ws://{host}" + path.replace("TOKEN", viewer.guard.token)
    refused = viewer.guard.refused
    with pytest.raises(InvalidStatus, match="403"):
        _ws(url, own if origin == "self" else origin)
    assert viewer.guard.refused == refused + 1


def test_websocket_of_the_page_accepted(viewer):
    host = viewer.url.split("/")[2]
    with _ws(f"ws://{host}/{viewer.guard.token}", f"http://{host}") as ws:
        assert len(ws.recv(timeout=10)) > 0  # viser's first messages


def test_a_port_in_use_is_an_error_not_another_port(viewer):
    port = int(viewer.url.split("/")[2].rsplit(":", 1)[1])
    with pytest.raises(ViewError, match=f"port {port} is in use"):
        Viewer(None, port=port)


def test_guard_host_check():
    g = Guard("t", loopback=True)
    server = start_server("127.0.0.1", 0, g)
    try:
        port = server.get_port()
        req = urllib.request.Request(
            f"http://127.0.0.1:{port}/t", headers={"Host": f"evil.example:{port}"}
        )
        with pytest.raises(urllib.error.HTTPError, match="403"):
            urllib.request.urlopen(req, timeout=10)
    finally:
        stop_quietly(server)
