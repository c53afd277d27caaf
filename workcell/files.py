"""Files: every file the project writes or reads by name goes through here.

Writing (:func:`atomic_path`, :func:`atomic_write_bytes`, :func:`atomic_write_text`): a
temp file beside the target, fsynced, then renamed over it, so readers see the old file
or the new one, never a part. The target is resolved through symbolic links (the link's
target is written, the link stays); a target that is not a regular file (a folder, a
FIFO, a device) is refused; an existing file keeps its mode (and, when allowed, its
owner). A temp file is removed on any error, on Ctrl-C and on SIGTERM. Every
file-system failure (missing folder, not a folder, permission, read-only, name too long,
disk full) becomes the caller's :class:`~workcell.errors.WorkcellError` subclass naming
the path; :func:`check_writable` runs the same checks before expensive work starts. A
temp file's name says which machine and process writes it, and the next write of the
same file removes those whose process died (SIGKILL leaves them: nothing runs then).

Reading (:func:`read_bytes`, :func:`read_text`, :func:`load_json`): regular files only
(a folder, a FIFO, a socket or a device is refused before anything opens it, and the
open cannot block: a file swapped in between is caught after the open), bounded by the
``max_file_bytes`` limit (:mod:`workcell.limits`), confined to the root folder in force
(:mod:`workcell.confine`), and a file that does not parse gives the caller's error class
without echoing the file's content.

Confinement (:func:`resolve_inside`, :func:`leaves_root`) lives in :mod:`workcell.confine`
(re-exported here).
"""

from __future__ import annotations

import contextlib
import json
import os
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from workcell import confine, limits
from workcell.confine import leaves_root, resolve_inside
from workcell.errors import WorkcellError
from workcell.tempfiles import install_sigterm_cleanup, reason, temp_file
from workcell.tempfiles import kind as file_kind

__all__ = [
    "atomic_path",
    "atomic_write_bytes",
    "atomic_write_text",
    "check_folder",
    "check_writable",
    "install_sigterm_cleanup",
    "leaves_root",
    "load_json",
    "make_folder",
    "read_bytes",
    "read_text",
    "resolve_inside",
    "write_files",
]

Error = type[WorkcellError]


def _name(path: str | os.PathLike, doing: str, error: Error) -> str:
    """``path`` as a string the file system can take; ``error`` for a NUL character or a
    lone surrogate (text no file name can hold; quoted escaped in the message)."""
    name = os.fspath(path)
    try:
        os.fsencode(name)
    except UnicodeEncodeError:
        raise error(f"cannot {doing} {name!r}: the name holds a lone surrogate") from None
    if "\x00" in str(name):
        raise error(f"cannot {doing} {name!r}: the name holds a NUL character")
    return name


# ------------------------------------------------------------------ writing
def _target(path: str | os.PathLike, error: Error) -> tuple[Path, os.stat_result | None]:
    """The file a write to ``path`` replaces (symbolic links followed) and its stat."""
    p = Path(os.path.realpath(_name(path, "write", error)))
    try:
        st = os.stat(p)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise error(f"cannot write '{path}': {reason(exc)}") from exc
    if st is not None and not stat.S_ISREG(st.st_mode):
        kind = "a folder" if stat.S_ISDIR(st.st_mode) else file_kind(st.st_mode)
        raise error(
            f"cannot write '{path}': it is {kind}, not a regular file; refusing to replace it"
        )
    folder = p.parent
    try:
        fst = os.stat(folder)
    except OSError as exc:
        why = (
            f"folder '{folder}' does not exist"
            if isinstance(exc, FileNotFoundError)
            else reason(exc)
        )
        raise error(f"cannot write '{path}': {why}") from exc
    if not stat.S_ISDIR(fst.st_mode):
        raise error(f"cannot write '{path}': '{folder}' is not a folder")
    try:
        name_max = os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError):
        name_max = 255
    if len(os.fsencode(p.name)) > name_max:
        raise error(f"cannot write '{path}': file name too long (at most {name_max} bytes)")
    return p, st


