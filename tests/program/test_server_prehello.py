"""Issue 19, item 5: what a client without a token can do before its hello.

The attacks of the issue, performed: a 1,100-deep JSON array and a 5,000-digit integer
as the first line (an InternalError with a traceback in the log, the connection kept
open), bad hellos repeated on one connection (29,000 replies in 2 s), and idle sockets
without a token holding every connection slot. Now each bad first line gets one reply
and one short log line and the connection is closed; connections waiting for their
hello have their own pool, and a token holder always gets in."""

from __future__ import annotations

import json
import logging
import socket
import threading
import time

import pytest

from workcell.client import Client
from workcell.errors import ProgramError
from workcell.program.server import Server


def serve(**options) -> Server:
    srv = Server(port=0, **options)
    srv.serve_in_thread()
    return srv


@pytest.fixture
def server(tmp_path):
    srv = serve(root=tmp_path, hello_timeout=60.0, bad_token_delay=0.02)
    yield srv
    srv.stop()


def connect(port: int):
    s = socket.create_connection(("127.0.0.1", port), timeout=20)
    r = s.makefile("rb")
    assert json.loads(r.readline())["protocol"] == "workcell"
    return s, r


def replies_until_closed(r, limit: int = 100) -> list[dict]:
    out = []
    while len(out) < limit and (line := r.readline()):
        out.append(json.loads(line))
    return out


DEEP = b"[" * 1100 + b"]" * 1100
BIG_INT = b"1" * 5000
BAD_FIRST_LINES = {
    "deep array": DEEP,
    "deep array in a hello": b'{"id": 0, "command": "hello", "args": {"token": ' + DEEP + b"}}",
    "5000-digit integer": BIG_INT,
    "5000-digit id": b'{"id": ' + BIG_INT + b', "command": "hello", "args": {}}',
    "hello of another version": b'{"id": 0, "command": "hello", "args": {"version": 2}}',
    "hello args not an object": b'{"id": 0, "command": "hello", "args": [1]}',
    "hello with a 400-digit version": b'{"id": 0, "command": "hello", "args": {"version": '
    + b"9" * 400
    + b"}}",
}


@pytest.mark.parametrize("what", sorted(BAD_FIRST_LINES))
def test_a_bad_first_line_gets_one_reply_one_short_log_line_and_a_closed_connection(
    server, caplog, what
):
    line = BAD_FIRST_LINES[what]
    with caplog.at_level(logging.INFO, logger="workcell.server"):
        s, r = connect(server.port)
        s.sendall((line + b"\n") * 50)  # the same line again and again: one reply only
        replies = replies_until_closed(r)
        s.close()
        time.sleep(0.2)  # the closing log line
    assert len(replies) == 1, replies
    assert replies[0]["error"]["type"] == "ProtocolError"
    assert "closed" in replies[0]["error"]["message"]
    assert "Traceback" not in caplog.text
    assert "InternalError" not in caplog.text
    lines = [rec for rec in caplog.records if "connection" in rec.getMessage()]
    assert len(lines) <= 3, caplog.text  # opened, why, closed
    assert all(len(rec.getMessage()) < 400 for rec in lines)


def test_the_same_lines_after_the_hello_are_typed_errors_and_the_connection_goes_on(server, caplog):
    with caplog.at_level(logging.INFO, logger="workcell.server"), Client(port=server.port) as c:
        for line in (DEEP, BIG_INT, b'{"id": 1, "command": "list", "args": [' + BIG_INT + b"]}"):
            c._sock.sendall(line + b"\n")
            reply = json.loads(c._r.readline())
            assert reply["error"]["type"] == "ProtocolError", reply
            assert "malformed JSON" in reply["error"]["message"]
        assert c.call("list", "block") == []
    assert "Traceback" not in caplog.text


def test_idle_sockets_without_a_token_never_keep_a_token_holder_out(server):
    """40 sockets connect and say nothing (the hello deadline is 60 s here): the first 16
    used to take every slot. Now each new one closes the oldest waiting one, and a
    client with the token gets in at once."""
    idle = [connect(server.port) for _ in range(40)]
    assert server.waiting <= server.max_waiting
    t0 = time.monotonic()
    with Client(port=server.port, timeout=20) as c:
        assert c.call("list", "block") == []
    assert time.monotonic() - t0 < 10  # long before any idle socket's deadline
    closed = 0
    for s, r in idle:
        s.settimeout(0.5)
        try:
            reply = json.loads(r.readline() or b"null")
        except (TimeoutError, OSError):
            reply = None
        if reply is not None:
            assert "make room for a new connection" in reply["error"]["message"]
            closed += 1
        s.close()
    assert closed >= 40 - server.max_waiting


def test_wrong_tokens_waiting_on_the_throttle_are_closed_to_make_room(tmp_path):
    """Wrong tokens are answered ever later (a thread waits for each); a flood of them
    cannot pile up waiting threads: a new connection closes the oldest waiting one, and
    its thread ends at once."""
    srv = serve(root=tmp_path, hello_timeout=60.0, bad_token_delay=2.0, max_waiting=4)
    try:
        before = threading.active_count()
        socks = []
        for _ in range(30):
            s, r = connect(srv.port)
            s.sendall(b'{"id": 0, "command": "hello", "args": {"token": "wrong-token-1"}}\n')
            socks.append((s, r))
        time.sleep(0.5)
        assert threading.active_count() - before <= srv.max_waiting + 8
        with Client(port=srv.port, timeout=20) as c:  # the right token: in at once
            assert c.call("list", "block") == []
        for s, _ in socks:
            s.close()
    finally:
        srv.stop()


def test_served_connections_keep_their_own_cap(tmp_path):
    srv = serve(root=tmp_path, max_connections=2, max_waiting=2)
    try:
        held = [Client(port=srv.port, timeout=10) for _ in range(2)]
        with pytest.raises(Exception, match="server busy"):
            Client(port=srv.port, timeout=10)
        for c in held:
            c.close()
    finally:
        srv.stop()


def test_server_options_are_checked():
    with pytest.raises(ProgramError, match="max_waiting must be an integer >= 1"):
        Server(port=0, max_waiting=0)
