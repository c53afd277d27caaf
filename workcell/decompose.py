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
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import trimesh

from workcell.checks import is_finite_number
from workcell.errors import GeometryError
from workcell.files import atomic_write_bytes

__all__ = ["CACHE_ENV", "DEFAULT_CONCAVITY", "cache_dir", "cache_key", "decompose"]

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


def _run_coacd(mesh: trimesh.Trimesh, concavity: float, label: str) -> list[trimesh.Trimesh]:
    import coacd

    coacd.set_log_level("error")
    talk = sys.stderr.isatty()
    if talk:
        print(f"workcell: convex decomposition of {label} (CoACD)...", end="", file=sys.stderr)
    t0 = time.perf_counter()
    try:
        parts = coacd.run_coacd(
            coacd.Mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces)),
            threshold=float(concavity),
            seed=_SEED,
        )
    except (RuntimeError, ValueError):  # a mesh CoACD cannot take: the caller's hull
        parts = []
    if talk:
        print(f" {len(parts)} pieces, {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    out = []
    for v, f in parts:
        piece = trimesh.Trimesh(np.asarray(v, dtype=np.float64), np.asarray(f), process=True)
        hull = piece.convex_hull  # CoACD's pieces are hulls; make them exactly convex
        if hull.volume > _MIN_PIECE_VOLUME:
            out.append(hull)
    return out


def decompose(
    mesh: trimesh.Trimesh, concavity: float = DEFAULT_CONCAVITY, *, label: str = "a solid"
) -> list[trimesh.Trimesh]:
    """Convex pieces of the closed ``mesh`` (same frame, m), from the cache or CoACD.

    ``concavity``: the error bound in (0, 1] (module doc). ``label`` names the solid in
    the progress line shown on a terminal. An empty result (a degenerate mesh) gives the
    mesh's convex hull.
    """
    if not (is_finite_number(concavity) and 0 < float(concavity) <= 1):
        raise GeometryError(
            f"concavity (the CoACD error bound) must be a number in (0, 1], got {concavity!r}"
        )
    path = cache_dir() / f"{cache_key(mesh, concavity)}.npz"
    pieces = _load(path) if path.exists() else None
    if pieces is None:
        pieces = _run_coacd(mesh, float(concavity), label) or [mesh.convex_hull]
        _store(path, pieces)
    return pieces
