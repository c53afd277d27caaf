"""The remote program interface: protocol v1 over TCP, the Python client, robustness."""

from __future__ import annotations

import json
import math
import os
import socket
import subprocess
import sys
import threading

import numpy as np
import pytest
from program_helpers import EXAMPLE1_SIM_TIME

from workcell import JointLimitError, ModelError, ProgramError, ProtocolError
from workcell.client import Client
from workcell.examples import thesis_joints
from workcell.program import Session
from workcell.program.protocol import MAX_MESSAGE_BYTES, to_jsonable
from workcell.program.server import Server, is_loopback
from workcell.program.tokens import read_token_file
from workcell.sim.timeline import Event

TOKEN = "s3cret-token-123"


@pytest.fixture
def server():
    srv = Server(port=0)
    srv.serve_in_thread()
    yield srv
    srv.stop()


class Raw:
    """A bare protocol connection: lines in, lines out; says hello (with the server's
    token from its token file) unless ``hello=False``."""

    def __init__(self, port: int, host: str = "127.0.0.1", *, hello: bool = True) -> None:
        self.sock = socket.create_connection((host, port), timeout=10)
        self.r = self.sock.makefile("rb")
        self.hello = json.loads(self.r.readline())
        if hello:
            token = read_token_file(port)
            r = self.ask({"id": 0, "command": "hello", "args": {"version": 1, "token": token}})
            assert r["result"]["protocol"] == "workcell", r

    def send(self, data: bytes) -> None:
        self.sock.sendall(data)

    def ask(self, obj) -> dict:
        self.send((obj if isinstance(obj, str) else json.dumps(obj)).encode() + b"\n")
        return self.reply()

    def reply(self) -> dict:
        line = self.r.readline()
        assert line, "the server closed the connection"
        return json.loads(line)

    def close(self) -> None:
        self.r.close()
        self.sock.close()


def still_serving(port: int) -> None:
    with Client(port=port, timeout=10) as c:
        assert c.call("list") == {"surface": [], "block": [], "object": [], "scene": []}


def test_hello_says_protocol_version_and_bound(server):
    raw = Raw(server.port)
    assert raw.hello == {
        "protocol": "workcell",
        "version": 1,
        "server": raw.hello["server"],
        "max_message_bytes": MAX_MESSAGE_BYTES,
        "sessions": "own",
        "token_required": True,
        "idle_timeout_s": 300.0,
    }
    assert raw.ask({"id": "a", "command": "hello", "args": {"version": 1}})["id"] == "a"
    r = raw.ask({"id": 7, "command": "commands"})
    mja = next(c for c in r["result"] if c["name"] == "move_joints_absolute")
    assert [a["name"] for a in mja["args"]] == ["robot", "q", "plan", "zone"]
    assert raw.ask({"id": 8, "command": "bye"}) == {"id": 8, "result": None}
    assert raw.r.readline() == b""  # closed after bye
    raw.close()


def test_example_1_runs_unchanged_remote_with_the_hand_formula_time(server):
    with Client(port=server.port) as c:
        c.example_cell("joints")
        c.simulate("path", dt=0.01)
        thesis_joints.program(c)  # the same function that drives a Simulator in-process
        assert c.sim_time == pytest.approx(EXAMPLE1_SIM_TIME, abs=1e-9)
        q = c.joints("puma")
        assert isinstance(q, np.ndarray)
        assert np.allclose(q, np.radians(thesis_joints.START_DEG))
        T = c.tool_pose("puma")
        local = thesis_joints.build().robots["puma"]
        assert T.shape == (4, 4)
        assert np.allclose(T, local.tool_pose(), atol=1e-9)
        assert c.robots == ("puma",)
        assert all(isinstance(e, Event) for e in c.events)
        assert [e.kind for e in c.events] == ["speed", "move", "move", "move"]
        assert c.summary()["frames"] == c.frames


def test_an_error_reply_raises_the_matching_error_and_both_go_on(server):
    with Client(port=server.port) as c:
        c.example_cell("joints")
        c.simulate()
        with pytest.raises(JointLimitError, match="joint 1"):
            c.move_joints_absolute("puma", np.radians([170, 0, -90, 0, 90, 0]))
        assert c.create_cube("a", 1.0) == "a"  # any command of the vocabulary is a method
        with pytest.raises(ModelError, match="already exists"):
            c.call("create_cube", "a", 1.0)
        with pytest.raises(ProgramError, match="unknown command 'fly'"):
            c.call("fly")
        with pytest.raises(ProgramError, match="no pose 'up'; named poses: home, zero"):
            c.call("move_joints_absolute", robot="puma", q="up")
        with pytest.raises(ProgramError, match="missing argument"):
            c.call("set_speed", robot="puma")
        # the connection is still good, and nothing changed
        assert c.sim_time == 0.0
        assert c.frames == 1
    still_serving(server.port)


