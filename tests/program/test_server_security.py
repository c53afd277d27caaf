"""Issue 14, items 1, 3, 4: the server under attack (cross-protocol requests, tokens,
connection floods, idle and half-open connections, huge replies, abrupt disconnects),
and its log. Each test performs the attack and checks what the protocol promises."""

from __future__ import annotations

import json
import logging
import os
import signal
import socket
import stat
import struct
import subprocess
import sys
import threading
import time

import pytest

from workcell.client import Client
from workcell.errors import ProgramError, ProtocolError
from workcell.program import Session
from workcell.program.protocol import MAX_MESSAGE_BYTES
from workcell.program.server import Server
from workcell.program.tokens import read_token_file, token_file


def serve(**options):
    srv = Server(port=0, **options)
    srv.serve_in_thread()
    return srv


@pytest.fixture
def server(tmp_path):
    srv = serve(root=tmp_path, hello_timeout=2.0, bad_token_delay=0.02)
    yield srv
    srv.stop()


def connect(port: int, timeout: float = 10) -> tuple[socket.socket, object]:
    s = socket.create_connection(("127.0.0.1", port), timeout=timeout)
    r = s.makefile("rb")
    hello = json.loads(r.readline())
    assert hello["protocol"] == "workcell"
    return s, r


def lines_until_closed(r) -> list[dict]:
    out = []
    while line := r.readline():
        out.append(json.loads(line))
    return out


def say_hello(s, r, token) -> dict:
    s.sendall(json.dumps({"id": 0, "command": "hello", "args": {"token": token}}).encode() + b"\n")
    return json.loads(r.readline())


class Counting(Session):
    made = 0

    def __init__(self) -> None:
        super().__init__()
        type(self).made += 1


# ------------------------------------------------------------------ 1. cross-protocol
@pytest.mark.parametrize("require_token", [True, False])
def test_an_http_post_carrying_commands_runs_nothing_and_is_closed(tmp_path, require_token):
    """A web page can POST to 127.0.0.1: the request line is no hello, so the body's JSON
    lines (a save here) never run, even on a tokenless server."""
    Counting.made = 0
    srv = serve(root=tmp_path, require_token=require_token, session_factory=Counting)
    try:
        body = json.dumps({"id": 1, "command": "save", "args": {"path": "pwned.json"}}) + "\n"
        request = (
            "POST / HTTP/1.1\r\nHost: 127.0.0.1:5260\r\nContent-Type: text/plain\r\n"
            f"Content-Length: {len(body)}\r\n\r\n{body}"
        )
        s, r = connect(srv.port)
        s.sendall(request.encode())
        replies = lines_until_closed(r)  # the server closes: this returns
        assert len(replies) == 1
        assert replies[0]["error"]["type"] == "ProtocolError"
        assert "the first message must be a hello" in replies[0]["error"]["message"]
        assert list(tmp_path.iterdir()) == []  # nothing was saved
        assert Counting.made == 0  # no session was even made
    finally:
        srv.stop()


@pytest.mark.parametrize(
    "first",
    [
        b"GET / HTTP/1.1\r\n",
        b"\xff\xfe garbage\n",
        b'{"id": 1, "command": "list"}\n',  # a command before the hello
        b'{"id": 1, "command": "bye"}\n',
        b"[1, 2, 3]\n",
        b"x" * (MAX_MESSAGE_BYTES + 10) + b"\n",
    ],
)
def test_a_first_line_that_is_not_a_hello_closes_the_connection(server, first):
    s, r = connect(server.port)
    s.sendall(first + b'{"id": 2, "command": "create_cube", "args": ["c", 1]}\n')
    replies = lines_until_closed(r)
    assert len(replies) == 1, replies  # the create_cube after it is never answered
    assert "first message must be a hello" in replies[0]["error"]["message"]
    s.close()


