"""Cartesian tool paths: lines, circular arcs and the blends that round their corners.

A :class:`CartesianPath` is a chain of pieces; each piece gives the tool point and the
tool orientation as functions of a path parameter u in [0, ``span``] (m). For every
piece but a pure reorientation, u is the tool point's arc length (``span`` = ``length``);
a line whose tool point does not move (the tool only turns) has ``length`` 0 and
``span`` = :data:`TURN_SCALE` x its angle, so it can still be timed.

- :class:`Line`: from p0 to p1, orientation slerped from R0 to R1 (by arc length);
- :class:`Arc`: the circle through three points (:func:`arc_through`: start, via, end;
  collinear or coincident points raise ProgramError), orientation slerped;
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

import abc
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicHermiteSpline
from scipy.spatial.transform import Rotation

from workcell.errors import ProgramError
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
TURN_SCALE = 0.1  # m of path parameter per rad of a pure reorientation
_TINY = 1e-12
# the blend's control points E + a t_a, E + b t_a with a = b / 2 and b / z by the angle
# the path turns through: chosen for a small peak curvature (within ~10 % of the best
# quintic of this shape) with a curvature that builds up gently from the lines' zero (a
# smaller a lowers the peak a little but ramps the curvature 10-20 times as steeply:
# the joints' accelerations would jump at the junctions)
_TURNS = np.radians([0.0, 30.0, 60.0, 90.0, 120.0, 150.0, 180.0])
_INNER = np.array([0.75, 0.7, 0.7, 0.65, 0.55, 0.35, 0.1])


def slerp(R0: Array, R1: Array, s: Array) -> Array:
    """Rotations (k, 3, 3) from R0 to R1 at fractions s (k,), along the shortest arc
    (fractions outside [0, 1] continue the same rotation)."""
    s = np.asarray(s, dtype=np.float64)
    Rrel = R0.T @ R1
    angle = angle_between(R0, R1)
    if angle < _TINY:
        return np.repeat(R0[None], len(s), axis=0)
    w = np.array([Rrel[2, 1] - Rrel[1, 2], Rrel[0, 2] - Rrel[2, 0], Rrel[1, 0] - Rrel[0, 1]])
    if np.linalg.norm(w) < 1e-9:  # angle ~ pi: the axis from the symmetric part
        M = (Rrel + np.eye(3)) / 2.0
        axis = M[:, int(np.argmax(np.diag(M)))]
    else:
        axis = w
    axis = axis / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    th = angle * s[:, None, None]
    R = np.eye(3) + np.sin(th) * K + (1.0 - np.cos(th)) * (K @ K)
    return R0 @ R


class Piece(abc.ABC):
    """A piece of a path: tool point and orientation as functions of u in [0, span]."""

    span: float  # m of path parameter
    length: float  # m of tool-point arc length
    angle: float  # rad of orientation change
    max_step: float = math.inf  # m: samples of a curved piece are at most this far apart

    @abc.abstractmethod
    def points(self, u: Array) -> Array:
        """Tool points (k, 3) at parameters u (k,)."""

    @abc.abstractmethod
    def rotations(self, u: Array) -> Array:
        """Tool orientations (k, 3, 3) at parameters u (any real u: the law continues)."""

    @abc.abstractmethod
    def tangents(self, u: Array) -> Array:
        """Unit tangents (k, 3) of the tool point's path at u."""

    @abc.abstractmethod
    def curvatures(self, u: Array) -> Array:
        """Curvature vectors (k, 3) at u: the principal normal over the radius (1/m)."""


