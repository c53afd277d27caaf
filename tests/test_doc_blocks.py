"""Every code block of README.md and docs/*.md runs as written (see tests/docrun.py for how
each kind of block is run), in a fresh copy of the repository's tracked files: what a new
user has after a clone. The README is walked from its top: ``make demo`` (with the
environment this checkout installed), ``source .venv/bin/activate``, then every block in
order. Blocks are discovered, so sections added later are covered without changing this
file; a block that cannot run here says so on its first line (``# not run here: why``),
and the server ones are run by ``test_marked_server_blocks``."""

from __future__ import annotations

import json
import math
import re
import signal
import socket
import subprocess
from pathlib import Path

import pytest
from docrun import (
    ROOT,
    Block,
    PythonWorker,
    blocks,
    commands,
    doc_files,
    environment,
    fresh_copy,
    replay_transcript,
    shell,
)

FILES = doc_files()


def all_blocks() -> list[Block]:
    return [b for f in FILES for b in blocks(f)]


# ---------------------------------------------------------------------- discovery
def test_every_block_is_of_a_kind_the_tests_run():
    found = all_blocks()
    assert len(found) > 20
    unknown = [f"{b.where} ({b.lang or 'no language'})" for b in found if b.kind == "unknown"]
    assert not unknown, (
        f"blocks of no known kind: {unknown}; give them a language the doc tests run "
        "(python, sh, wcl, json) or 'text' for literal text"
    )
    for b in found:
        if b.marked is not None:
            assert "test" in b.marked, f"{b.where}: say which test covers it: {b.marked!r}"
            assert b.kind in ("sh", "python", "wcl"), b.where


def test_the_readme_starts_with_the_two_commands_and_where_the_tools_are():
    first, second = blocks("README.md")[:2]
    assert [c.split("#")[0].strip() for c in commands(first.text)] == ["make demo", "make test"]
    assert commands(second.text)[0] == "source .venv/bin/activate"
    text = (ROOT / "README.md").read_text()
    assert text.index(".venv/bin") < text.index(second.text)  # said right under them
    assert "make test" in (ROOT / ".ci" / "run").read_text()  # what CI runs
    demo = (ROOT / "Makefile").read_text().split("\ndemo:")[1].split("\n\n")[0]
    assert "workcell demo handoff" in demo


def test_nothing_points_outside_the_repository():
    for f in FILES:
        text = (ROOT / f).read_text()
        assert "../shared" not in text, f
        assert "DESIGN.md" not in text, f
        assert "THESIS_SPEC" not in text, f


def broken_links(copy: Path, file: str) -> list[str]:
    """Relative links of ``file`` that name nothing in ``copy`` (run after its commands,
    so a picture the README's commands write counts)."""
    text = (copy / file).read_text()
    return [
        t
        for t in re.findall(r"\]\(([^)#\s]+)", text)
        if "://" not in t and not ((copy / file).parent / t).exists()
    ]


# ---------------------------------------------------------------------- running
@pytest.fixture(scope="module")
def copy(tmp_path_factory) -> Path:
    return fresh_copy(tmp_path_factory.mktemp("clone"))


def run_blocks(copy: Path, file: str, log: Path) -> list[str]:
    """Run every unmarked block of ``file`` in order in ``copy``; the failures."""
    failures: list[str] = []
    worker = PythonWorker(copy, log)
    try:
        for b in blocks(file):
            if b.marked is not None:
                continue
            problem = ""
            if b.kind == "python":
                problem = worker.run(b)
            elif b.kind == "sh":
                for cmd in commands(b.text):
                    if cmd.split("#")[0].strip() == "make test":
                        continue  # the test suite itself (CI's command): running now
                    r = shell(copy, cmd)
                    if r.returncode != 0:
                        problem = (
                            f"`{cmd}` exited {r.returncode}:\n{r.stdout[-2000:]}{r.stderr[-3000:]}"
                        )
                        break
            elif b.kind == "wcl":
                first = b.text.splitlines()[0]
                name = re.match(r"#\s*([\w.-]+\.wcl)\b", first)
                path = copy / (name.group(1) if name else f"_block_{b.line}.wcl")
                path.write_text(b.text)
                r = shell(copy, f"workcell run {path.name}")
                if r.returncode != 0:
                    problem = (
                        f"workcell run exited {r.returncode}:\n{r.stdout[-2000:]}{r.stderr[-3000:]}"
                    )
            elif b.kind == "json":
                problem = _json_problem(b.text)
            elif b.kind == "transcript":
                problem = replay_transcript(copy, b)
            elif b.kind == "exchange":
                problem = replay_exchange(b)
            if problem:
                failures.append(f"{b.where} ({b.kind}): {problem}")
    finally:
        worker.close()
    return failures


def _json_problem(text: str) -> str:
    try:
        json.loads(text)
        return ""
    except json.JSONDecodeError:
        pass
    for i, line in enumerate(text.splitlines(), 1):
        try:
            json.loads(line)
        except json.JSONDecodeError as exc:
            return f"line {i} is not JSON: {exc}"
    return ""