def test_the_token_file_is_user_only_and_clients_find_it(server):
    path = token_file(server.port)
    assert server.token_path == path
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert stat.S_IMODE(path.parent.stat().st_mode) == 0o700
    token = read_token_file(server.port)
    assert token == server.token
    assert len(token) >= 40
    with Client(port=server.port) as c:  # reads the file: no token given
        assert c.call("list", "block") == []
    other = serve(root=server.root)
    try:
        assert other.token != server.token  # a new one per server
    finally:
        other.stop()
    assert not token_file(other.port).exists()  # removed on stop


# ------------------------------------------------------------------ 3. tokens
@pytest.mark.parametrize(
    "hello",
    [
        b'{"id": 1, "command": "hello", "args": {"token": "\\ud800"}}\n',  # a lone surrogate
        b'{"id": 1, "command": "hello", "args": {"token": "wrong-token-123"}}\n',
        b'{"id": 1, "command": "hello", "args": {"token": 12345678}}\n',
        b'{"id": 1, "command": "hello", "args": {}}\n',
    ],
)
def test_a_bad_token_hello_gets_an_error_and_the_connection_is_closed(server, hello):
    s, r = connect(server.port)
    s.sendall(hello)
    replies = lines_until_closed(r)
    assert replies == [
        {
            "id": 1,
            "error": {
                "type": "ProtocolError",
                "message": "wrong or missing token; the connection is closed",
            },
        }
    ]


def test_repeated_bad_tokens_are_answered_ever_more_slowly(tmp_path):
    srv = serve(root=tmp_path, bad_token_delay=0.01)
    try:
        waits = []
        for _ in range(4):
            s, r = connect(srv.port)
            t0 = time.monotonic()
            assert "wrong" in say_hello(s, r, "guess-0000")["error"]["message"]
            waits.append(time.monotonic() - t0)
            s.close()
        # 0.01, 0.02, 0.04, 0.08 s: each at least its share
        for w, expected in zip(waits, (0.01, 0.02, 0.04, 0.08), strict=True):
            assert w >= expected * 0.9, waits
        # parallel guesses queue behind each other (they cannot be spread over connections)
        t0 = time.monotonic()
        threads = [
            threading.Thread(target=lambda: say_hello(*connect(srv.port), "guess-1111"))
            for _ in range(3)
        ]
        for t in threads:
            t.start()
        for t in threads:
            t.join(30)
        assert time.monotonic() - t0 >= 0.16 + 0.32 + 0.64 - 0.05  # queued one after another
        # the right token is answered at once and resets the count
        s, r = connect(srv.port)
        t0 = time.monotonic()
        assert say_hello(s, r, srv.token)["result"]["protocol"] == "workcell"
        assert time.monotonic() - t0 < 0.5
    finally:
        srv.stop()


