"""The ``shell``, ``run`` and ``serve`` subcommands (added to ``workcell`` by ``register``).

Top-level imports stay light: ``workcell --help`` imports this module; the program
package is imported when a subcommand runs.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
from typing import Any

from workcell.examples import CELLS

__all__ = ["register"]

_MODES = ("path", "joint-by-joint", "playback")


def _start(args: argparse.Namespace) -> Any:
    """A function making a session as the options ask (a cell, a running simulation)."""
    from workcell.program.cellcommands import ExampleCell, LoadCell
    from workcell.program.session import Session
    from workcell.program.simcommands import Simulate

    def make() -> Session:
        s = Session()
        if args.cell:
            s.execute(LoadCell(os.path.abspath(args.cell)))
        elif args.example:
            s.execute(ExampleCell(args.example))
        if args.mode:
            s.execute(Simulate(args.mode, args.dt))
        return s

    return make


def _shell(args: argparse.Namespace) -> int:
    from workcell.program.shell import run_shell

    session = _start(args)()
    if not args.view:
        return run_shell(session, history=args.history, echo=args.echo)
    from workcell.view.cli import viewer_of

    with viewer_of(args, session.sim, "view_") as viewer:  # the live view (workcell.view)
        viewer.follow(session)
        return run_shell(session, history=args.history, echo=args.echo)


def _run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from workcell.cli import check_outputs
    from workcell.errors import WorkcellError
    from workcell.program.interpreter import run_script
    from workcell.program.session import Session

    check_outputs(rrd=args.save, png=args.render)
    session = Session(base_dir=Path(args.script).parent)
    try:
        run_script(args.script, session, echo=args.echo)
    except WorkcellError as exc:
        if session.sim is not None:  # keep what ran, with the error, in the files asked for
            session.sim._log_error(exc)
            _outputs(args, session.sim)
        raise
    _outputs(args, session.sim)
    if args.cycle_time and session.sim is not None:
        from workcell.sim.cycle import format_table

        print(format_table(session.sim.cycle_time()))
    if args.summary and session.sim is not None:
        import json

        from workcell.program.protocol import to_jsonable

        print(json.dumps(to_jsonable(session.sim.summary())))
    return 0


def _outputs(args: argparse.Namespace, sim: Any) -> None:
    """Write the recording and the picture ``--save`` and ``--render`` ask for."""
    if (args.save or args.render) and sim is None:
        from workcell.errors import ProgramError

        raise ProgramError("--save/--render: the script never started a simulation")
    if args.save:
        from workcell.record import record

        stats = record(sim, args.save, fps=args.record_fps or None)
        print(
            f"recording written to {stats.path} ({stats.frames} of {sim.frames} frames; "
            f"open it with: rerun {stats.path})"
        )
    if args.render:
        from workcell.record import contact_sheet

        contact_sheet(sim, args.render)
        print(f"picture written to {args.render}")


def _serve(args: argparse.Namespace) -> int:
    import logging

    from workcell.files import install_sigterm_cleanup
    from workcell.program.server import Server

    logging.basicConfig(
        level=args.log_level.upper(), format="%(asctime)s %(levelname)s %(message)s"
    )
    install_sigterm_cleanup()

    def stop(signum: int, frame: object) -> None:  # SIGTERM stops as Ctrl-C does
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)
    token = args.token or os.environ.get("WORKCELL_TOKEN") or None
    make = _start(args)
    make()  # a bad --cell or --mode fails here, not at each client's connection
    viewer = None
    if args.view:  # the live view shows the session that ran a command last
        from workcell.view.cli import viewer_of

        viewer = viewer_of(args, None, "view_", announce=False, control=args.view_control,
                           root=args.root)  # fmt: skip
        plain = make

        def make() -> Any:
            session = plain()
            viewer.follow(session)
            return session

    server = Server(
        args.host,
        args.port,
        token=token,
        require_token=not args.no_token,
        shared=args.shared,
        session_factory=make,
        root=args.root,
        max_connections=args.max_connections,
        idle_timeout=args.idle_timeout,
    )
    kind = "one shared session" if args.shared else "a session per client"
    auth = f"token in {server.token_path}" if server.token_path else "no token"
    print(
        f"workcell server: listening on {args.host}:{server.port} (protocol 1, {kind}, {auth}, "
        f"files in {server.root}); Ctrl-C stops",
        flush=True,
    )
    if viewer is not None:
        from workcell.view.cli import announce_url

        announce_url(viewer)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
        if viewer is not None:
            viewer.close()
    return 0


def _session_options(p: argparse.ArgumentParser) -> None:
    g = p.add_mutually_exclusive_group()
    g.add_argument("--cell", metavar="CELL.json", help="start with this cell loaded")
    g.add_argument("--example", choices=tuple(CELLS), help="start with a thesis example cell")
    p.add_argument("--mode", choices=_MODES, help="also start simulating in this mode")
    p.add_argument("--dt", type=float, default=0.01, metavar="SECONDS", help="sampling (0.01)")


def _view_options(p: argparse.ArgumentParser) -> None:
    from workcell.view.cli import add_view_options

    p.add_argument("--view", action="store_true",
                   help="also show the session live in a web page (prints its URL)")  # fmt: skip
    add_view_options(p, "view-")


def register(sub: Any) -> None:
    """Add ``shell``, ``run`` and ``serve`` to the argparse subparsers ``sub``."""
    shell = sub.add_parser(
        "shell",
        help="the interactive command language (completion, history, help)",
        description="Type commands of the workcell language; 'help' lists them. "
        "Angles in degrees and lengths in metres unless a unit says otherwise. "
        "Reads lines from standard input when it is not a terminal.",
    )
    _session_options(shell)
    shell.add_argument("--history", metavar="FILE", help="history file (~/.workcell_history)")
    shell.add_argument("--echo", action="store_true", help="print each line read (transcripts)")
    _view_options(shell)
    shell.set_defaults(func=_shell)

    run = sub.add_parser(
        "run",
        help="run a command-language script (.wcl)",
        description="Run a .wcl script; the first error stops it (exit status 2).",
    )
    run.add_argument("script", metavar="FILE.wcl")
    run.add_argument("--echo", action="store_true", help="print each command before its output")
    run.add_argument(
        "--summary", action="store_true", help="print the simulation's summary as JSON at the end"
    )
    run.add_argument(
        "--cycle-time",
        action="store_true",
        help="print the cycle-time table at the end: each command's start, duration and the "
        "limit that set it",
    )
    run.add_argument("--save", metavar="FILE.rrd", help="record the run (also up to an error)")
    from workcell.cli import add_record_fps

    add_record_fps(run)
    run.add_argument("--render", metavar="FILE.png", help="a contact sheet of the run's key frames")
    run.set_defaults(func=_run)

    serve = sub.add_parser(
        "serve",
        help="serve the remote program interface (JSON lines over TCP; docs/protocol.md)",
        description="Serve programs over TCP (docs/protocol.md; its 'Security' section). "
        "Binds 127.0.0.1 unless --host says otherwise. Clients must send a token: a random "
        "one, written to a user-only token file that local clients read, unless --token "
        "(or WORKCELL_TOKEN) gives one. File names in commands stay inside --root.",
    )
    serve.add_argument("--host", default="127.0.0.1", help="address to bind (127.0.0.1)")
    serve.add_argument("--port", type=int, default=5260, help="port (5260; 0: any free port)")
    serve.add_argument("--token", help="token clients must send (or set WORKCELL_TOKEN)")
    serve.add_argument(
        "--no-token",
        action="store_true",
        help="serve without a token (loopback only; any local user may then connect)",
    )
    serve.add_argument(
        "--root",
        default=".",
        metavar="DIR",
        help="the folder file names in commands resolve inside (default: the current one)",
    )
    serve.add_argument(
        "--max-connections",
        type=int,
        default=16,
        metavar="N",
        help="connections served at once; more are refused with an error (16)",
    )
    serve.add_argument(
        "--idle-timeout",
        type=float,
        default=300.0,
        metavar="SECONDS",
        help="close a connection without a request for this long (300)",
    )
    serve.add_argument(
        "--log-level",
        default="info",
        choices=("debug", "info", "warning", "error"),
        help="info: a line per connection and per error; debug: also per command",
    )
    serve.add_argument(
        "--shared", action="store_true", help="one session for all clients (serialised)"
    )
    _session_options(serve)
    _view_options(serve)
    serve.add_argument("--view-control", action="store_true",
                       help="with --view: the page may jog, teach and run (default: watch only)")  # fmt: skip
    serve.set_defaults(func=_serve)


def main(argv: list[str] | None = None) -> int:
    """Run one of these subcommands alone (``python -m workcell.program.cli run x.wcl``)."""
    parser = argparse.ArgumentParser(prog="workcell")
    register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    from workcell.cli import run_command

    return run_command(args)


if __name__ == "__main__":
    sys.exit(main())
