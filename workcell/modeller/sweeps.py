"""Sweeps (thesis §3): translational, rotational, and along a general position/direction curve.

- :func:`extrude`: a surface (with holes) swept along a straight director: one side patch
  per contour edge (the unit square mapped onto a parallelogram) plus the two caps;
- :func:`revolve`: a profile revolved about z in ``n`` uniform steps, full or partial
  (partial sweeps are capped with the profile); each edge's patch is one planar surface
  placed ``n`` times;
- :func:`sweep`: the thesis's "PD curve" extension: a surface carried along a path of
  positions and directions, optionally scaled, with rotation-minimising frames; the sides
  are unit triangles mapped onto the swept quads.

Lengths in metres, angles in radians.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell import limits, spatial
from workcell.checks import is_finite_number
from workcell.errors import GeometryError
from workcell.modeller.model import Model
from workcell.modeller.patches import (
    UNIT_SQUARE,
    UNIT_TRIANGLE,
    build_block,
    parallelogram_transforms,
    planar_patches,
    triangle_transforms,
)
from workcell.modeller.surface import Surface

__all__ = ["extrude", "revolve", "sweep"]

_FLIP = spatial.scaling(1.0, 1.0, -1.0)


def _profile(
    model: Model, name: str, surface: Surface | str | ArrayLike
) -> tuple[Surface, Surface | str]:
    """(geometry, what build_block gets): an existing surface entity is shared by name."""
    if isinstance(surface, str):
        s = model.surface(("surface", surface))
        return s, surface
    if isinstance(surface, Surface):
        return surface, surface
    s = Surface(surface, name=f"{name}.profile")
    return s, s


def extrude(
    model: Model,
    name: str,
    surface: Surface | str | ArrayLike,
    *,
    height: float | None = None,
    direction: ArrayLike | None = None,
    colour: ArrayLike | None = None,
) -> str:
    """Translational sweep of ``surface`` (a Surface, a surface entity's name, or points).

    Give ``height`` (m, along +z) or a ``direction`` vector (m; its length is the sweep
    length; it must leave the surface's plane). The block has m + n side patches (one
    per edge of the main contour and of the holes) and the two caps.
    """
    s, ref = _profile(model, name, surface)
    if (height is None) == (direction is None):
        raise GeometryError(f"sweep '{name}': give exactly one of height or direction")
    d = (
        np.array([0.0, 0.0, height], dtype=np.float64)
        if direction is None
        else np.asarray(direction, dtype=np.float64)
    )
    if d.shape != (3,) or not np.all(np.isfinite(d)):
        raise GeometryError(
            f"sweep '{name}': direction must be a finite 3-vector, got {direction!r}"
        )
    limits.check("max_coordinate", float(np.abs(d).max()), f"sweep '{name}': the direction")
    if abs(d[2]) <= 1e-12 * max(1.0, float(np.linalg.norm(d))):
        raise GeometryError(
            f"sweep '{name}': the direction {d.tolist()} lies in the surface's plane (z = 0)"
        )
    limits.check("max_facets", 4 * s.n_edges, f"sweep '{name}'")
    a2, b2 = s.edges()
    a = np.column_stack([a2, np.zeros(len(a2))])
    e1 = np.column_stack([b2 - a2, np.zeros(len(a2))])
    if d[2] > 0:
        sides = parallelogram_transforms(a, e1, np.broadcast_to(d, e1.shape))
        caps = np.stack([_FLIP, spatial.translation(*d)])
    else:  # sweeping below the plane: every patch turned over
        sides = parallelogram_transforms(a + e1, -e1, np.broadcast_to(d, e1.shape))
        caps = np.stack([np.eye(4), spatial.translation(*d) @ _FLIP])
    return build_block(
        model,
        name,
        {"side": Surface(UNIT_SQUARE, name=f"{name}.side"), "profile": ref},
        [("side", sides), ("profile", caps)],
        colour=colour,
    )


def revolve(
    model: Model,
    name: str,
    profile: Surface | str | ArrayLike,
    *,
    n: int = 32,
    angle: float = 2 * np.pi,
    colour: ArrayLike | None = None,
) -> str:
    """Rotational sweep about z of a closed profile given in the (r, z) half-plane, r >= 0.

    ``profile`` points are (r, z) pairs (m) in the xz-plane (a Surface, a surface name, or
    points); points on the axis (r = 0) are allowed. The profile is revolved by ``angle``
    (rad, in (0, 2 pi]) in ``n`` equal steps; a partial sweep is closed by two profile caps.
    """
    s, ref = _profile(model, name, profile)
    if not (is_finite_number(angle) and 0 < angle <= 2 * np.pi + 1e-12):
        raise GeometryError(f"sweep '{name}': angle must be in (0, 2 pi] rad, got {angle!r}")
    full = angle >= 2 * np.pi - 1e-12
    n_min = 3 if full else 1
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < n_min:
        raise GeometryError(f"sweep '{name}': n must be an integer >= {n_min}, got {n!r}")
    limits.check("max_facets", 2 * s.n_edges * int(n) + 2 * s.n_edges, f"sweep '{name}' (n = {n})")
    if min(c[:, 0].min() for c in s.contours) < -1e-12:
        raise GeometryError(f"sweep '{name}': the profile crosses the axis (r < 0); keep r >= 0")
    step = 2 * np.pi / n if full else angle / n
    Rz = np.stack([spatial.rot_z(k * step) for k in range(int(n))])
    c, sn = np.cos(step), np.sin(step)

    def at(r: float, z: float, k: int) -> NDArray[np.float64]:
        return np.array([r * (c if k else 1.0), r * (sn if k else 0.0), z])

    surfaces: dict[str, Surface | str] = {}
    relations: list[tuple[str, NDArray[np.float64]]] = []
    a2, b2 = s.edges()
    # radii within the weld tolerance of the axis are on the axis (else the mesh tears there)
    on_axis = 1e-9 * max(1.0, max(float(np.ptp(c, axis=0).max()) for c in s.contours))
    a2, b2 = a2.copy(), b2.copy()
    a2[a2[:, 0] <= on_axis, 0] = 0.0
    b2[b2[:, 0] <= on_axis, 0] = 0.0
    keep = [
        i for i in range(len(a2)) if a2[i, 0] > 0 or b2[i, 0] > 0
    ]  # axis edges sweep to nothing
    # corners start with the profile edge itself (never degenerate), counter-clockwise outside
    corners = np.array([[at(*b2[i], 0), at(*a2[i], 0), at(*a2[i], 1), at(*b2[i], 1)] for i in keep])
    patches, F = planar_patches(corners, [f"{name}.edge{i}" for i in keep])
    for k, i in enumerate(keep):
        surfaces[f"edge{i}"] = patches[k]
        relations.append((f"edge{i}", Rz @ F[k]))
    if not full:
        T0 = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
        surfaces["profile"] = ref
        relations.append(("profile", np.stack([T0, spatial.rot_z(angle) @ T0 @ _FLIP])))
    return build_block(model, name, surfaces, relations, colour=colour)


def _transport_frames(
    P: NDArray[np.float64], D: NDArray[np.float64], up: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Rotation-minimising frames (K, 3, 3): columns x, y, z with z along the directions D."""
    z = D / np.linalg.norm(D, axis=1, keepdims=True)
    x0 = up - z[0] * np.dot(up, z[0])
    if np.linalg.norm(x0) < 1e-9:
        raise GeometryError("sweep: the 'up' vector is parallel to the first direction")
    R = np.zeros((len(P), 3, 3))
    x = x0 / np.linalg.norm(x0)
    for k in range(len(P)):
        if k:  # double reflection method (Wang et al. 2008)
            v1 = P[k] - P[k - 1]
            c1 = v1 @ v1
            if c1 > 0:
                xl = x - (2 / c1) * (v1 @ x) * v1
                tl = z[k - 1] - (2 / c1) * (v1 @ z[k - 1]) * v1
            else:
                xl, tl = x, z[k - 1]
            v2 = z[k] - tl
            c2 = v2 @ v2
            x = xl - (2 / c2) * (v2 @ xl) * v2 if c2 > 0 else xl
            x = x - z[k] * (x @ z[k])
            x /= np.linalg.norm(x)
        R[k] = np.column_stack([x, np.cross(z[k], x), z[k]])
    return R


def sweep(
    model: Model,
    name: str,
    surface: Surface | str | ArrayLike,
    path: ArrayLike,
    *,
    directions: ArrayLike | None = None,
    scales: ArrayLike | None = None,
    up: ArrayLike = (1.0, 0.0, 0.0),
    colour: ArrayLike | None = None,
) -> str:
    """Sweep ``surface`` along a position/direction ("PD") curve, optionally scaling it.

    ``path`` (K, 3) positions (m); ``directions`` (K, 3) the section normals (default: the
    path's tangents by finite differences); ``scales`` (K,) or (K, 2) scale factors of the
    section in its own x and y; ``up`` fixes the first section's x axis. Section k is the
    surface placed at path[k] in a rotation-minimising frame. Corners are not mitred:
    sample sharp turns densely. Check the result with ``model.validity`` (self-intersection).
    """
    s, ref = _profile(model, name, surface)
    P = np.asarray(path, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) < 2 or not np.all(np.isfinite(P)):
        raise GeometryError(f"sweep '{name}': path must be (K >= 2, 3) finite points")
    limits.check("max_coordinate", float(np.abs(P).max()), f"sweep '{name}': the path")
    limits.check("max_facets", 2 * (len(P) - 1) * s.n_edges + 2 * s.n_edges, f"sweep '{name}'")
    if directions is None:
        D = np.gradient(P, axis=0)
    else:
        D = np.asarray(directions, dtype=np.float64)
        if D.shape != P.shape:
            raise GeometryError(f"sweep '{name}': directions must have the path's shape {P.shape}")
    if (np.linalg.norm(D, axis=1) < 1e-12).any():
        raise GeometryError(f"sweep '{name}': a direction is zero (repeated path points?)")
    S = np.ones((len(P), 2)) if scales is None else np.asarray(scales, dtype=np.float64)
    if S.ndim == 1:
        S = np.column_stack([S, S])
    if S.shape != (len(P), 2) or not (S > 0).all():
        raise GeometryError(
            f"sweep '{name}': scales must be positive, (K,) or (K, 2) for K = {len(P)}"
        )
    R = _transport_frames(P, D, np.asarray(up, dtype=np.float64))
    A = np.zeros((len(P), 4, 4))  # section placements: translate, rotate, scale in-plane
    A[:, :3, :3] = R * np.concatenate([S, np.ones((len(P), 1))], axis=1)[:, None, :]
    A[:, :3, 3], A[:, 3, 3] = P, 1.0
    a2, b2 = s.edges()
    a = np.column_stack([a2, np.zeros(len(a2)), np.ones(len(a2))])
    b = np.column_stack([b2, np.zeros(len(b2)), np.ones(len(b2))])
    pa = np.einsum("kij,ej->kei", A[:, :3], a)  # (K, E, 3) edge starts per section
    pb = np.einsum("kij,ej->kei", A[:, :3], b)
    # quad (a_k, b_k, b_k+1, a_k+1) outward for a CCW main contour: split into two triangles
    t1 = triangle_transforms(pa[:-1].reshape(-1, 3), pb[:-1].reshape(-1, 3), pb[1:].reshape(-1, 3))
    t2 = triangle_transforms(pa[:-1].reshape(-1, 3), pb[1:].reshape(-1, 3), pa[1:].reshape(-1, 3))
    caps = np.stack([A[0] @ _FLIP, A[-1]])
    return build_block(
        model,
        name,
        {"tri": Surface(UNIT_TRIANGLE, name=f"{name}.tri"), "profile": ref},
        [("tri", np.concatenate([t1, t2])), ("profile", caps)],
        colour=colour,
    )
