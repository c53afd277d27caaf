"""Issue 19, item 7: secrets and leftovers.

The token given on the command line is in every user's ``ps``: it can come from a file
or the environment instead (``--token`` warns). A server killed with SIGKILL leaves its
token file: the next server removes it. Study workers outlive a parent killed with
SIGKILL: now they end with it. A study whose ``parts`` folder is a symbolic link would
read and delete another folder's files: refused. A save killed with SIGKILL leaves its
temp file: the next save of the same file removes it (and never a live writer's)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from workcell.client import Client
from workcell.errors import ProgramError, StudyError
from workcell.files import atomic_write_text
from workcell.program.server import Server
from workcell.program.tokens import given_token, read_token_file, token_file


def start_server(
    tmp_path: Path, *options: str, env: dict | None = None
) -> tuple[subprocess.Popen, int]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "workcell.program.cli", "serve", "--port", "0", *options],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, **(env or {})},
    )
    line = proc.stdout.readline()
    assert "listening on" in line, (line, proc.stderr.read() if proc.poll() is not None else "")
    return proc, int(line.split("127.0.0.1:")[1].split()[0])


def stop(proc: subprocess.Popen) -> str:
    proc.send_signal(signal.SIGINT)
    return proc.communicate(timeout=30)[1]


def cmdline(pid: int) -> str:
    return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()


# ------------------------------------------------------------------ tokens
@pytest.mark.skipif(not Path("/proc/self/cmdline").exists(), reason="needs /proc")
def test_a_token_from_a_file_never_shows_in_the_process_list(tmp_path):
    secret = "file-token-0123456789"
    f = tmp_path / "token"
    f.write_text(secret + "\n")
    f.chmod(0o600)
    proc, port = start_server(tmp_path, "--token-file", str(f))
    try:
        assert secret not in cmdline(proc.pid)  # what every user's ps shows
        with Client(port=port, token=secret) as c:
            assert c.call("list", "block") == []
    finally:
        err = stop(proc)
    assert "warning" not in err


def test_a_token_from_the_environment_works_and_on_the_command_line_it_warns(tmp_path):
    proc, port = start_server(tmp_path, env={"WORKCELL_TOKEN": "env-token-0123456789"})
    try:
        assert "env-token" not in cmdline(proc.pid)
        with Client(port=port, token="env-token-0123456789") as c:
            assert c.call("list", "block") == []
    finally:
        assert "warning" not in stop(proc)
    proc, port = start_server(tmp_path, "--token", "argv-token-0123456789")
    try:
        with Client(port=port, token="argv-token-0123456789") as c:  # still works
            assert c.call("list", "block") == []
    finally:
        err = stop(proc)
    assert "--token puts the token on the command line" in err
    assert "--token-file" in err


def test_token_file_errors(tmp_path):
    with pytest.raises(ProgramError, match="cannot read token file"):
        given_token(None, str(tmp_path / "none"))
    (tmp_path / "empty").write_text("\n")
    with pytest.raises(ProgramError, match="is empty"):
        given_token(None, str(tmp_path / "empty"))
    (tmp_path / "open").write_text("open-token-123\nrest")
    (tmp_path / "open").chmod(0o644)
    token, warning = given_token(None, str(tmp_path / "open"))
    assert token == "open-token-123"
    assert "can be read by other users" in warning
    with pytest.raises(ProgramError, match="not both"):
        given_token("x" * 10, str(tmp_path / "open"))
    assert given_token(None, None, {"WORKCELL_TOKEN": "e" * 10}) == ("e" * 10, None)
    assert given_token(None, None, {}) == (None, None)


def test_a_killed_servers_token_file_is_removed_by_the_next_server(tmp_path):
    proc, port = start_server(tmp_path)
    assert read_token_file(port)
    proc.kill()  # SIGKILL: nothing of the server runs
    proc.wait(30)
    proc.stdout.close()
    proc.stderr.close()
    assert token_file(port).exists()  # left behind
    live, live_port = start_server(tmp_path)  # a live server's file must stay
    try:
        srv = Server(port=0, root=tmp_path)
        try:
            assert not token_file(port).exists()  # the dead one's is gone
            assert token_file(live_port).exists()
            assert token_file(srv.port).exists()
        finally:
            srv.server_close()
    finally:
        stop(live)
    other = token_file(1)  # another machine's server (a shared home folder): left alone
    other.write_text(
        json.dumps({"port": 1, "token": "x" * 10, "pid": 2**22 + 12345, "machine": "elsewhere"})
    )
    srv = Server(port=0, root=tmp_path)
    srv.server_close()
    assert other.exists()
    other.unlink()


# ------------------------------------------------------------------ study workers
@pytest.mark.skipif(sys.platform != "linux", reason="reads /proc")
def test_study_workers_end_when_their_parent_is_killed(tmp_path):
    code = textwrap.dedent(
        f"""
        import os, time
        from workcell.study import Study, run

        def sleepy(sim):
            time.sleep(120)

        if __name__ == "__main__":
            print(os.getpid(), flush=True)
            study = Study(cell="joints", program=sleepy, vary={{"puma.base.x": "0,0.01,0.02"}})
            run(study, {str(tmp_path / "out")!r}, backend="process", workers=2, plots=False)
        """
    )
    script = tmp_path / "study.py"
    script.write_text(code)
    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    parent = int(proc.stdout.readline())

    def children() -> list[int]:
        out = []
        for d in Path("/proc").iterdir():
            if d.name.isdigit():
                try:
                    stat = (d / "stat").read_text()
                except OSError:
                    continue
                if int(stat.rsplit(")", 1)[1].split()[1]) == parent:
                    out.append(int(d.name))
        return out

    deadline = time.monotonic() + 120
    while len(workers := children()) < 2 and time.monotonic() < deadline:
        time.sleep(0.2)
    assert len(workers) >= 2, "the workers never started"
    time.sleep(2.0)  # they are set up and sleeping in a candidate
    proc.kill()  # kill -9 of the parent
    proc.wait(30)
    proc.stdout.close()
    deadline = time.monotonic() + 15
    alive = workers
    while alive and time.monotonic() < deadline:
        time.sleep(0.2)
        alive = [w for w in workers if Path(f"/proc/{w}").exists() and "Z" not in _state(w)]
    assert not alive, f"workers {alive} outlived their parent"


def _state(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return "Z"


# ------------------------------------------------------------------ study parts
def test_a_study_never_reads_or_deletes_through_a_parts_link(tmp_path):
    from workcell.study import Study, run

    other = tmp_path / "precious"
    other.mkdir()
    for name in ("part-1.parquet", ".part-2", "notes.txt"):
        (other / name).write_text("mine")
    out = tmp_path / "out"
    out.mkdir()
    (out / "parts").symlink_to(other)
    study = Study(cell="joints", vary={"puma.base.x": "0,0.01"})
    with pytest.raises(StudyError, match="is a symbolic link"):
        run(study, out, backend="serial", plots=False)
    assert sorted(p.name for p in other.iterdir()) == [".part-2", "notes.txt", "part-1.parquet"]


# ------------------------------------------------------------------ temp files
def test_a_save_killed_mid_write_leaves_a_temp_file_the_next_save_removes(tmp_path):
    target = tmp_path / "model.json"
    code = textwrap.dedent(
        f"""
        import time
        from workcell.files import atomic_path
        with atomic_path({str(target)!r}) as tmp:
            open(tmp, "wb").write(b"half" * 1000)
            print("writing", flush=True)
            time.sleep(120)
        """
    )
    killed = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    live = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert killed.stdout.readline() == "writing\n"
        assert live.stdout.readline() == "writing\n"
        killed.kill()  # kill -9: no handler runs, the temp file stays
        killed.wait(30)
        temps = lambda: sorted(p.name for p in tmp_path.iterdir() if p.name.startswith("."))  # noqa: E731
        assert len(temps()) == 2
        live_temp = [t for t in temps() if f"-{live.pid}-" in t]
        atomic_write_text(target, "{}")  # the next save of the same file
        assert temps() == live_temp  # the dead writer's is gone, the live one's is not
        assert target.read_text() == "{}"
    finally:
        live.kill()
        live.wait(30)
        for p in (killed, live):
            p.stdout.close()
    atomic_write_text(target, "{}")
    assert not any(p.name.startswith(".") for p in tmp_path.iterdir())
