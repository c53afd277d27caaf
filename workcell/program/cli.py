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
    # another package's part around the session (workcell.view adds --view): a context
    # manager factory set as a parser default, so this package imports nothing above it
    around = getattr(args, "around_session", None)
    if around is None:
        return run_shell(session, history=args.history, echo=args.echo)
    with around(args, session):
        return run_shell(session, history=args.history, echo=args.echo)


def _run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from workcell.cli_common import check_outputs
    from workcell.errors import WorkcellError
    from workcell.program.interpreter import run_script
    from workcell.program.session import Session

    check_outputs(rrd=args.save, png=args.render)
    if args.camera and not args.render:
        from workcell.errors import ProgramError

        raise ProgramError("--camera names the view of --render's picture: give --render too")
    if args.robot_program:  # CELL --robot-program R=FILE: robot programs on a cell
        from workcell.robotprog.cli import run_robot_programs

        keep: list[Any] = []
        try:
            sim = run_robot_programs(args, keep)
        except WorkcellError:
            if keep:
                _outputs(args, keep[0])
                _collisions(keep[0], args.allow_collisions)
            raise
        return _finish(args, sim)
    session = Session(base_dir=Path(args.script).parent)
    try:
        run_script(args.script, session, echo=args.echo)
    except WorkcellError as exc:
        if session.sim is not None:  # keep what ran, with the error, in the files asked for
            session.sim._log_error(exc)
            _outputs(args, session.sim)
            _collisions(session.sim, args.allow_collisions)
        elif args.save or args.render:
            print("workcell: nothing recorded or drawn: the script stopped before it started "
                  "a simulation", file=sys.stderr)  # fmt: skip
        raise
    return _finish(args, session.sim)


def _finish(args: argparse.Namespace, sim: Any) -> int:
    """The outputs, cycle-time table and summary a finished run asks for."""
    _outputs(args, sim)
    if args.cycle_time and sim is not None:
        from workcell.sim.cycle import format_table

        print(format_table(sim.cycle_time()))
    if args.summary and sim is not None:
        import json

        from workcell.program.protocol import to_jsonable

        print(json.dumps(to_jsonable(sim.summary())))
    return _collisions(sim, args.allow_collisions)


COLLIDED = 3  # the exit status of a run that collided (without --allow-collisions)


def _collisions(sim: Any, allowed: bool) -> int:
    """Say on stderr how many collisions the run had and the first one; the exit status
    of a run that got to its end: 0, or :data:`COLLIDED` when it collided (not allowed)."""
    hits = [] if sim is None else [e for e in sim.events if e.kind == "collision"]
    if not hits:
        return 0
    first = hits[0]
    hint = "" if allowed else " (--allow-collisions: exit status 0 all the same)"
    print(
        f"workcell: {len(hits)} collision(s); the first at t = {first.t:.6g} s "
        f"(frame {first.frame}): {first.detail}{hint}",
        file=sys.stderr,
    )
    return 0 if allowed else COLLIDED


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

        contact_sheet(sim, args.render, camera=args.camera)
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
    from workcell.program.tokens import given_token

    token, warning = given_token(args.token, args.token_file)
    if warning:
        print(warning, file=sys.stderr, flush=True)
    make = _start(args)
    make()  # a bad --cell or --mode fails here, not at each client's connection
    # another package's part in the server (workcell.view adds --view), set as a parser
    # default: .sessions(make) -> make, .started(), .close()
    extra = getattr(args, "serving", None)
    part = extra(args) if extra is not None else None
    if part is not None:
        make = part.sessions(make)
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
    if part is not None:
        part.started()
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
        if part is not None:
            part.close()
    return 0


def _session_options(p: argparse.ArgumentParser) -> None:
    g = p.add_mutually_exclusive_group()
    g.add_argument("--cell", metavar="CELL.json", help="start with this cell loaded")
    g.add_argument("--example", choices=tuple(CELLS), help="start with a thesis example cell")
    p.add_argument("--mode", choices=_MODES, help="also start simulating in this mode")
    p.add_argument("--dt", type=float, default=0.01, metavar="SECONDS", help="sampling (0.01)")


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
    shell.set_defaults(func=_shell)

    run = sub.add_parser(
        "run",
        help="run a command-language script (.wcl)",
        description="Run a .wcl script; the first error stops it. Exit status: 0 the script "
        "ran to its end without a collision; 2 an error stopped it (or the options were "
        "wrong); 3 it ran to its end but things collided (stderr says how many and the "
        "first; --allow-collisions: 0); 130 interrupted (Ctrl-C).",
    )
    run.add_argument(
        "script",
        metavar="FILE.wcl|CELL",
        help="a script; with --robot-program, the cell (CELL.json or an example) to run on",
    )
    run.add_argument(
        "--robot-program",
        action="append",
        metavar="ROBOT=FILE",
        help="run a robot program (.script, .src, .mod, .ls; docs/robot-programs.md) on "
        "ROBOT of the cell; repeat for several robots (run one after another)",
    )
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
    from workcell.cli_common import add_record_fps

    add_record_fps(run)
    run.add_argument("--render", metavar="FILE.png", help="a contact sheet of the run's key frames")
    run.add_argument(
        "--camera",
        metavar="NAME",
        help="with --render: a camera of the cell, or a view: overview (the default), "
        "front, back, left, right, top",
    )
    run.add_argument(
        "--allow-collisions",
        action="store_true",
        help="exit 0 even when things collided (they are still reported on stderr)",
    )
    run.set_defaults(func=_run)

    serve = sub.add_parser(
        "serve",
        help="serve the remote program interface (JSON lines over TCP; docs/protocol.md)",
        description="Serve programs over TCP (docs/protocol.md; its 'Security' section). "
        "Binds 127.0.0.1 unless --host says otherwise. Clients must send a token: a random "
        "one, written to a user-only token file that local clients read, unless "
        "--token-file FILE or the WORKCELL_TOKEN environment variable gives one (--token "
        "TOKEN works too, but every user of the machine can read a command line). File "
        "names in commands stay inside --root.",
    )
    serve.add_argument("--host", default="127.0.0.1", help="address to bind (127.0.0.1)")
    serve.add_argument("--port", type=int, default=5260, help="port (5260; 0: any free port)")
    serve.add_argument(
        "--token-file",
        metavar="FILE",
        help="read the token clients must send from FILE's first line (keep it mode 600); "
        "or set WORKCELL_TOKEN",
    )
    serve.add_argument(
        "--token",
        help="the token clients must send; visible to every user in the process list (ps): "
        "prefer --token-file or WORKCELL_TOKEN",
    )
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
    serve.set_defaults(func=_serve)


def main(argv: list[str] | None = None) -> int:
    """Run one of these subcommands alone (``python -m workcell.program.cli run x.wcl``)."""
    parser = argparse.ArgumentParser(prog="workcell")
    register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    from workcell.cli_common import run_command

    return run_command(args)


if __name__ == "__main__":
    sys.exit(main())
