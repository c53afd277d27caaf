"""Cartesian tool paths: chains of pieces, and the blends that round their corners.

A :class:`CartesianPath` is a chain of pieces (:mod:`workcell.sim.pieces`: :class:`Line`,
:class:`Arc`, and the :class:`Blend` below); each piece gives the tool point and the tool
orientation as functions of its own parameter u in [0, ``span``] (m, the tool point's arc
length but for a pure reorientation), and the path's parameter s runs through them in
order.

- :class:`Blend`: the corner path of a zone (:func:`blend_paths`): a quintic Bezier from
  the point ``zone`` before the corner on the first path (arc length) to the point
  ``zone`` after it on the second, with control points E, E + a t_a, E + b t_a,
  X - b t_b, X - a t_b, X (E, X the entry and exit points, t_a, t_b the paths' tangents
  there; a = b / 2, b <= 0.75 zone chosen by the angle of the turn for a small peak
  curvature reached gently; next to an arc the two inner points move off the tangent by
  1.25 a^2 times the arc's curvature vector). It is tangent and curvature-continuous to
  both paths (C2 in arc length: the joints' accelerations do not jump at the junctions)
  and, between two lines, it lies inside the sphere of radius ``zone`` about the corner
  (the convex hull of its control points does: they lie on the two segments from the
  corner). Its
  orientation blends the two paths' own orientation laws (each continued past its end)
  with a quintic smooth step, so the tool's turning rate is continuous too.

Orientation laws extend beyond a piece's ends (slerp with fractions outside [0, 1]);
:meth:`CartesianPath.sub` trims a path to a parameter range.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicHermiteSpline
from scipy.spatial.transform import Rotation

from workcell.sim.pieces import TINY, TURN_SCALE, Arc, Line, Piece, arc_through, slerp
from workcell.spatial import angle_between

__all__ = [
    "MAX_TURN",
    "TURN_SCALE",
    "Arc",
    "Blend",
    "CartesianPath",
    "Line",
    "Piece",
    "arc_through",
    "blend_paths",
    "slerp",
]

Array = NDArray[np.float64]
# the blend's control points E + a t_a, E + b t_a with a = b / 2 and b / z by the angle
# the path turns through: chosen for a small peak curvature (within ~10 % of the best
# quintic of this shape) with a curvature that builds up gently from the lines' zero (a
# smaller a lowers the peak a little but ramps the curvature 10-20 times as steeply:
# the joints' accelerations would jump at the junctions)
_TURNS = np.radians([0.0, 30.0, 60.0, 90.0, 120.0, 150.0, 180.0])
_INNER = np.array([0.75, 0.7, 0.7, 0.65, 0.55, 0.35, 0.1])


def _smoothstep(x: Array) -> Array:
    x = np.clip(x, 0.0, 1.0)
    return x * x * x * (10.0 + x * (-15.0 + 6.0 * x))


def _pairwise_slerp(Ra: Array, Rb: Array, w: Array) -> Array:
    rel = Rotation.from_matrix(np.einsum("kji,kjl->kil", Ra, Rb)).as_rotvec()
    return Ra @ Rotation.from_rotvec(rel * w[:, None]).as_matrix()


class Blend(Piece):
    """A zone's corner path (module doc): a quintic Bezier from E to X via the corner C,
    parameterised by arc length through a table; ``rot_a``/``rot_b`` give the two paths'
    orientation laws, ``rot_a`` of u (from the entry) and ``rot_b`` of u - span (from the
    exit)."""

    _N = 513  # arc-length table points

    def __init__(
        self,
        E: Array,
        ta: Array,
        C: Array,
        X: Array,
        tb: Array,
        zone: float,
        rot_a: Callable[[Array], Array],
        rot_b: Callable[[Array], Array],
        ka: Array | None = None,
        kb: Array | None = None,
    ) -> None:
        turn = math.acos(float(np.clip(ta @ tb, -1.0, 1.0)))
        b = float(np.interp(turn, _TURNS, _INNER)) * zone
        a = 0.5 * b
        # the inner points leave the tangents by 1.25 a^2 times the neighbours' curvature
        # vectors: the corner starts and ends with their curvature (C2 in arc length)
        da = 0.0 if ka is None else 1.25 * a * a * ka
        db = 0.0 if kb is None else 1.25 * a * a * kb
        self.P = np.array([E, E + a * ta, E + b * ta + da, X - b * tb + db, X - a * tb, X])
        t = np.linspace(0.0, 1.0, self._N)
        speed = np.linalg.norm(self._bezier(t, order=1), axis=1)
        # arc length by Simpson's rule per table interval, then a smooth map u -> t
        mid = np.linalg.norm(self._bezier(0.5 * (t[:-1] + t[1:]), order=1), axis=1)
        seg = (speed[:-1] + 4.0 * mid + speed[1:]) * (t[1] - t[0]) / 6.0
        u = np.concatenate([[0.0], np.cumsum(seg)])
        self._t_of_u = CubicHermiteSpline(u, t, 1.0 / speed)  # dt/du = 1 / |B'(t)| exactly
        self.length = self.span = float(u[-1])
        self.max_step = self.span / 64.0  # its curvature builds up fast: sample it densely
        self._rot_a, self._rot_b = rot_a, rot_b
        R = self.rotations(np.array([0.0, self.span]))
        self.angle = angle_between(R[0], R[1])

    def _bezier(self, t: Array, order: int = 0) -> Array:
        P = self.P
        for _ in range(order):  # derivative control points
            P = (len(P) - 1) * np.diff(P, axis=0)
        n = len(P) - 1
        coef = np.array([math.comb(n, k) for k in range(n + 1)], dtype=float)
        t = np.asarray(t)[:, None]
        basis = coef * t ** np.arange(n + 1) * (1.0 - t) ** (n - np.arange(n + 1))
        return basis @ P

    def points(self, u: Array) -> Array:
        return self._bezier(self._t_of_u(np.clip(u, 0.0, self.span)))

    def tangents(self, u: Array) -> Array:
        d = self._bezier(self._t_of_u(np.clip(u, 0.0, self.span)), order=1)
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    def curvatures(self, u: Array) -> Array:
        t = self._t_of_u(np.clip(u, 0.0, self.span))
        d1, d2 = self._bezier(t, order=1), self._bezier(t, order=2)
        sp2 = np.einsum("ij,ij->i", d1, d1)
        perp = d2 - (np.einsum("ij,ij->i", d2, d1) / sp2)[:, None] * d1
        return perp / sp2[:, None]

    def rotations(self, u: Array) -> Array:
        u = np.asarray(u, dtype=np.float64)
        Ra, Rb = self._rot_a(u), self._rot_b(u - self.span)
        return _pairwise_slerp(Ra, Rb, _smoothstep(u / self.span))


@dataclass(frozen=True)
class _Trimmed(Piece):
    base: Piece
    u0: float
    u1: float

    @property
    def span(self) -> float:  # type: ignore[override]
        return self.u1 - self.u0

    @property
    def length(self) -> float:  # type: ignore[override]
        return self.base.length * self.span / self.base.span if self.base.span else 0.0

    @property
    def angle(self) -> float:  # type: ignore[override]
        R = self.base.rotations(np.array([self.u0, self.u1]))
        return angle_between(R[0], R[1])

    @property
    def max_step(self) -> float:  # type: ignore[override]
        return self.base.max_step

    def points(self, u: Array) -> Array:
        return self.base.points(np.asarray(u) + self.u0)

    def rotations(self, u: Array) -> Array:
        return self.base.rotations(np.asarray(u) + self.u0)

    def tangents(self, u: Array) -> Array:
        return self.base.tangents(np.asarray(u) + self.u0)

    def curvatures(self, u: Array) -> Array:
        return self.base.curvatures(np.asarray(u) + self.u0)


class CartesianPath:
    """A chain of pieces; s in [0, ``span``] (m) runs through them in order."""

    def __init__(self, pieces: list[Piece]) -> None:
        self.pieces = [p for p in pieces if p.span > 0.0] or pieces[:1]
        spans = [p.span for p in self.pieces]
        self.starts = np.concatenate([[0.0], np.cumsum(spans)])
        self.span = float(self.starts[-1])
        self.length = float(sum(p.length for p in self.pieces))
        self.angle = float(sum(p.angle for p in self.pieces))

    def _locate(self, s: Array) -> tuple[NDArray[np.intp], Array]:
        i = np.clip(np.searchsorted(self.starts, s, side="right") - 1, 0, len(self.pieces) - 1)
        return i, s - self.starts[i]

    def _each(self, s: Array, what: str, width: tuple[int, ...]) -> Array:
        s = np.asarray(s, dtype=np.float64)
        i, u = self._locate(s)
        out = np.empty((len(s), *width))
        for k in np.unique(i):
            sel = i == k
            out[sel] = getattr(self.pieces[k], what)(u[sel])
        return out

    def points(self, s: Array) -> Array:
        """Tool points (k, 3) at path parameters s."""
        return self._each(np.clip(s, 0.0, self.span), "points", (3,))

    def rotations(self, s: Array) -> Array:
        """Tool orientations (k, 3, 3) at s; beyond the ends the end pieces' laws go on."""
        return self._each(s, "rotations", (3, 3))

    def tangents(self, s: Array) -> Array:
        """Unit tangents (k, 3) at s."""
        return self._each(np.clip(s, 0.0, self.span), "tangents", (3,))

    def curvatures(self, s: Array) -> Array:
        """Curvature vectors (k, 3) at s (1/m, towards the centre of curvature)."""
        return self._each(np.clip(s, 0.0, self.span), "curvatures", (3,))

    def poses(self, s: Array) -> Array:
        """Tool poses (k, 4, 4) at s."""
        s = np.asarray(s, dtype=np.float64)
        T = np.repeat(np.eye(4)[None], len(s), axis=0)
        T[:, :3, :3] = self.rotations(np.clip(s, 0.0, self.span))
        T[:, :3, 3] = self.points(s)
        return T

    def tool_length(self, s: Array) -> Array:
        """Tool-point arc length (m) from the start to s."""
        s = np.clip(np.asarray(s, dtype=np.float64), 0.0, self.span)
        i, u = self._locate(s)
        before = np.concatenate([[0.0], np.cumsum([p.length for p in self.pieces])])
        ratio = np.array([p.length / p.span if p.span else 0.0 for p in self.pieces])
        return before[i] + u * ratio[i]

    def sub(self, a: float, b: float) -> CartesianPath:
        """The part of the path between parameters a < b."""
        out: list[Piece] = []
        for k, p in enumerate(self.pieces):
            lo, hi = max(a, self.starts[k]), min(b, self.starts[k + 1])
            if hi - lo > TINY:
                u0, u1 = lo - self.starts[k], hi - self.starts[k]
                out.append(p if (u0 <= TINY and u1 >= p.span - TINY) else _Trimmed(p, u0, u1))
        return CartesianPath(out or [_Trimmed(self.pieces[-1], 0.0, 0.0)])

    def then(self, other: CartesianPath) -> CartesianPath:
        """This path followed by ``other``."""
        return CartesianPath([*self.pieces, *other.pieces])