def check_writable(path: str | os.PathLike, *, error: Error = WorkcellError) -> Path:
    """Check that ``path`` can be written (the checks of :func:`atomic_path`, plus a real
    temp file created and removed in its folder); return the file that would be written.

    Call it before expensive work whose result goes to ``path``.
    """
    p, _ = _target(path, error)
    with temp_file(p, ".probe", path, error, "write"):
        pass
    return p


@contextlib.contextmanager
def atomic_path(
    path: str | os.PathLike,
    suffix: str = ".tmp",
    *,
    error: Error = WorkcellError,
    mode: int | None = None,
) -> Iterator[str]:
    """A temp file name beside ``path`` for a writer that needs a file name.

    When the block succeeds the file is fsynced, given ``mode`` (default: the mode of the
    file it replaces; a new file 0666 less the umask; the temp file is 0600 until then)
    and renamed over ``path`` (through symbolic links);
    on any error, Ctrl-C or SIGTERM it is removed and ``path`` is left as it was.
    File-system failures raise ``error`` naming the path (see the module doc); so does an
    OSError raised in the block. ``suffix``: the temp file's ending (some writers choose
    the format by it).
    """
    p, st = _target(path, error)
    install_sigterm_cleanup()
    with temp_file(p, suffix, path, error, "write") as tmp:
        try:
            yield tmp
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
            if mode is not None:
                os.chmod(tmp, mode)
            elif st is not None:
                os.chmod(tmp, stat.S_IMODE(st.st_mode))
                with contextlib.suppress(OSError):  # keep the owner where we may
                    if (st.st_uid, st.st_gid) != (os.getuid(), os.getgid()):
                        os.chown(tmp, st.st_uid, st.st_gid)
            else:
                umask = os.umask(0)
                os.umask(umask)
                os.chmod(tmp, 0o666 & ~umask)
            os.replace(tmp, p)
        except OSError as exc:
            raise error(f"cannot write '{path}': {reason(exc)}") from exc


def atomic_write_bytes(
    path: str | os.PathLike, data: bytes, *, error: Error = WorkcellError, mode: int | None = None
) -> None:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path, error=error, mode=mode) as tmp, open(tmp, "wb") as f:
        f.write(data)


def atomic_write_text(
    path: str | os.PathLike, text: str, *, error: Error = WorkcellError, mode: int | None = None
) -> None:
    """Write UTF-8 ``text`` to ``path`` atomically (see :func:`atomic_path`)."""
    atomic_write_bytes(path, text.encode("utf-8"), error=error, mode=mode)


def check_folder(path: str | os.PathLike, *, error: Error = WorkcellError) -> Path:
    """Check that folder ``path`` exists or can be created, and that files can be written
    in it (the nearest existing folder on the way gets a real temp file, removed at
    once); ``error`` naming the path if not. Call it before expensive work."""
    p = Path(os.path.realpath(os.fspath(path)))
    here = p
    while True:
        try:
            st = os.stat(here)
            break
        except FileNotFoundError:
            here = here.parent  # the root folder exists: this ends
        except OSError as exc:
            raise error(f"cannot write into folder '{path}': {reason(exc)}") from exc
    if not stat.S_ISDIR(st.st_mode):
        raise error(f"cannot write into folder '{path}': '{here}' is not a folder")
    with temp_file(here / "workcell", ".probe", path, error, "write into folder"):
        pass
    return p


def make_folder(path: str | os.PathLike, *, error: Error = WorkcellError) -> Path:
    """Create folder ``path`` and its parents when missing; ``error`` naming the path if not."""
    p = Path(path)
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise error(f"cannot create folder '{path}': {reason(exc)}") from exc
    return p