# ------------------------------------------------------------------ 3. connections
def test_a_burst_of_connections_is_queued_by_the_backlog():
    """50 clients connecting while the server is busy all complete their TCP handshake
    (the backlog was 5: most timed out)."""
    srv = Server(port=0, max_connections=64)  # listening, not yet accepting
    try:
        assert srv.request_queue_size >= 128
        socks, failed = [], []

        def knock() -> None:
            try:
                socks.append(socket.create_connection(("127.0.0.1", srv.port), timeout=1.0))
            except OSError as exc:
                failed.append(exc)

        threads = [threading.Thread(target=knock) for _ in range(50)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(10)
        assert not failed
        assert len(socks) == 50
        srv.serve_in_thread()
        for s in socks:  # each is then served
            s.settimeout(10)
            assert b'"protocol":"workcell"' in s.makefile("rb").readline()
            s.close()
    finally:
        srv.stop()


def test_connections_over_the_cap_are_refused_politely(tmp_path):
    srv = serve(root=tmp_path, max_connections=3)
    try:
        held = [Client(port=srv.port, timeout=10) for _ in range(3)]
        s = socket.create_connection(("127.0.0.1", srv.port), timeout=10)
        replies = lines_until_closed(s.makefile("rb"))
        assert replies[0]["error"]["type"] == "ProtocolError"
        assert "server busy: 3 connections are open (the limit)" in replies[0]["error"]["message"]
        assert len(replies) == 1
        with pytest.raises(ProtocolError, match="server busy"):
            Client(port=srv.port, timeout=10)
        held.pop().close()
        deadline = time.monotonic() + 10
        while srv.active >= 3 and time.monotonic() < deadline:
            time.sleep(0.01)
        with Client(port=srv.port, timeout=10) as c:  # a slot is free again
            assert c.call("list", "scene") == []
        for c in held:
            c.close()
    finally:
        srv.stop()


def test_idle_connections_are_closed_after_the_timeout(tmp_path):
    srv = serve(root=tmp_path, idle_timeout=0.5, hello_timeout=0.3)
    try:
        s, r = connect(srv.port)
        assert "result" in say_hello(s, r, srv.token)
        t0 = time.monotonic()
        replies = lines_until_closed(r)
        assert 0.4 < time.monotonic() - t0 < 5
        assert replies == [
            {
                "id": None,
                "error": {
                    "type": "ProtocolError",
                    "message": "closed after 0.5 s without a request",
                },
            }
        ]
    finally:
        srv.stop()


def test_a_connection_that_never_completes_its_hello_is_closed(tmp_path):
    srv = serve(root=tmp_path, idle_timeout=60, hello_timeout=0.5)
    try:
        _silent, r1 = connect(srv.port)
        slow, r2 = connect(srv.port)  # slowloris: a byte every 0.1 s, never a newline
        t0 = time.monotonic()
        for _ in range(20):
            try:
                slow.sendall(b"{")
            except OSError:
                break
            time.sleep(0.1)
        for r in (r1, r2):
            replies = lines_until_closed(r)
            assert "no hello within 0.5 s" in replies[-1]["error"]["message"]
        assert time.monotonic() - t0 < 5
    finally:
        srv.stop()


def test_a_reply_over_the_bound_becomes_an_error_reply(server):
    with Client(port=server.port, timeout=60) as c:
        c.create_sphere(name="s", radius=1.0, m=64, n=32)  # 1.24 MiB of relations as JSON
        c.new_cell(name="c")
        raw_line = None

        def read_raw() -> dict:  # the next reply line as sent, to check its length
            nonlocal raw_line
            raw_line = c._r.readline(64 << 20)
            return json.loads(raw_line)

        c._read = read_raw
        with pytest.raises(ProtocolError, match="over the 1,048,576-byte bound"):
            c.call("cell_data")
        assert len(raw_line) < 1000
        assert c.call("list", "block") == ["s"]  # the connection goes on


# ------------------------------------------------------------------ 3, 4. disconnects, log
@pytest.mark.slow
def test_abrupt_disconnects_print_no_traceback_and_the_log_has_a_line_per_connection(tmp_path):
    proc = subprocess.Popen(
        [sys.executable, "-m", "workcell.program.cli", "serve", "--port", "0"],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = proc.stdout.readline()
        port = int(line.split("127.0.0.1:")[1].split()[0])
        token = read_token_file(port)
        hello = json.dumps({"id": 0, "command": "hello", "args": {"token": token}}).encode()
        big = json.dumps({"id": 1, "command": "commands"}).encode()
        # reset (RST) at every moment: before reading the hello, mid-hello, after the hello,
        # mid-request, with a big reply unread, before a reply
        moments = [
            b"",
            hello[:10],
            hello + b"\n",
            hello + b"\n" + big[:5],
            hello + b"\n" + big + b"\n",
        ]
        for i in range(15):
            s = socket.create_connection(("127.0.0.1", port), timeout=10)
            if i % 3:
                s.recv(10)
            s.sendall(moments[i % len(moments)])
            if i % 2:
                time.sleep(0.05)
            s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
            s.close()
        with Client(port=port, timeout=30) as c:  # still serving; one error for the log
            c.call("list")
            with pytest.raises(ProgramError):
                c.call("fly")
        time.sleep(0.5)
    finally:
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    assert "Traceback" not in err, err
    opened = [ln for ln in err.splitlines() if "opened" in ln]
    closed = [ln for ln in err.splitlines() if " closed: " in ln]
    assert len(opened) == len(closed) == 16, err
    errors = [ln for ln in err.splitlines() if ": request " in ln]  # one per error
    assert len(errors) == 1, err
    assert "(fly): ProgramError: unknown command" in errors[0]
    assert not any("list" in ln for ln in err.splitlines())  # not a line per command
    assert not token_file(port).exists()  # removed at exit


def test_the_debug_log_has_a_line_per_command(server, caplog):
    with caplog.at_level(logging.DEBUG, logger="workcell.server"), Client(port=server.port) as c:
        c.call("list")
        c.call("list", "block")
    text = caplog.text
    assert text.count(": list") == 2
    assert "opened" in text


def test_log_lines_cannot_be_forged_by_a_client(server, caplog):
    with (
        caplog.at_level(logging.INFO, logger="workcell.server"),
        Client(port=server.port) as c,
        pytest.raises(ProgramError),
    ):
        c.call("x\nINFO connection 99 closed: forged")
    assert all("forged" not in ln or "\\n" in ln for ln in caplog.text.splitlines())


def test_the_python_and_node_clients_keep_working_with_tokens_by_default(server):
    import shutil
    from pathlib import Path

    with Client(port=server.port) as c:
        assert c.server_hello["token_required"] is True
    node = shutil.which("node")
    if node is None:
        return
    script = Path(__file__).resolve().parents[2] / "scripts" / "example1_client.js"
    r = subprocess.run(
        [node, str(script), str(server.port)], capture_output=True, text=True, timeout=60,
        env={**os.environ, "WORKCELL_TOKEN": ""},
    )  # fmt: skip
    assert r.returncode == 0, r.stderr  # it read the token file


def test_the_security_section_states_what_the_code_does():
    from pathlib import Path

    from workcell.limits import DEFAULTS
    from workcell.program import server as srv_module

    doc = (Path(__file__).resolve().parents[2] / "docs" / "protocol.md").read_text()
    section = doc.split("## Security", 1)[1].split("\n## ", 1)[0]
    facts = [
        f"| listen backlog | {Server.request_queue_size} |",
        f"| connections served at once | {srv_module.MAX_CONNECTIONS} (`--max-connections N`) |",
        f"| time to complete the hello | {srv_module.HELLO_TIMEOUT:g} s |",
        f"| connections waiting for their hello | {srv_module.MAX_WAITING} |",
        f"{srv_module.IDLE_TIMEOUT:g} s (`--idle-timeout S`)",
        f"answered ever later ({srv_module.BAD_TOKEN_DELAY:g} s, then",
        f"{MAX_MESSAGE_BYTES:,} bytes",
        "`server-PORT.json`",
        "`$WORKCELL_RUNTIME_DIR`",
        "mode 0600",
        "serve --root DIR`",
        "`--no-token`",
        f"| `max_facets` | {DEFAULTS.max_facets:,} |",
        f"| `max_frames_per_command` | {DEFAULTS.max_frames_per_command:,} |",
        f"| `max_frames` | {DEFAULTS.max_frames:,} |",
        f"| `max_spill_bytes` | {DEFAULTS.max_spill_bytes >> 30} GiB |",
        f"| `max_sim_time` | {DEFAULTS.max_sim_time:.0e} s |".replace("e+0", "e"),
        f"| `max_file_bytes` | {DEFAULTS.max_file_bytes >> 20} MiB |",
        f"| `max_coordinate` | {DEFAULTS.max_coordinate:.0e} m |".replace("e+0", "e"),
        *(
            f"| `{name}` | {getattr(DEFAULTS, name):,} |"
            for name in ("max_path_samples", "max_candidates", "max_workers", "max_images")
        ),
        f"| `max_pixels` | {DEFAULTS.max_pixels:,} |",
        f"| `max_line_chars` | {DEFAULTS.max_line_chars:,} |",
    ]
    for fact in facts:
        assert fact in section, fact