@pytest.mark.parametrize(
    ("line", "words"),
    [
        ("{not json", "malformed JSON"),
        ("[1, 2]", "JSON object"),
        ('{"id": [1], "command": "list"}', '"id" must be'),
        ('{"id": 1, "command": 5}', '"command" must be a string'),
        ('{"id": 1, "command": "list", "args": 3}', '"args" must be'),
        ('{"id": 1, "version": 2, "command": "list"}', "version 2 unknown"),
        ('{"id": 1, "command": "hello", "args": {"version": 9}}', "version 9 unknown"),
        ('"\\ud800"', "JSON object"),
    ],
)
def test_malformed_requests_get_a_protocol_error_and_the_connection_goes_on(server, line, words):
    raw = Raw(server.port)
    r = raw.ask(line)
    assert r["error"]["type"] == "ProtocolError"
    assert words in r["error"]["message"]
    assert raw.ask({"id": 2, "command": "list", "args": {"level": "block"}}) == {
        "id": 2,
        "result": [],
    }
    raw.send(b"\xff\xfe\n")  # not UTF-8
    assert "UTF-8" in raw.reply()["error"]["message"]
    raw.close()
    still_serving(server.port)


def test_pipelined_requests_are_answered_in_order_and_crlf_is_accepted(server):
    raw = Raw(server.port)
    raw.send(
        b'{"id": 1, "command": "create_cube", "args": ["c", 2]}\r\n\n'
        b'{"id": 2, "command": "properties", "args": ["c"], "future": true}\n'
        b'{"id": 3, "command": "remove", "args": {"ref": ["block", "c"]}}\n'
    )
    assert raw.reply() == {"id": 1, "result": "c"}
    r = raw.reply()
    assert r["id"] == 2
    assert r["result"]["volume"] == pytest.approx(8.0)
    assert raw.reply() == {"id": 3, "result": ["c"]}
    raw.close()


def test_wrong_argument_types_name_the_argument_and_echo_the_id(server):
    raw = Raw(server.port)
    r = raw.ask({"id": "x1", "command": "create_cube", "args": {"name": "c", "size": "big"}})
    assert r == {
        "id": "x1",
        "error": {
            "type": "ProgramError",
            "message": "create_cube: size must be a finite number, got 'big'",
        },
    }
    r = raw.ask({"id": "x2", "command": "create_cube", "args": ["c", 0.5]})
    assert r == {"id": "x2", "result": "c"}
    raw.close()


def test_oversized_messages_are_refused_at_the_documented_bound(server):
    raw = Raw(server.port)
    raw.send(b'{"id": 1, "command": "list", "pad": "' + b"x" * MAX_MESSAGE_BYTES + b'"}\n')
    r = raw.reply()
    assert r["id"] is None
    assert r["error"]["type"] == "ProtocolError"
    assert f"longer than {MAX_MESSAGE_BYTES} bytes" in r["error"]["message"]
    # exactly at the bound (newline included) is accepted
    body = b'{"id": 2, "command": "list"}'
    raw.send(body + b" " * (MAX_MESSAGE_BYTES - len(body) - 1) + b"\n")
    assert raw.reply()["id"] == 2
    raw.close()
    still_serving(server.port)


def test_abrupt_disconnects_leave_the_server_serving(server):
    a = Raw(server.port)
    a.send(b'{"id": 1, "command": "li')  # half a request, then gone
    a.close()
    b = socket.create_connection(("127.0.0.1", server.port))
    b.close()  # gone before the hello is read
    c = Raw(server.port)
    c.send(json.dumps({"id": 1, "command": "example_cell", "args": ["joints"]}).encode() + b"\n")
    c.sock.shutdown(socket.SHUT_RDWR)  # gone before the reply
    c.close()
    still_serving(server.port)


def test_each_client_has_its_own_session_and_runs_at_the_same_time(server):
    results: dict[float, float] = {}
    errors: list[BaseException] = []

    def client(speed: float) -> None:
        try:
            with Client(port=server.port, timeout=60) as c:
                c.example_cell("joints")
                c.simulate("path", 0.01)
                c.call("create_cube", f"mine_{speed}", 1.0)
                assert c.call("list", "block") == [f"mine_{speed}"]  # no one else's
                thesis_joints.program(c)
                c.set_speed("puma", speed)
                c.move_joints_relative("puma", np.radians([-70, 0, 0, 0, 0, 0]))
                results[speed] = c.sim_time
        except BaseException as exc:
            errors.append(exc)

    speeds = [0.1, 0.2, 0.3, 0.4, 0.5]
    threads = [threading.Thread(target=client, args=(s,)) for s in speeds]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert not errors, errors
    for s in speeds:  # example 1 at 0.3 rad/s, then 70 deg at each client's own speed
        assert results[s] == pytest.approx(EXAMPLE1_SIM_TIME + math.radians(70) / s, abs=1e-9)


