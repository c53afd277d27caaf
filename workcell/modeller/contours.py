"""Polygon contours of a :class:`~workcell.modeller.surface.Surface`: cleaning and checks.

A contour is an (N, 2) array of points (metres) in the surface's plane, closed implicitly
(the last point joins the first). :func:`clean_contour` turns user input into one (drops
the closing and repeated points, refuses non-numbers and open contours),
:func:`check_simple` refuses a zero-area or self-intersecting contour,
:func:`check_holes` holes that are not strictly inside the main contour or that touch each
other, and :func:`ngon` makes a regular polygon. Every refusal is a GeometryError naming
the surface and the contour.
"""

from __future__ import annotations

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from shapely.geometry import LinearRing, Polygon

from workcell import limits
from workcell.checks import is_finite_number
from workcell.errors import GeometryError

__all__ = [
    "EPS",
    "check_holes",
    "check_simple",
    "clean_contour",
    "convex_mask",
    "next_points",
    "ngon",
    "signed_area",
    "strictly_convex",
]

EPS = 1e-12


def next_points(p: NDArray[np.float64]) -> NDArray[np.float64]:
    """The array shifted by one along axis 0 (element i is p[i + 1], cyclically); cheap roll."""
    return np.concatenate([p[1:], p[:1]])


def signed_area(p: NDArray[np.float64]) -> float:
    """Signed area (m^2) of a closed polygon, thesis formula 1/2 sum(x_i y_i+1 - x_i+1 y_i)."""
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, next_points(y)) - np.dot(next_points(x), y))


def clean_contour(points: ArrayLike, label: str, surface: str) -> NDArray[np.float64]:
    """Return an (N, 2) float array with the closing point and repeated points removed."""
    try:
        kind = np.asarray(points).dtype.kind
        p = np.array(points, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise GeometryError(f"surface '{surface}': {label} is not a list of (x, y) points") from exc
    if kind not in "iuf":
        raise GeometryError(
            f"surface '{surface}': {label} must hold numbers (not strings or bools)"
        )
    if p.ndim != 2 or p.shape[1] != 2:
        raise GeometryError(
            f"surface '{surface}': {label} must be a list of (x, y) points, got shape {p.shape}"
        )
    if not np.all(np.isfinite(p)):
        raise GeometryError(f"surface '{surface}': {label} has a non-finite coordinate")
    if len(p):
        limits.check("max_coordinate", float(np.abs(p).max()), f"surface '{surface}': {label}")
    limits.check("max_facets", len(p), f"surface '{surface}': {label} (points)")
    keep = np.ones(len(p), dtype=bool)
    if len(p) > 1:
        keep[1:] = np.any(np.abs(np.diff(p, axis=0)) > EPS, axis=1)
    p = p[keep]
    # the closing point only after dropping repeats: (..., a, a) closed twice is still closed
    if len(p) > 1 and np.abs(p[0] - p[-1]).max() <= EPS:
        p = p[:-1]
    if len(p) < 3:
        raise GeometryError(
            f"surface '{surface}': {label} is not closed: it needs at least 3 distinct points, "
            f"got {len(p)}"
        )
    return p


def convex_mask(P: NDArray[np.float64]) -> NDArray[np.bool_]:
    """For a stack of contours (K, N, 2): which are strictly convex (so simple), either winding.

    Every turn has the same sign, none doubles back (a turn of ~pi), and the turns add up
    to one loop, not two (a pentagram's all-left turns add up to 4 pi).
    """
    e = np.roll(P, -1, axis=1) - P
    en = np.roll(e, -1, axis=1)
    turn = e[..., 0] * en[..., 1] - e[..., 1] * en[..., 0]
    same = (turn > 0).all(axis=1) | (turn < 0).all(axis=1)
    angle = np.abs(np.arctan2(turn, e[..., 0] * en[..., 0] + e[..., 1] * en[..., 1]))
    return (
        same & (angle.max(axis=1) < np.pi - 1e-9) & (np.abs(angle.sum(axis=1) - 2 * np.pi) < 1e-6)
    )


def strictly_convex(p: NDArray[np.float64]) -> bool:
    """True when the contour (N, 2) is strictly convex (see :func:`convex_mask`)."""
    return bool(convex_mask(p[None])[0])


def check_simple(p: NDArray[np.float64], label: str, surface: str) -> bool:
    """Refuse a zero-area or self-intersecting contour; return whether it is strictly convex."""
    if abs(signed_area(p)) <= EPS * max(1.0, float(np.ptp(p, axis=0).max()) ** 2):
        # zero signed area: collinear (or tiny) points, or lobes that cancel (a bow-tie)
        sv = np.linalg.svd(p - p.mean(axis=0), compute_uv=False)
        if sv[-1] <= 1e-9 * sv[0] or LinearRing(p).is_simple:
            raise GeometryError(f"surface '{surface}': {label} has zero area")
    convex = strictly_convex(p)
    if not convex and not LinearRing(p).is_simple:
        reason = shapely.is_valid_reason(Polygon(p))
        raise GeometryError(f"surface '{surface}': {label} is not simple ({reason})")
    return convex


def ngon(
    n: int, radius: float, center: tuple[float, float], phase: float, name: str
) -> NDArray[np.float64]:
    """The ``n`` corners (n, 2) of a regular polygon on the circle of ``radius`` (m) about
    ``center``, the first at angle ``phase`` (rad); refuses bad arguments for surface ``name``."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 3:
        raise GeometryError(f"surface '{name}': a polygon needs an integer n >= 3 sides, got {n!r}")
    if not (is_finite_number(radius) and radius > 0):
        raise GeometryError(f"surface '{name}': radius must be a number > 0, got {radius!r}")
    if not (is_finite_number(phase) and len(center) == 2 and all(map(is_finite_number, center))):
        raise GeometryError(f"surface '{name}': center must be two numbers and phase a number")
    limits.check("max_facets", int(n), f"surface '{name}' (n = {n})")
    t = phase + 2 * np.pi * np.arange(int(n)) / int(n)
    return np.column_stack([center[0] + radius * np.cos(t), center[1] + radius * np.sin(t)])


def check_holes(main: NDArray[np.float64], holes: list[NDArray[np.float64]], name: str) -> None:
    """Refuse holes not strictly inside the main contour, or touching or overlapping each other."""
    if not holes:
        return
    outer = Polygon(main)
    polys = [Polygon(h) for h in holes]
    inside = shapely.contains_properly(outer, polys)
    for i, ok in enumerate(inside):
        if not ok:
            where = "crosses or touches" if outer.intersects(polys[i]) else "lies outside"
            raise GeometryError(
                f"surface '{name}': hole {i} {where} the main contour; holes must lie strictly inside"
            )
    tree = shapely.STRtree(polys)
    pairs = tree.query(polys, predicate="intersects")
    for i, j in pairs.T:
        if i < j:
            raise GeometryError(
                f"surface '{name}': holes {i} and {j} overlap or touch; holes must be disjoint"
            )
