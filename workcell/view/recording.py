"""A recording (.rrd) in rerun's web viewer: ``workcell view FILE.rrd``.

Runs ``rerun --serve-web`` (the viewer that ships with rerun-sdk) as a child process
bound to ``host`` (default loopback) on a free web port and a free data port, and prints
the URL of the page with ``renderer=webgl`` (without it the viewer picks WebGPU, which
software rendering does not survive). The recording's default layout frames the cell
and draws the gripper as a step signal (:mod:`workcell.record.rerun_log`).
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import quote

from workcell.errors import RecordError

__all__ = ["recording_url", "serve_recording"]


def _free_port(host: str) -> int:
    with socket.socket() as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


def recording_url(host: str, web_port: int, data_port: int) -> str:
    """The web viewer's URL for a recording served on ``data_port``."""
    data = quote(f"rerun+http://{host}:{data_port}/proxy", safe="")
    return f"http://{host}:{web_port}?url={data}&renderer=webgl"


def serve_recording(path: str | Path, *, host: str = "127.0.0.1", port: int = 0) -> int:
    """Serve ``path`` in rerun's web viewer until Ctrl-C; returns the exit status."""
    p = Path(path)
    if not p.is_file():
        raise RecordError(f"no recording {str(p)!r}")
    exe = shutil.which("rerun") or str(Path(sys.executable).with_name("rerun"))
    if not Path(exe).exists():
        raise RecordError("the 'rerun' command (from rerun-sdk) is not installed")
    web = port or _free_port(host)
    data = _free_port(host)
    cmd = [exe, "--serve-web", "--bind", host, "--web-viewer-port", str(web),
           "--port", str(data), str(p)]  # fmt: skip
    # its own process group: the 'rerun' command runs the viewer binary as a child, and
    # both end with the group
    child = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                             start_new_session=True)  # fmt: skip
    try:
        print(f"recording in the web viewer: {recording_url(host, web, data)}  (Ctrl-C stops)",
              flush=True)  # fmt: skip
        while child.poll() is None:
            time.sleep(0.5)
        raise RecordError(f"rerun's web viewer stopped (status {child.returncode})")
    except KeyboardInterrupt:
        return 0
    finally:
        _end_group(child)


def _end_group(child: subprocess.Popen) -> None:
    """Stop the child's process group (SIGTERM, then SIGKILL after 5 s)."""
    for sig in (signal.SIGTERM, signal.SIGKILL):
        try:
            os.killpg(child.pid, sig)
        except ProcessLookupError:
            return
        try:
            child.wait(5)
            return
        except subprocess.TimeoutExpired:
            continue
