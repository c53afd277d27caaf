"""A client in another language (Node.js) runs thesis example 1 against the server."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest
from program_helpers import EXAMPLE1_SIM_TIME

from workcell.program.server import Server

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "example1_client.js"
NODE = shutil.which("node")

pytestmark = pytest.mark.skipif(NODE is None, reason="Node.js is not installed")


@pytest.fixture
def server():
    srv = Server(port=0)
    srv.serve_in_thread()
    yield srv
    srv.stop()


def node(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([NODE, str(SCRIPT), *args], capture_output=True, text=True, timeout=60)


def test_the_node_client_runs_example_1_with_the_hand_formula_time(server):
    r = node(str(server.port))
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["sim_time_s"] == pytest.approx(EXAMPLE1_SIM_TIME, abs=1e-9)
    assert out["joints_deg"] == [0, 0, -90, 0, 90, 0]


def test_the_node_client_sends_the_token_and_ends_on_an_error():
    srv = Server("127.0.0.1", 0, token="node-token-1234")
    srv.serve_in_thread()
    try:
        r = node(str(srv.port), "127.0.0.1", "wrong-token-000")
        assert r.returncode == 1
        assert r.stderr.startswith("ProtocolError: wrong or missing token")
        r = node(str(srv.port), "127.0.0.1", "node-token-1234")
        assert r.returncode == 0, r.stderr
        assert json.loads(r.stdout)["sim_time_s"] == pytest.approx(EXAMPLE1_SIM_TIME, abs=1e-9)
    finally:
        srv.stop()


@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_the_node_client_prints_its_usage(flag):
    r = node(flag)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("Usage: node scripts/example1_client.js [PORT] [HOST] [TOKEN]")
    assert "workcell serve" in r.stdout
    assert r.stderr == ""


def test_the_node_client_refuses_a_port_that_is_not_a_number():
    r = node("five")
    assert r.returncode == 2
    assert r.stderr.startswith('not a port number: "five"')
    assert "Usage:" in r.stderr
    assert "RangeError" not in r.stderr
