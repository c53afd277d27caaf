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

:func:`decompositions` is the general form, for imported meshes (robot links,
:mod:`workcell.robots.linkshapes`): CoACD ``options`` beyond the bound (coarser searches),
a :class:`HullFit` under which a mesh's own convex hull stands for it (checked in the
child, before any CoACD), and a wall-time bound per mesh after which the mesh collides
as its hull; each result says which of these happened (:class:`Decomposition`). All of
them are part of the cache key; a mesh that ran out of time is remembered with its bound
(a larger bound tries again).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import sys
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import QhullError

from workcell import limits
from workcell.checks import is_finite_number
from workcell.errors import DegenerateError, GeometryError
from workcell.files import atomic_write_bytes
from workcell.hullfit import HullFit, hull_deviation

__all__ = [
    "CACHE_ENV",
    "COACD_OPTIONS",
    "DEFAULT_CONCAVITY",
    "Decomposition",
    "HullFit",
    "cache_dir",
    "cache_key",
    "coacd_pieces",
    "decompose",
    "decompose_many",
    "decompositions",
    "hull_deviation",
]

CACHE_ENV = "WORKCELL_COACD_CACHE"
DEFAULT_CONCAVITY = 0.05
_FORMAT = 1  # bump when the stored pieces change meaning
# CoACD's own parameters besides the bound (threshold) and the seed (coacd.run_coacd)
COACD_OPTIONS = frozenset(
    {
        "max_convex_hull", "preprocess_mode", "preprocess_resolution", "resolution",
        "mcts_nodes", "mcts_iterations", "mcts_max_depth", "pca", "merge", "decimate",
        "max_ch_vertex", "extrude", "extrude_margin", "apx_mode",
    }
)  # fmt: skip
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


@dataclass(frozen=True)
class Decomposition:
    """The collision pieces of one mesh (same frame, m) and how they came: ``method``
    "coacd" (CoACD's pieces), "hull" (the convex hull fits within the :class:`HullFit`),
    "timeout" (CoACD ran over the time bound: the hull), "unsplit" (CoACD could not take
    the mesh: the hull); ``seconds``: the wall time it took here (0 from the cache)."""

    pieces: list[trimesh.Trimesh]
    method: str
    seconds: float = 0.0


def cache_key(
    mesh: trimesh.Trimesh,
    concavity: float,
    options: Mapping[str, object] | None = None,
    hull_fit: HullFit | None = None,
) -> str:
    """The cache key of ``mesh`` decomposed with ``concavity`` (and CoACD ``options``,
    and a ``hull_fit`` test, when given) (hex SHA-256)."""
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(mesh.vertices, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(mesh.faces, dtype=np.int64).tobytes())
    params: dict[str, object] = {
        "concavity": float(concavity),
        "coacd": _coacd_version(),
        "format": _FORMAT,
    }
    if options:
        params["options"] = dict(options)
    if hull_fit is not None:
        params["hull_fit"] = [hull_fit.distance, hull_fit.volume]
    h.update(json.dumps(params, sort_keys=True).encode())
    return h.hexdigest()


def _load(path: Path) -> tuple[list[trimesh.Trimesh], str, float] | None:
    """(pieces, method, time bound) of a cache entry; None when missing or unreadable."""
    try:
        with np.load(path) as z:
            n = int(z["n"])
            pieces = [trimesh.Trimesh(z[f"v{i}"], z[f"f{i}"], process=False) for i in range(n)]
            method = str(z["method"]) if "method" in z.files else "coacd"
            bound = float(z["bound"]) if "bound" in z.files else 0.0
            return pieces, method, bound
    except (OSError, KeyError, ValueError):
        return None  # decompose again


