"""What the command line's modules share, below all of them (``workcell.cli`` and each
package's subcommand module import it; it imports nothing above ``workcell.files``).

- :func:`check_outputs` and :func:`check_recording_path`: refuse output files that cannot
  be written before any work;
- :func:`add_record_fps`: the ``--record-fps`` option of the commands that record;
- :func:`run_command`: run a parsed subcommand under the ``--limit`` settings, with the
  command line's exit statuses (a user's error: 2; Ctrl-C: 130).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

__all__ = ["add_record_fps", "check_outputs", "check_recording_path", "interrupted", "run_command"]


def check_recording_path(path: str | os.PathLike[str]) -> Path:
    """``path`` if a recording can be written there (an ``.rrd`` name in a writable folder,
    see :func:`workcell.files.check_writable`), else RecordError; call it before the work."""
    from workcell.errors import RecordError
    from workcell.files import check_writable

    target = Path(path)
    if target.suffix != ".rrd":
        raise RecordError(f"a recording file must end in .rrd, got '{target}'")
    check_writable(target, error=RecordError)
    return target


def check_outputs(
    *, rrd: str | None = None, png: str | None = None, folder: str | None = None
) -> None:
    """Refuse, before any work, output files that cannot be written: a recording ``rrd``,
    a picture ``png``, an output ``folder`` (each None: not asked for)."""
    from workcell.errors import ModelError, RenderError
    from workcell.files import check_folder, check_writable

    if rrd:
        check_recording_path(rrd)
    if png:
        check_writable(png, error=RenderError)
    if folder:
        check_folder(folder, error=ModelError)


def add_record_fps(parser: argparse.ArgumentParser) -> None:
    """The ``--record-fps`` option of the commands that record (``--save``)."""
    parser.add_argument(
        "--record-fps",
        type=float,
        default=60.0,
        metavar="HZ",
        help="with --save: frames per simulated second in the recording (default 60; every "
        "event keeps its exact frame; 0: every frame of the timeline)",
    )


def interrupted() -> int:
    """After Ctrl-C: one line on stderr, exit status 130."""
    # objects half-built when the interrupt came may fail in their finalizers on the way
    # out; that is no news after Ctrl-C: keep the one line
    sys.unraisablehook = lambda unraisable: None
    print("workcell: interrupted", file=sys.stderr)
    return 130


def run_command(args: argparse.Namespace) -> int:
    """Run a parsed subcommand (``args.func``) under the ``--limit`` settings: a
    WorkcellError prints one line and gives status 2; Ctrl-C prints one line and gives
    130 (files being written are removed, never left half-written under their names);
    anything else is a bug and raises."""
    from workcell import limits
    from workcell.errors import WorkcellError
    from workcell.files import install_sigterm_cleanup

    install_sigterm_cleanup()
    try:
        changes = dict(limits.parse_limit(t) for t in getattr(args, "limit", None) or [])
        limits.set_limits(**changes)
        return args.func(args)
    except WorkcellError as exc:  # the user's; anything else is ours
        print(f"workcell: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return interrupted()