def test_a_shared_session_serialises_the_clients():
    srv = Server(port=0, shared=True)
    srv.serve_in_thread()
    try:
        errors: list[BaseException] = []

        def client(k: int) -> None:
            try:
                with Client(port=srv.port) as c:
                    assert c.server_hello["sessions"] == "shared"
                    for i in range(15):
                        c.call("create", "block", f"b{k}_{i}")
            except BaseException as exc:
                errors.append(exc)

        threads = [threading.Thread(target=client, args=(k,)) for k in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(60)
        assert not errors, errors
        with Client(port=srv.port) as c:
            names = c.call("list", "block")
        assert sorted(names) == sorted(f"b{k}_{i}" for k in range(4) for i in range(15))
    finally:
        srv.stop()


def test_binding_beyond_loopback_needs_a_token_and_clients_must_send_it(monkeypatch):
    assert is_loopback("127.0.0.1")
    assert is_loopback("localhost")
    assert is_loopback("::1")
    assert not is_loopback("0.0.0.0")
    with pytest.raises(ProgramError, match="without a token"):
        Server("0.0.0.0", 0, require_token=False)
    with pytest.raises(ProgramError, match="at least 8"):
        Server("127.0.0.1", 0, token="short")
    srv = Server("0.0.0.0", 0, token=TOKEN, bad_token_delay=0.01)
    srv.serve_in_thread()
    try:
        raw = Raw(srv.port, hello=False)
        assert raw.hello["token_required"] is True
        r = raw.ask({"id": 2, "command": "hello", "args": {"token": "wrong-token-000"}})
        assert "wrong or missing token" in r["error"]["message"]
        assert raw.r.readline() == b""  # closed
        raw.close()
        with pytest.raises(ProtocolError, match="wrong or missing token"):
            Client(port=srv.port, token="wrong-token-000")
        monkeypatch.setenv("WORKCELL_RUNTIME_DIR", "/nonexistent")  # no token file
        with pytest.raises(ProtocolError, match="needs a token"):
            Client(port=srv.port)
        with Client(port=srv.port, token=TOKEN) as c:
            assert c.call("list", "scene") == []
    finally:
        srv.stop()


def test_an_internal_error_is_reported_and_the_server_goes_on():
    class Broken(Session):
        def execute(self, command):
            if command.wire == "frames":
                raise RuntimeError("boom")
            return super().execute(command)

    srv = Server(port=0, session_factory=Broken)
    srv.serve_in_thread()
    try:
        raw = Raw(srv.port)
        r = raw.ask({"id": 1, "command": "frames"})
        assert r == {"id": 1, "error": {"type": "InternalError", "message": "boom"}}
        assert raw.ask({"id": 2, "command": "list", "args": ["scene"]}) == {"id": 2, "result": []}
        raw.close()
    finally:
        srv.stop()


def test_results_are_plain_json():
    assert to_jsonable({"a": np.array([1.0, np.nan]), "b": (np.float32(2), np.inf)}) == {
        "a": [1.0, None],
        "b": [2.0, None],
    }
    with pytest.raises(ProtocolError):
        to_jsonable(object())


def test_workcell_serve_runs_example_1_for_a_client():
    p = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "workcell.program.cli",
            "serve",
            "--port",
            "0",
            "--example",
            "joints",
            "--mode",
            "path",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = p.stdout.readline()
        assert "listening on 127.0.0.1:" in line, p.stderr.read() if p.poll() is not None else line
        port = int(line.split("127.0.0.1:")[1].split()[0])
        with Client(port=port, timeout=30) as c:
            thesis_joints.program(c)
            assert c.sim_time == pytest.approx(EXAMPLE1_SIM_TIME, abs=1e-9)
    finally:
        p.terminate()
        p.wait(10)


def test_workcell_serve_refuses_a_public_address_without_a_token():
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "workcell.program.cli",
            "serve",
            "--host",
            "0.0.0.0",
            "--port",
            "0",
            "--no-token",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env={k: v for k, v in os.environ.items() if k != "WORKCELL_TOKEN"},
    )
    assert r.returncode == 2
    assert "without a token" in r.stderr
