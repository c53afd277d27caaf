"""Approximate convex decomposition of non-convex solids (CoACD), cached on disk.

MuJoCo collides a mesh through its convex hull, so a bin made with ``difference`` would
collide as a solid block. :func:`decompose` splits a closed mesh into convex pieces with
CoACD (Wei et al., "Approximate convex decomposition for 3D meshes with collision-aware
concavity and tree search", SIGGRAPH 2022): the pieces follow the surface and leave
holes, slots and cavities open.

The error bound is ``concavity`` (CoACD's ``threshold``, default
:data:`DEFAULT_CONCAVITY` = 0.05): the largest concavity a piece may keep, measured on the
part scaled to its bounding box, so roughly a fraction of the part's size (0.05 of a
20 cm bin: pieces within about a centimetre of the true surface where they must bridge a
concavity; flat walls come out exact). Smaller values give more pieces that follow the
surface more closely and take longer. The run is seeded (seed 0): the same mesh and
bound give the same pieces.

A decomposition takes seconds, so the pieces are cached by content: the key is the
SHA-256 of the mesh's vertices and faces (float64 / int64 bytes), the bound, the CoACD
version and this module's format; a cell compiles from the cache the second time. The
cache folder is ``$WORKCELL_COACD_CACHE`` if set, else ``$XDG_CACHE_HOME/workcell/coacd``
(``~/.cache/workcell/coacd``); each entry is one ``.npz`` file written atomically, and
deleting the folder only costs time. A cache that cannot be written is skipped with a
warning. Units: metres.

CoACD runs in child processes (:mod:`workcell.native`, bounded by the
``max_native_seconds`` and ``max_native_bytes`` limits): it aborts the whole process on
some inputs, and that must not end a server or a user's session. Several meshes are
decomposed on all cores at once (:func:`decompose_many`).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import QhullError

from workcell.checks import is_finite_number
from workcell.errors import DegenerateError, GeometryError
from workcell.files import atomic_write_bytes

__all__ = [
    "CACHE_ENV",
    "DEFAULT_CONCAVITY",
    "cache_dir",
    "cache_key",
    "coacd_pieces",
    "decompose",
    "decompose_many",
]

CACHE_ENV = "WORKCELL_COACD_CACHE"
DEFAULT_CONCAVITY = 0.05
_FORMAT = 1  # bump when the stored pieces change meaning
_SEED = 0
_MIN_PIECE_VOLUME = 1e-12  # m^3: slivers below this are dropped (MuJoCo refuses flat meshes)


def cache_dir() -> Path:
    """The decomposition cache folder (see the module doc); not created here."""
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "workcell" / "coacd"


def _coacd_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("coacd")
    except PackageNotFoundError:  # pragma: no cover - coacd is a dependency
        return "unknown"


def cache_key(mesh: trimesh.Trimesh, concavity: float) -> str:
    """The cache key of ``mesh`` decomposed with ``concavity`` (hex SHA-256)."""
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(mesh.vertices, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(mesh.faces, dtype=np.int64).tobytes())
    params = {"concavity": float(concavity), "coacd": _coacd_version(), "format": _FORMAT}
    h.update(json.dumps(params, sort_keys=True).encode())
    return h.hexdigest()


def _load(path: Path) -> list[trimesh.Trimesh] | None:
    try:
        with np.load(path) as z:
            n = int(z["n"])
            return [trimesh.Trimesh(z[f"v{i}"], z[f"f{i}"], process=False) for i in range(n)]
    except (OSError, KeyError, ValueError):
        return None  # missing or unreadable: decompose again


def _store(path: Path, pieces: list[trimesh.Trimesh]) -> None:
    arrays: dict[str, np.ndarray] = {"n": np.array(len(pieces))}
    for i, p in enumerate(pieces):
        arrays[f"v{i}"] = np.asarray(p.vertices, dtype=np.float64)
        arrays[f"f{i}"] = np.asarray(p.faces, dtype=np.int64)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(path, buf.getvalue())
    except OSError as exc:
        warnings.warn(
            f"cannot write the convex decomposition cache {path.parent} ({exc}); "
            f"set {CACHE_ENV} to a writable folder",
            stacklevel=3,
        )


def coacd_pieces(
    vertices: np.ndarray, faces: np.ndarray, concavity: float
) -> list[tuple[np.ndarray, np.ndarray]]:
    """CoACD's convex pieces of one closed mesh as (vertices, faces) arrays, each made
    exactly convex (its hull), slivers dropped; [] when CoACD cannot take the mesh.

    Native code that may abort the process: it runs in a child process
    (:mod:`workcell.native`), called through :func:`decompose_many`."""
    import coacd

    coacd.set_log_level("error")
    try:
        parts = coacd.run_coacd(
            coacd.Mesh(np.asarray(vertices), np.asarray(faces)),
            threshold=float(concavity),
            seed=_SEED,
        )
    except (RuntimeError, ValueError):  # a mesh CoACD cannot take: the caller's hull
        return []
    out = []
    for v, f in parts:
        piece = trimesh.Trimesh(np.asarray(v, dtype=np.float64), np.asarray(f), process=True)
        try:
            hull = piece.convex_hull  # CoACD's pieces are hulls; make them exactly convex
        except QhullError:  # a flat sliver
            continue
        if hull.volume > _MIN_PIECE_VOLUME:
            out.append((np.asarray(hull.vertices), np.asarray(hull.faces)))
    return out


def _check_concavity(concavity: float) -> float:
    if not (is_finite_number(concavity) and 0 < float(concavity) <= 1):
        raise GeometryError(
            f"concavity (the CoACD error bound) must be a number in (0, 1], got {concavity!r}"
        )
    return float(concavity)


def decompose_many(
    meshes: Sequence[trimesh.Trimesh],
    concavity: float = DEFAULT_CONCAVITY,
    *,
    labels: Sequence[str] | None = None,
    on_done: Callable[[int, str, float], None] | None = None,
) -> list[list[trimesh.Trimesh]]:
    """Convex pieces of each closed mesh (same frame, m), from the cache or from CoACD in
    child processes (:mod:`workcell.native`: a crash there is a
    :class:`~workcell.errors.NativeCrashError` naming the mesh's label, a run over
    ``max_native_seconds`` a LimitError; nothing is cached then).

    ``concavity``: the error bound in (0, 1] (module doc); ``labels`` name the meshes in
    messages and progress; ``on_done(i, label, seconds)`` is called as each decomposition
    finishes (not for cache hits). A mesh CoACD cannot split gives its convex hull.
    """
    from workcell import native

    c = _check_concavity(concavity)
    names = list(labels) if labels is not None else [f"solid {i + 1}" for i in range(len(meshes))]
    out: list[list[trimesh.Trimesh] | None] = []
    todo: list[int] = []
    for i, mesh in enumerate(meshes):
        path = cache_dir() / f"{cache_key(mesh, c)}.npz"
        pieces = _load(path) if path.exists() else None
        out.append(pieces)
        if pieces is None:
            todo.append(i)
    jobs = [
        native.Job(
            "workcell.decompose:coacd_pieces",
            (np.asarray(meshes[i].vertices), np.asarray(meshes[i].faces), c),
            f"convex decomposition of {names[i]} (CoACD)",
        )
        for i in todo
    ]
    talk = sys.stderr.isatty() and on_done is None and bool(jobs)
    if talk:
        print(f"workcell: convex decomposition of {len(jobs)} solid(s) (CoACD)...", file=sys.stderr)
    t0 = time.perf_counter()
    found = (
        native.run(jobs, on_done=None if on_done is None else _remap(on_done, todo)) if jobs else []
    )
    if talk:
        print(f"workcell: decomposed in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    for i, arrays in zip(todo, found, strict=True):
        pieces = [trimesh.Trimesh(v, f, process=False) for v, f in arrays]
        pieces = pieces or [_hull(meshes[i], names[i])]
        _store(cache_dir() / f"{cache_key(meshes[i], c)}.npz", pieces)
        out[i] = pieces
    return [p for p in out if p is not None]


def _remap(on_done: Callable[[int, str, float], None], todo: list[int]) -> Callable:
    return lambda k, label, seconds: on_done(todo[k], label, seconds)


def _hull(mesh: trimesh.Trimesh, label: str) -> trimesh.Trimesh:
    try:
        return mesh.convex_hull
    except QhullError as exc:
        raise DegenerateError(
            f"{label}: the solid is flat or degenerate (no convex hull with a volume)"
        ) from exc


def decompose(
    mesh: trimesh.Trimesh, concavity: float = DEFAULT_CONCAVITY, *, label: str = "a solid"
) -> list[trimesh.Trimesh]:
    """Convex pieces of the closed ``mesh`` (same frame, m): :func:`decompose_many` of one.

    ``concavity``: the error bound in (0, 1] (module doc). ``label`` names the solid in
    messages and in the progress line shown on a terminal. An empty result (a degenerate
    mesh) gives the mesh's convex hull.
    """
    return decompose_many([mesh], concavity, labels=[label])[0]