@pytest.mark.slow
def test_the_readme_walk_runs_every_command_as_written(copy, tmp_path):
    """A new user's first hour, from the top of the README."""
    failures = run_blocks(copy, "README.md", tmp_path / "python.log")
    assert not failures, "\n\n".join(failures) + f"\n(python output: {tmp_path / 'python.log'})"
    assert not broken_links(copy, "README.md")
    for made in ("handoff.rrd", "handoff.png", "my_cell.png", "my_cell_script.png", "cell.json"):
        assert (copy / made).is_file(), made  # the files the README says its commands write


@pytest.mark.slow
@pytest.mark.parametrize("file", [f for f in FILES if f != "README.md"])
def test_every_doc_block_runs(copy, file, tmp_path):
    failures = run_blocks(copy, file, tmp_path / "python.log")
    assert not failures, "\n\n".join(failures) + f"\n(python output: {tmp_path / 'python.log'})"
    assert not broken_links(copy, file)


# ---------------------------------------------------------------------- servers
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def same_json(a: object, b: object, rel: float = 1e-9) -> bool:
    """Whether two JSON values are equal, floats within ``rel`` (a documented cycle time
    printed with 17 digits moves in its last digits with the order of floating-point
    sums, e.g. 16.931437229640736 vs ...641713 between two numpy builds)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same_json(a[k], b[k], rel) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same_json(x, y, rel) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) or isinstance(b, float):
        if isinstance(a, bool) or isinstance(b, bool):
            return a == b
        return (
            isinstance(a, int | float)
            and isinstance(b, int | float)
            and math.isclose(a, b, rel_tol=rel, abs_tol=1e-12)
        )
    return a == b


def replay_exchange(block: Block) -> str:
    """Send the exchange's client lines to a server (the documented token placeholder
    replaced by the server's) and compare its replies, as JSON, with the documented ones."""
    from workcell.program.server import Server

    token = "doc-exchange-token"
    srv = Server(port=0, token=token)
    srv.serve_in_thread()
    try:
        sock = socket.create_connection(("127.0.0.1", srv.port), timeout=30)
        reader = sock.makefile("rb")
        for i, line in enumerate(block.text.splitlines(), block.line + 1):
            who, _, message = line.partition(": ")
            if who == "C":
                message = re.sub(r'"token": "[^"]*"', f'"token": "{token}"', message)
                sock.sendall(message.encode() + b"\n")
                continue
            got = reader.readline().decode()
            if not got:
                return f"line {i}: the server closed the connection; documented {message}"
            if not same_json(json.loads(got), json.loads(message)):
                return f"line {i}: the server says\n  {got.strip()}\nthe document says\n  {message}"
        sock.close()
    finally:
        srv.stop()
    return ""


def test_marked_server_blocks(tmp_path):
    """Blocks that start ``workcell serve`` run as written (on a free port instead of the
    documented one, which another program may hold), with a client program of each kind
    against them: Python's Client, the Node.js example and the raw protocol."""
    served = [b for f in FILES for b in blocks(f) if b.marked and "workcell serve" in b.text]
    assert served, "the README documents workcell serve"
    for b in served:
        (cmd,) = [c for c in commands(b.text) if c.startswith("workcell serve")]
        port = _free_port()
        cmd = re.sub(r"--port \d+", f"--port {port}", cmd.split("#")[0])
        env = environment(ROOT)
        proc = subprocess.Popen(
            ["bash", "-c", f"source .venv/bin/activate && exec {cmd}"],
            cwd=ROOT,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        try:
            assert proc.stdout is not None
            line = proc.stdout.readline()
            assert "listening" in line, line
            _client_programs(port)
        finally:
            proc.send_signal(signal.SIGINT)  # Ctrl-C, as the README says
            out, _ = proc.communicate(timeout=60)
        assert proc.returncode == 0, out


def _client_programs(port: int) -> None:
    import math
    import shutil

    from workcell.client import Client

    with Client(port=port, timeout=60) as sim:  # the token comes from the token file
        sim.example_cell("joints")
        sim.simulate("path", dt=0.01)
        sim.set_speed("puma", 0.3)
        sim.move_joints_relative("puma", [math.radians(d) for d in (-70, -10, 10, 30, -20, -10)])
        assert sim.sim_time == pytest.approx(math.radians(70) / 0.3, abs=1e-9)
    node = shutil.which("node")
    if node is not None:
        r = subprocess.run(
            [node, str(ROOT / "scripts" / "example1_client.js"), str(port)],
            capture_output=True,
            text=True,
            timeout=120,
            env=environment(ROOT),
        )
        assert r.returncode == 0, r.stderr
        assert json.loads(r.stdout)["sim_time_s"] == pytest.approx(math.radians(170) / 0.3)
    from workcell.program.tokens import read_token_file

    with socket.create_connection(("127.0.0.1", port), timeout=30) as s:  # the nc lines
        r = s.makefile("rb")
        assert json.loads(r.readline())["protocol"] == "workcell"
        token = read_token_file(port)
        s.sendall(f'{{"id":0,"command":"hello","args":{{"token":"{token}"}}}}\n'.encode())
        s.sendall(b'{"id":1,"command":"list"}\n')
        assert json.loads(r.readline())["id"] == 0
        assert json.loads(r.readline())["result"] == {
            "surface": [], "block": [], "object": [], "scene": []
        }  # fmt: skip