MAX_TURN = math.radians(170.0)  # a path turning back more sharply has no corner to round


def blend_paths(
    a: CartesianPath, b: CartesianPath, zone: float
) -> tuple[CartesianPath, float, float] | None:
    """``a`` to ``zone`` before its end, the blend, ``b`` from ``zone`` after its start
    (module doc; ``zone`` in m of arc length, at most half of each path). Returns the
    path and the parameters where the blend starts and ends, or None when the path turns
    back by more than :data:`MAX_TURN` (the tool must stop to reverse)."""
    sa, sb = a.span - zone, zone
    E, C = a.points(np.array([sa, a.span]))
    X = b.points(np.array([sb]))[0]
    ta, tb = a.tangents(np.array([sa]))[0], b.tangents(np.array([sb]))[0]
    if math.acos(float(np.clip(ta @ tb, -1.0, 1.0))) > MAX_TURN:
        return None
    ka, kb = a.curvatures(np.array([sa]))[0], b.curvatures(np.array([sb]))[0]
    blend = Blend(
        E, ta, C, X, tb, zone, lambda u: a.rotations(sa + u), lambda v: b.rotations(sb + v),
        ka, kb,
    )  # fmt: skip
    path = a.sub(0.0, sa).then(CartesianPath([blend])).then(b.sub(sb, b.span))
    return path, sa, sa + blend.span