class Line(Piece):
    """The straight line p0 -> p1, orientation slerped R0 -> R1 (module doc)."""

    def __init__(self, p0: Array, p1: Array, R0: Array, R1: Array) -> None:
        self.p0, self.p1, self.R0, self.R1 = p0, p1, R0, R1
        self.length = float(np.linalg.norm(p1 - p0))
        self.angle = angle_between(R0, R1)
        self.span = self.length if self.length > _TINY else TURN_SCALE * self.angle
        d = p1 - p0
        self._dir = d / self.length if self.length > _TINY else np.array([0.0, 0.0, 1.0])

    def points(self, u: Array) -> Array:
        if self.length <= _TINY:
            return np.repeat(self.p0[None], len(u), axis=0)
        return self.p0 + np.outer(u, self._dir)

    def rotations(self, u: Array) -> Array:
        return slerp(self.R0, self.R1, np.asarray(u) / self.span if self.span else 0 * u)

    def tangents(self, u: Array) -> Array:
        return np.repeat(self._dir[None], len(u), axis=0)

    def curvatures(self, u: Array) -> Array:
        return np.zeros((len(u), 3))


class Arc(Piece):
    """A circular arc: ``center``, ``radius``, in-plane unit vectors e1 (towards the
    start) and e2 (the direction of travel at the start), swept by ``sweep`` rad."""

    def __init__(
        self, center: Array, radius: float, e1: Array, e2: Array, sweep: float, R0: Array, R1: Array
    ) -> None:
        self.center, self.radius, self.e1, self.e2, self.sweep = center, radius, e1, e2, sweep
        self.R0, self.R1 = R0, R1
        self.length = self.span = radius * sweep
        self.angle = angle_between(R0, R1)
        self.max_step = 0.1 * radius  # the tangent turns <= 5.7 deg between samples

    def points(self, u: Array) -> Array:
        th = np.asarray(u) / self.radius
        return self.center + self.radius * (
            np.outer(np.cos(th), self.e1) + np.outer(np.sin(th), self.e2)
        )

    def rotations(self, u: Array) -> Array:
        return slerp(self.R0, self.R1, np.asarray(u) / self.span)

    def tangents(self, u: Array) -> Array:
        th = np.asarray(u) / self.radius
        return np.outer(-np.sin(th), self.e1) + np.outer(np.cos(th), self.e2)

    def curvatures(self, u: Array) -> Array:
        return (self.center - self.points(u)) / self.radius**2


def arc_through(
    p0: Array, via: Array, p1: Array, R0: Array, R1: Array, what: str = "move_circular"
) -> Arc:
    """The arc from p0 through ``via`` to p1 (m). ProgramError (its message starting with
    ``what``) when the three points are collinear or two of them coincide (no circle
    passes through them)."""
    a, b = via - p0, p1 - p0
    n = np.cross(a, b)
    scale = max(float(np.linalg.norm(a)), float(np.linalg.norm(b)), 1e-300)
    if np.linalg.norm(n) <= 1e-9 * scale * scale:
        raise ProgramError(
            f"{what}: the start, via and end points are collinear (or two coincide): "
            f"start ({_fmt(p0)}), via ({_fmt(via)}), end ({_fmt(p1)}) m; a circle needs "
            "three points not on one line"
        )
    # centre: p0 + x a + y b with |c - p0| = |c - via| = |c - p1|
    aa, bb, ab = a @ a, b @ b, a @ b
    det = 2.0 * (aa * bb - ab * ab)
    x = bb * (aa - ab) / det
    y = aa * (bb - ab) / det
    center = p0 + x * a + y * b
    radius = float(np.linalg.norm(p0 - center))
    e1 = (p0 - center) / radius
    normal = n / np.linalg.norm(n)  # p0 -> via -> p1 turns positively about n
    e2 = np.cross(normal, e1)

    def angle_of(p: Array) -> float:
        d = p - center
        return math.atan2(float(d @ e2), float(d @ e1)) % (2.0 * math.pi)

    sweep = angle_of(p1)
    if angle_of(via) > sweep:  # the via point lies on the other way round
        e2 = -e2
        sweep = angle_of(p1)
    return Arc(center, radius, e1, e2, sweep, R0, R1)


def _fmt(p: Array) -> str:
    return ", ".join(f"{v:.4g}" for v in p)


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
            if hi - lo > _TINY:
                u0, u1 = lo - self.starts[k], hi - self.starts[k]
                out.append(p if (u0 <= _TINY and u1 >= p.span - _TINY) else _Trimmed(p, u0, u1))
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
