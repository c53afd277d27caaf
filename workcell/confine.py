"""Confinement: file names kept inside a root folder (the server's ``--root``).

- :func:`resolve_inside`: a file name taken relative to a root folder, refused when it
  could lead outside it (absolute, ``~``, ``..``, hidden names, symbolic links, and
  regular files with more than one hard link: a hard link planted in the root may be
  the same file as one anywhere else on the file system);
- :func:`leaves_root`: why a path may lead outside a root (None: it does not);
- :func:`confined`: a block (this thread or task) in which every file read through
  :func:`workcell.files.read_bytes` must lie inside the root; :func:`current_root` the
  root in force. A server session runs each command in such a block, so a file reached
  by a name the command did not check itself (a robot file's mesh, a cell's robot file)
  is held to the same rule;
- :func:`opened_leaves_root`: the check *after* opening: where the kernel says the open
  file is (``/proc/self/fd``), so a symbolic link swapped in between the check of the
  name and the open cannot lead outside.

Every reason is worded the same whether or not a file outside the root exists.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import stat
from collections.abc import Iterator
from pathlib import Path

from workcell.errors import WorkcellError

__all__ = [
    "confined",
    "current_root",
    "leaves_root",
    "opened_leaves_root",
    "resolve_inside",
]

Error = type[WorkcellError]

_root: contextvars.ContextVar[str | None] = contextvars.ContextVar("workcell_root", default=None)

OUTSIDE = "it leads outside the root folder"


@contextlib.contextmanager
def confined(root: str | os.PathLike | None) -> Iterator[None]:
    """Within the block (this thread or task), files read by name must lie inside ``root``
    (None: no confinement is added; an outer one stays)."""
    if root is None:
        yield
        return
    token = _root.set(os.path.realpath(os.fspath(root)))
    try:
        yield
    finally:
        _root.reset(token)


def current_root() -> str | None:
    """The root folder of the innermost :func:`confined` block (resolved), or None."""
    return _root.get()


def resolve_inside(root: str | os.PathLike, name: object, *, error: Error = WorkcellError) -> Path:
    """The file ``name`` (relative) inside folder ``root``, symbolic links resolved.

    Refused (``error``): a name that is not a non-empty string, absolute paths, ``~``,
    ``..``, hidden names (a part starting with '.'), NUL characters, and anything that
    resolves outside ``root`` through a symbolic link. The message is the same whether
    or not the file exists.
    """
    if not isinstance(name, str) or not name.strip():
        raise error(f"a file name must be a non-empty string, got {name!r}")
    try:
        os.fsencode(name)
    except UnicodeEncodeError:
        raise error(f"file name {name!r} refused: it holds a lone surrogate") from None
    rule = (
        "file names are relative to the server's root folder: no absolute paths, '~', "
        "'..' or hidden ('.') names"
    )
    parts = Path(name).parts
    if (
        "\x00" in name
        or os.path.isabs(name)
        or name.startswith("~")
        or any(part == ".." or part.startswith(".") for part in parts)
    ):
        raise error(f"file name {name!r} refused: {rule}")
    full = os.path.realpath(os.path.join(os.path.realpath(os.fspath(root)), name))
    why = leaves_root(full, root)
    if why is not None:
        raise error(f"file name {name!r} refused: {why}")
    return Path(full)


def _inside(full: str, real_root: str) -> bool:
    return os.path.commonpath([full, real_root]) == real_root


def _links(st: os.stat_result) -> str | None:
    if stat.S_ISREG(st.st_mode) and st.st_nlink > 1:
        return (
            f"it is a file with {st.st_nlink} hard links, which may lead outside the "
            "root folder; copy the file into the root instead"
        )
    return None


def leaves_root(path: str | os.PathLike, root: str | os.PathLike) -> str | None:
    """Why ``path`` may lead outside the folder ``root`` (None: it does not).

    ``path`` resolved through symbolic links must lie inside ``root`` (resolved too); an
    existing regular file must have one hard link only (another name of the same file
    may lie anywhere on the file system, and nothing tells where). The reasons never
    say whether a file outside the root exists.
    """
    real_root = os.path.realpath(os.fspath(root))
    full = os.path.realpath(os.fspath(path))
    if not _inside(full, real_root):
        return OUTSIDE
    try:
        st = os.stat(full)
    except OSError:
        return None  # not there (yet): reading it fails later, writing it creates it
    return _links(st)


def opened_leaves_root(fd: int, path: str | os.PathLike, root: str | os.PathLike) -> str | None:
    """Why the file open as ``fd`` (opened by the name ``path``) may lie outside ``root``.

    Where the file is comes from the kernel (``/proc/self/fd/N``); without it, the name
    is resolved again and must still name the same file. A regular file must have one
    hard link (see :func:`leaves_root`).
    """
    real_root = os.path.realpath(os.fspath(root))
    st = os.fstat(fd)
    try:
        where = os.readlink(f"/proc/self/fd/{fd}")
    except OSError:
        where = os.path.realpath(os.fspath(path))
        try:
            again = os.stat(where)
        except OSError:
            return OUTSIDE
        if (again.st_dev, again.st_ino) != (st.st_dev, st.st_ino):
            return OUTSIDE
    if not _inside(where, real_root):
        return OUTSIDE
    return _links(st)