def write_files(
    folder: str | os.PathLike, files: dict[str, bytes], *, error: Error = WorkcellError
) -> None:
    """Write ``files`` (relative name -> bytes) into ``folder``, each atomically, creating
    the folders on the way; ``error`` naming the path on any file-system failure."""
    out = Path(folder)
    for name, data in files.items():
        make_folder((out / name).parent, error=error)
        atomic_write_bytes(out / name, data, error=error)


# ------------------------------------------------------------------ reading
def read_bytes(
    path: str | os.PathLike,
    *,
    what: str = "file",
    error: Error = WorkcellError,
    root: str | os.PathLike | None = None,
) -> bytes:
    """The bytes of regular file ``path``, at most ``max_file_bytes`` (:mod:`workcell.limits`).

    ``root`` (default: the root of :func:`workcell.confine.confined` in force, if any):
    the file must lie inside it (checked on the name before anything is opened, with a
    message that never tells whether a file outside exists, and again on the file
    opened). A folder, FIFO, socket or device is refused (``error``) before it is opened;
    the open never blocks (``O_NONBLOCK``) and the file opened is checked again (a FIFO
    swapped in between is refused, not waited on). A larger file raises LimitError before
    it is read; ``error`` for a file that cannot be read.
    """
    bound = limits.current().max_file_bytes
    root = confine.current_root() if root is None else root
    name = _name(path, f"read {what}", error)
    if root is not None:
        why = leaves_root(name, root)
        if why is not None:
            raise error(f"cannot read {what} '{path}': {why}")
    try:
        st = os.stat(name)
    except OSError as exc:
        raise error(f"cannot read {what} '{path}': {reason(exc)}") from None
    _regular(st, path, what, error)
    limits.check("max_file_bytes", st.st_size, f"{what} '{path}'")
    try:
        fd = os.open(name, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY | os.O_CLOEXEC)
    except OSError as exc:
        raise error(f"cannot read {what} '{path}': {reason(exc)}") from exc
    try:
        st = os.fstat(fd)
        _regular(st, path, what, error)
        if root is not None:
            why = confine.opened_leaves_root(fd, name, root)
            if why is not None:
                raise error(f"cannot read {what} '{path}': {why}")
        limits.check("max_file_bytes", st.st_size, f"{what} '{path}'")
        with os.fdopen(os.dup(fd), "rb") as f:
            data = f.read(bound + 1)
    except OSError as exc:
        raise error(f"cannot read {what} '{path}': {reason(exc)}") from exc
    finally:
        os.close(fd)
    limits.check("max_file_bytes", len(data), f"{what} '{path}' (read stopped there)")
    return data


def _regular(st: os.stat_result, path: object, what: str, error: Error) -> None:
    """``error`` unless ``st`` is a regular file's."""
    if stat.S_ISREG(st.st_mode):
        return
    kind = "a folder" if stat.S_ISDIR(st.st_mode) else file_kind(st.st_mode)
    raise error(f"cannot read {what} '{path}': it is {kind}, not a regular file")


def read_text(path: str | os.PathLike, *, what: str = "file", error: Error = WorkcellError) -> str:
    """The UTF-8 text of ``path`` (bounded as :func:`read_bytes`)."""
    data = read_bytes(path, what=what, error=error)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise error(f"{what} '{path}' is not UTF-8 text") from None


def load_json(path: str | os.PathLike, *, what: str = "file", error: Error = WorkcellError) -> Any:
    """Parse the JSON file ``path`` (bounded as :func:`read_bytes`). A file that does not
    parse (bad syntax, nesting too deep for the parser, an integer of more
    than 4300 digits) raises ``error`` saying where, never quoting the file."""
    text = read_text(path, what=what, error=error)
    where = f"{what} '{path}'"
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise error(
            f"{where} is not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})"
        ) from None
    except RecursionError:
        raise error(f"{where} is not a workcell file: its JSON is nested too deeply") from None
    except ValueError as exc:
        msg = str(exc)
        why = "an integer has more than 4300 digits" if "digits" in msg else msg.split(";")[0]
        raise error(f"{where} is not valid JSON: {why}") from None
