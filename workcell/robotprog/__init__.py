"""Robot programs out and in: the vendors' languages (see docs/robot-programs.md).

:func:`export` writes what a robot did in a simulation (:mod:`.instructions`) in URScript,
KRL, RAPID or FANUC TP (:mod:`.urscript`, :mod:`.krl`, :mod:`.rapid`, :mod:`.fanuc`);
:func:`load` reads such a program back (or one written by hand) as a
:class:`RobotProgram` that :meth:`RobotProgram.run` executes in a simulator.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from workcell import limits
from workcell.errors import ProgramError, WorkcellError
from workcell.files import atomic_write_text, make_folder
from workcell.robotprog import fanuc, krl, rapid, urscript
from workcell.robotprog.instructions import Program, from_sim
from workcell.robotprog.runtime import VM, RobotProgram

__all__ = ["LANGUAGES", "SUFFIXES", "VM", "RobotProgram", "export", "language_of", "load"]

LANGUAGES = ("urscript", "krl", "rapid", "fanuc_ls")
SUFFIXES = {".script": "urscript", ".src": "krl", ".mod": "rapid", ".ls": "fanuc_ls"}
_WRITERS = {
    "urscript": urscript.write,
    "krl": krl.write,
    "rapid": rapid.write,
    "fanuc_ls": fanuc.write,
}


def language_of(path: str | Path, language: str | None) -> str:
    """``language``, or the one the suffix of ``path`` names (ProgramError otherwise)."""
    if language is not None:
        if language not in LANGUAGES:
            raise ProgramError(
                f"unknown robot language {language!r}; valid: {', '.join(LANGUAGES)}"
            )
        return language
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        known = ", ".join(f"{s} ({lang})" for s, lang in SUFFIXES.items())
        raise ProgramError(
            f"cannot tell the robot language of '{path}' from its suffix; use language= or "
            f"one of {known}"
        )
    return SUFFIXES[suffix]


def export(
    sim: Any,
    robot: str,
    path: str | Path,
    *,
    language: str | None = None,
    signals: Mapping[str, int] | None = None,
) -> list[str]:
    """Write ``robot``'s program as it ran in ``sim`` to ``path`` in ``language``
    (default: from the suffix, :data:`SUFFIXES`; a ``path`` without a suffix gets the
    language's); KRL also writes the ``.dat`` beside the ``.src``. Each file is written
    atomically. ``signals`` maps signal names (``"gripper"``) to I/O numbers. Returns the
    written paths. ProgramError for an unknown language or robot (nothing written)."""
    lang = language_of(path, language)
    prog: Program = from_sim(sim, robot, signals=signals)
    target = Path(path)
    if not target.suffix:  # the controller knows a program by its suffix: give it one
        target = target.with_suffix(next(k for k, v in SUFFIXES.items() if v == lang))
    files = _WRITERS[lang](prog, target.stem)
    written = [(target.with_suffix(s) if s == ".dat" else target, t) for s, t in files.items()]
    for p, text in written:
        make_folder(p.parent, error=ProgramError)
        atomic_write_text(p, text, error=ProgramError)
    return [str(p) for p, _ in written]


_IO = re.compile(r"I/O: (output|input) (\d+) = ([A-Za-z_][A-Za-z0-9_.]*)")


def _io_table(text: str) -> tuple[dict[int, str], dict[int, str]]:
    """The I/O names a file's header lists (``I/O: output 1 = gripper``)."""
    outputs: dict[int, str] = {}
    inputs: dict[int, str] = {}
    for kind, n, name in _IO.findall(text):
        (outputs if kind == "output" else inputs)[int(n)] = name
    return outputs, inputs


def load(path: str | Path, *, language: str | None = None) -> RobotProgram:
    """Read a robot program (``language`` as for :func:`export`, default from the suffix;
    a KRL ``.src`` reads the ``.dat`` beside it) as a :class:`RobotProgram`; its
    :meth:`~RobotProgram.run` executes it. ProgramError with ``file:line:column`` for
    what cannot be read or is not supported (docs/robot-programs.md lists what is)."""
    from workcell.robotprog import read_fanuc, read_krl, read_rapid, read_urscript

    lang = language_of(path, language)
    p = Path(path)
    if not p.is_file():
        raise ProgramError(f"no robot program file '{p}'")
    limits.check("max_file_bytes", p.stat().st_size, f"robot program '{p}'")
    readers = {
        "urscript": read_urscript.read,
        "krl": read_krl.read,
        "rapid": read_rapid.read,
        "fanuc_ls": read_fanuc.read,
    }
    try:
        outputs, inputs = _io_table(p.read_text(encoding="utf-8", errors="replace"))
        return readers[lang](p, outputs, inputs)
    except WorkcellError:
        raise
    except (RecursionError, ValueError, TypeError, IndexError, KeyError, AttributeError) as exc:
        raise ProgramError(
            f"{p}:1:1: cannot read the program ({type(exc).__name__}: {exc})"
        ) from exc
