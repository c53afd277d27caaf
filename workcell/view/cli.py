"""``workcell view``: the live view of a cell (and a recording in rerun's web viewer).

``workcell view CELL.json|EXAMPLE [--program FILE.wcl] [--host H] [--port N]`` loads
the cell, starts a simulator and the live view (:class:`workcell.view.Viewer`) and
prints the page's URL. With ``--program`` it waits for a page to open (``--no-wait``:
not), runs the program there for the page to show, then keeps the page up for jogging,
teaching and scrubbing until Ctrl-C.

``workcell view FILE.rrd`` serves a recording in rerun's web viewer (``rerun
--serve-web``, on ``--host``, default loopback) and prints the URL to open (with
``renderer=webgl``, which works where the browser has no WebGPU); Ctrl-C stops it.

Top-level imports stay light (``workcell --help`` imports this module).
"""

from __future__ import annotations

import argparse
import contextlib
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from workcell.examples import CELL_HELP

__all__ = ["add_view_options", "announce_url", "register", "viewer_of"]


def add_view_options(p: argparse.ArgumentParser, prefix: str = "") -> None:
    """--host/--port/--speed (or --view-host ... when ``prefix`` is "view-")."""
    p.add_argument(f"--{prefix}host", default="127.0.0.1",
                   help="address the page is served on (127.0.0.1: this machine only)")  # fmt: skip
    p.add_argument(f"--{prefix}port", type=int, default=0, metavar="N",
                   help="port of the page (0: any free one)")  # fmt: skip
    p.add_argument(f"--{prefix}speed", type=float, default=1.0, metavar="X",
                   help="show motions at X times real time (1); 0: only each command's end")  # fmt: skip


def viewer_of(
    args: argparse.Namespace, sim: Any, prefix: str = "", *, announce: bool = True, **kw: Any
) -> Any:
    """A Viewer as the options ask; prints its URL (unless ``announce`` is False)."""
    from workcell.view import Viewer

    get = lambda name: getattr(args, f"{prefix}{name}")  # noqa: E731
    speed = get("speed")
    v = Viewer(sim, host=get("host"), port=get("port"), speed=speed or None, **kw)
    if announce:
        announce_url(v)
    return v


def announce_url(viewer: Any) -> None:
    """Print the page's URL for the user."""
    print(f"live view: {viewer.url}  (open it in a browser; Ctrl-C stops)", flush=True)


def _serve_until_interrupted() -> int:
    try:
        while True:
            time.sleep(0.5)
    except KeyboardInterrupt:
        return 0


def _stop_on_sigterm() -> None:
    """SIGTERM stops as Ctrl-C does (the page's server and rerun's child end cleanly)."""
    import signal

    def stop(signum: int, frame: object) -> None:
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)


def _view(args: argparse.Namespace) -> int:
    _stop_on_sigterm()
    if args.cell.endswith(".rrd"):
        from workcell.view.recording import serve_recording

        return serve_recording(args.cell, host=args.host, port=args.port)
    from workcell.errors import ProgramError
    from workcell.examples import load_cell
    from workcell.sim import Simulator

    if args.program and not Path(args.program).is_file():
        raise ProgramError(f"--program: no file {args.program!r}")
    sim = Simulator(load_cell(args.cell), mode=args.mode, dt=args.dt)
    viewer = viewer_of(args, sim, root=args.root)
    try:
        if args.program:
            from workcell.program.interpreter import run_script
            from workcell.program.session import Session

            if not args.no_wait:
                print("waiting for a page to open the URL ...", flush=True)
                while viewer.clients == 0:
                    time.sleep(0.1)
            session = Session(sim=sim, base_dir=Path(args.program).parent, root=args.root)
            viewer.follow(session)
            try:
                run_script(args.program, session)
            except Exception as exc:
                from workcell.errors import WorkcellError

                if not isinstance(exc, WorkcellError):
                    raise
                sim._log_error(exc)
                print(f"workcell: {type(exc).__name__}: {exc}", flush=True)
            print(f"program done: t = {sim.sim_time:.4f} s; the page stays up", flush=True)
        return _serve_until_interrupted()
    finally:
        viewer.close()


@contextlib.contextmanager
def _around_shell(args: argparse.Namespace, session: Any) -> Iterator[None]:
    """``shell --view``: the live view of the shell's session while the shell runs."""
    if not args.view:
        yield
        return
    with viewer_of(args, session.sim, "view_") as viewer:
        viewer.follow(session)
        yield


class _Serving:
    """``serve --view``: the page shows the session that ran a command last (read-only
    unless --view-control)."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.viewer = viewer_of(args, None, "view_", announce=False,
                                control=args.view_control, root=args.root)  # fmt: skip

    def sessions(self, make: Callable[[], Any]) -> Callable[[], Any]:
        def followed() -> Any:
            session = make()
            self.viewer.follow(session)
            return session

        return followed

    def started(self) -> None:
        announce_url(self.viewer)

    def close(self) -> None:
        self.viewer.close()


def _serving(args: argparse.Namespace) -> _Serving | None:
    return _Serving(args) if args.view else None


def _add_view_flag(p: argparse.ArgumentParser) -> None:
    p.add_argument("--view", action="store_true",
                   help="also show the session live in a web page (prints its URL)")  # fmt: skip
    add_view_options(p, "view-")


def register(sub: Any) -> None:
    """Add ``view`` to the argparse subparsers ``sub``, and ``--view`` to ``shell`` and
    ``serve`` (registered before, by :mod:`workcell.program.cli`)."""
    shell, serve = sub.choices.get("shell"), sub.choices.get("serve")
    if shell is not None:
        _add_view_flag(shell)
        shell.set_defaults(around_session=_around_shell)
    if serve is not None:
        _add_view_flag(serve)
        serve.add_argument("--view-control", action="store_true",
                           help="with --view: the page may jog, teach and run (default: watch "
                           "only)")  # fmt: skip
        serve.set_defaults(serving=_serving)
    p = sub.add_parser(
        "view",
        help="the live view of a cell in a web page (jog, teach, run, watch), or a "
        "recording (.rrd) in rerun's web viewer",
        description="Serve the cell as a live web page and print its URL (with the token "
        "it needs). Loopback only unless --host says otherwise.",
    )
    p.add_argument("cell", metavar="CELL", help=CELL_HELP + "; or a recording FILE.rrd")
    p.add_argument("--program", metavar="FILE.wcl", help="run this program for the page")
    p.add_argument("--no-wait", action="store_true",
                   help="with --program: run at once, without waiting for a page")  # fmt: skip
    p.add_argument("--mode", choices=("path", "joint-by-joint", "playback"), default="path")
    p.add_argument("--dt", type=float, default=0.01, metavar="SECONDS", help="sampling (0.01)")
    p.add_argument("--root", default=".", metavar="DIR",
                   help="the folder the page saves programs in (the current one)")  # fmt: skip
    add_view_options(p)
    p.set_defaults(func=_view)