def _store(path: Path, pieces: list[trimesh.Trimesh], method: str = "", bound: float = 0) -> None:
    arrays: dict[str, np.ndarray] = {"n": np.array(len(pieces))}
    if method:
        arrays["method"], arrays["bound"] = np.array(method), np.array(float(bound))
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
    vertices: np.ndarray,
    faces: np.ndarray,
    concavity: float,
    options: Mapping[str, object] | None = None,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """CoACD's convex pieces of one closed mesh as (vertices, faces) arrays, each made
    exactly convex (its hull), slivers dropped; [] when CoACD cannot take the mesh.
    ``options``: CoACD's other parameters (:data:`COACD_OPTIONS`).

    Native code that may abort the process: it runs in a child process
    (:mod:`workcell.native`), called through :func:`decompose_many`."""
    import coacd

    coacd.set_log_level("error")
    try:
        parts = coacd.run_coacd(
            coacd.Mesh(np.asarray(vertices), np.asarray(faces)),
            threshold=float(concavity),
            seed=_SEED,
            **dict(options or {}),
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


def link_pieces(
    vertices: np.ndarray,
    faces: np.ndarray,
    concavity: float,
    options: Mapping[str, object] | None,
    fit: tuple[float, float] | None,
) -> tuple[str, list[tuple[np.ndarray, np.ndarray]]]:
    """The child's job of :func:`decompositions`: ("hull", [the hull]) when the mesh's
    hull fits within ``fit`` (distance, volume; :class:`HullFit`), else ("coacd",
    :func:`coacd_pieces`)."""
    if fit is not None:
        mesh = trimesh.Trimesh(np.asarray(vertices), np.asarray(faces), process=True)
        try:
            far, extra = hull_deviation(mesh)
        except QhullError:  # flat: CoACD's turn (it gives [] and the caller a hull error)
            far, extra = np.inf, None
        if far <= fit[0] and (extra is None or extra <= fit[1]):
            hull = mesh.convex_hull
            return "hull", [(np.asarray(hull.vertices), np.asarray(hull.faces))]
    return "coacd", coacd_pieces(vertices, faces, concavity, options)


def _check_options(options: Mapping[str, object] | None) -> dict[str, object]:
    out = dict(options or {})
    bad = sorted(set(out) - COACD_OPTIONS)
    if bad:
        raise GeometryError(
            f"unknown CoACD option(s) {bad}; valid: {', '.join(sorted(COACD_OPTIONS))}"
        )
    for k, v in out.items():
        if not isinstance(v, bool | int | float | str) or (
            isinstance(v, float) and not is_finite_number(v)
        ):
            raise GeometryError(f"CoACD option {k} must be a finite number or a word, got {v!r}")
    return dict(sorted(out.items()))


def _check_concavity(concavity: float) -> float:
    if not (is_finite_number(concavity) and 0 < float(concavity) <= 1):
        raise GeometryError(
            f"concavity (the CoACD error bound) must be a number in (0, 1], got {concavity!r}"
        )
    return float(concavity)


def decompositions(
    meshes: Sequence[trimesh.Trimesh],
    concavity: float = DEFAULT_CONCAVITY,
    *,
    labels: Sequence[str] | None = None,
    on_start: Callable[[int], None] | None = None,
    on_done: Callable[[int, str, float], None] | None = None,
    options: Mapping[str, object] | None = None,
    hull_fit: HullFit | None = None,
    seconds: float | None = None,
) -> list[Decomposition]:
    """The collision pieces of each mesh (same frame, m) and how they came
    (:class:`Decomposition`), from the cache or from child processes on all cores
    (:mod:`workcell.native`: a crash there is a :class:`~workcell.errors.NativeCrashError`
    naming the mesh's label, a run over ``max_native_seconds`` a LimitError; nothing is
    cached then).

    ``concavity``: the error bound in (0, 1] (module doc); ``options``: CoACD's other
    parameters (:data:`COACD_OPTIONS`); ``hull_fit``: a mesh whose hull fits is its hull;
    ``seconds``: the CPU time each mesh may take (its child's, so the outcome does not
    depend on the machine's load; ``max_native_seconds`` still bounds the wall time),
    after which it is its hull (method "timeout", remembered in the cache with the bound:
    a later call with a larger bound tries again; a run over ``max_native_seconds`` of
    wall time is its hull too, not remembered);
    ``labels`` name the meshes in messages; ``on_start(n)`` is called before ``n`` meshes
    go to child processes (not when all come from the cache), ``on_done(i, label,
    seconds)`` as each of them is done.
    """
    from workcell import native

    c = _check_concavity(concavity)
    opts = _check_options(options)
    names = list(labels) if labels is not None else [f"solid {i + 1}" for i in range(len(meshes))]
    paths = [cache_dir() / f"{cache_key(m, c, opts, hull_fit)}.npz" for m in meshes]
    bound = None if seconds is None else min(float(seconds), limits.current().max_native_seconds)
    out: list[Decomposition | None] = []
    for path in paths:
        hit = _load(path) if path.exists() else None
        if hit is not None and hit[1] == "timeout" and (bound is None or bound > hit[2]):
            hit = None  # more time now: try again
        out.append(None if hit is None else Decomposition(hit[0], hit[1]))
    first: dict[Path, int] = {}  # the same mesh twice (a left and a right finger): once
    for i, d in enumerate(out):
        if d is None:
            first.setdefault(paths[i], i)
    # the largest meshes first: the cores stay busy to the end (the longest-first rule;
    # CoACD's time grows with the mesh), and the results still come back in order
    todo = sorted(first.values(), key=lambda i: -len(meshes[i].faces))
    fit = None if hull_fit is None else (float(hull_fit.distance), float(hull_fit.volume))
    jobs = [
        native.Job(
            "workcell.decompose:link_pieces",
            (np.asarray(meshes[i].vertices), np.asarray(meshes[i].faces), c, opts, fit),
            f"convex decomposition of {names[i]} (CoACD)",
        )
        for i in todo
    ]
    took: dict[int, float] = {}

    def done(k: int, label: str, s: float) -> None:
        took[k] = s
        if on_done is not None:
            on_done(todo[k], label, s)

    if jobs and on_start is not None:
        on_start(len(jobs))
    found = (
        native.run(
            jobs,
            on_done=done,
            seconds=bound,
            on_timeout=None if bound is None else lambda k, label, s: (_late(s), []),
            cpu=True,
        )
        if jobs
        else []
    )
    for k, (i, (method, arrays)) in enumerate(zip(todo, found, strict=True)):
        pieces = [trimesh.Trimesh(v, f, process=False) for v, f in arrays]
        if not pieces:
            method = "unsplit" if method == "coacd" else method
            pieces = [_hull(meshes[i], names[i])]
        if method == "wall":  # out of wall time: the machine's load, not the mesh
            method = "timeout"
        else:
            _store(paths[i], pieces, method, bound or 0.0)
        out[i] = Decomposition(pieces, method, took.get(k, 0.0))
    for i, d in enumerate(out):
        if d is None:
            out[i] = out[first[paths[i]]]
    return [d for d in out if d is not None]


def decompose_many(
    meshes: Sequence[trimesh.Trimesh],
    concavity: float = DEFAULT_CONCAVITY,
    *,
    labels: Sequence[str] | None = None,
    on_done: Callable[[int, str, float], None] | None = None,
) -> list[list[trimesh.Trimesh]]:
    """Convex pieces of each closed mesh (same frame, m), from the cache or from CoACD in
    child processes: :func:`decompositions` with CoACD's defaults, no hull test and no
    time bound but ``max_native_seconds`` (a run over it is a LimitError).

    ``concavity``: the error bound in (0, 1] (module doc); ``labels`` name the meshes in
    messages and progress; ``on_done(i, label, seconds)`` is called as each decomposition
    finishes (not for cache hits). A mesh CoACD cannot split gives its convex hull. On a
    terminal, without ``on_done``, a line says what runs and another how long it took.
    """
    c = _check_concavity(concavity)
    names = list(labels) if labels is not None else [f"solid {i + 1}" for i in range(len(meshes))]
    n = sum(not (cache_dir() / f"{cache_key(m, c)}.npz").exists() for m in meshes)
    talk = sys.stderr.isatty() and on_done is None and n > 0
    if talk:
        print(f"workcell: convex decomposition of {n} solid(s) (CoACD)...", file=sys.stderr)
    t0 = time.perf_counter()
    out = decompositions(meshes, c, labels=names, on_done=on_done)
    if talk:
        print(f"workcell: decomposed in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    return [d.pieces for d in out]


def _late(wall: float) -> str:
    """How a mesh ran out of time after ``wall`` seconds: "wall" (``max_native_seconds``)
    or "timeout" (its own CPU bound)."""
    return "wall" if wall >= limits.current().max_native_seconds else "timeout"


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
