"""The pieces of a Cartesian tool path: straight lines and circular arcs.

A :class:`Piece` gives the tool point and the tool orientation as functions of a path
parameter u in [0, ``span``] (m). For every piece but a pure reorientation, u is the tool
point's arc length (``span`` = ``length``); a line whose tool point does not move (the
tool only turns) has ``length`` 0 and ``span`` = :data:`TURN_SCALE` x its angle, so it can
still be timed.

- :class:`Line`: from p0 to p1, orientation slerped from R0 to R1 (by arc length);
- :class:`Arc`: the circle through three points (:func:`arc_through`: start, via, end;
  collinear or coincident points raise ProgramError), orientation slerped.

Orientation laws extend beyond a piece's ends (:func:`slerp` with fractions outside
[0, 1]). Pieces chain into a :class:`~workcell.sim.paths.CartesianPath`, whose corners a
:class:`~workcell.sim.paths.Blend` rounds.
"""

from __future__ import annotations

import abc
import math

import numpy as np
from numpy.typing import NDArray

from workcell.errors import ProgramError
from workcell.spatial import angle_between

__all__ = ["TINY", "TURN_SCALE", "Arc", "Line", "Piece", "arc_through", "slerp"]

Array = NDArray[np.float64]
TURN_SCALE = 0.1  # m of path parameter per rad of a pure reorientation
TINY = 1e-12  # m (or rad): a length, span or angle this small counts as zero


def slerp(R0: Array, R1: Array, s: Array) -> Array:
    """Rotations (k, 3, 3) from R0 to R1 at fractions s (k,), along the shortest arc
    (fractions outside [0, 1] continue the same rotation)."""
    s = np.asarray(s, dtype=np.float64)
    Rrel = R0.T @ R1
    angle = angle_between(R0, R1)
    if angle < TINY:
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
        self.span = self.length if self.length > TINY else TURN_SCALE * self.angle
        d = p1 - p0
        self._dir = d / self.length if self.length > TINY else np.array([0.0, 0.0, 1.0])

    def points(self, u: Array) -> Array:
        if self.length <= TINY:
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
