"""Planar surfaces with holes: the 2-D level of the thesis datamodel (thesis §2, §3).

A :class:`Surface` is one main contour plus any number of hole contours, all polygons in
the surface's local xy-plane (metres). Its front side faces local +z. Surfaces are
validated when created and immutable afterwards: every contour is closed (the last point
joins the first), simple (no self-intersection), of non-zero area; holes lie strictly
inside the main contour and do not touch or overlap each other. Orientation is
normalised: the main contour counter-clockwise, holes clockwise (seen from +z). The
contour checks are in :mod:`~workcell.modeller.contours`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import mapbox_earcut
import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.checks import is_finite_number
from workcell.errors import GeometryError
from workcell.modeller.contours import (
    EPS,
    check_holes,
    check_simple,
    clean_contour,
    convex_mask,
    next_points,
    ngon,
    signed_area,
)

__all__ = ["Surface"]


@dataclass(frozen=True, eq=False)
class Surface:
    """A planar polygon with holes in its local xy-plane (coordinates in metres).

    Build one with ``Surface(main, holes)`` or a constructor (:meth:`rectangle`,
    :meth:`regular_polygon`, :meth:`circle`, :meth:`from_points`). Invalid input raises
    :class:`~workcell.errors.GeometryError` naming the contour and the reason.
    """

    main: NDArray[np.float64]
    holes: tuple[NDArray[np.float64], ...] = ()
    name: str = field(default="surface", compare=False)

    def __init__(
        self, main: ArrayLike, holes: Sequence[ArrayLike] = (), *, name: str = "surface"
    ) -> None:
        m = clean_contour(main, "main contour", name)
        convex = check_simple(m, "main contour", name)
        if signed_area(m) < 0:
            m = m[::-1].copy()
        hs = []
        for i, h in enumerate(holes):
            label = f"hole {i}"
            hp = clean_contour(h, label, name)
            check_simple(hp, label, name)
            if signed_area(hp) > 0:
                hp = hp[::-1].copy()
            hs.append(hp)
        check_holes(m, hs, name)
        for a in (m, *hs):
            a.flags.writeable = False
        object.__setattr__(self, "main", m)
        object.__setattr__(self, "holes", tuple(hs))
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "_tri", None)
        object.__setattr__(self, "_convex", convex and not hs)

    # ---------------------------------------------------------------- constructors
    @classmethod
    def rectangle(
        cls, width: float, height: float, *, center: bool = False, name: str = "rectangle"
    ) -> Surface:
        """Rectangle ``width`` x ``height`` (m) with a corner at the origin, or centred."""
        if not (is_finite_number(width) and is_finite_number(height) and width > 0 and height > 0):
            raise GeometryError(
                f"surface '{name}': width and height must be numbers > 0, got {width!r}, {height!r}"
            )
        x0, y0 = (-width / 2, -height / 2) if center else (0.0, 0.0)
        pts = [(x0, y0), (x0 + width, y0), (x0 + width, y0 + height), (x0, y0 + height)]
        return cls(pts, name=name)

    @classmethod
    def regular_polygon(
        cls,
        n: int,
        radius: float,
        *,
        center: tuple[float, float] = (0.0, 0.0),
        phase: float = 0.0,
        name: str = "polygon",
    ) -> Surface:
        """Regular ``n``-gon with vertices on the circle of ``radius`` (m); first at ``phase`` (rad)."""
        return cls(ngon(n, radius, center, phase, name), name=name)

    @classmethod
    def circle(
        cls,
        radius: float,
        n: int = 32,
        *,
        center: tuple[float, float] = (0.0, 0.0),
        name: str = "circle",
    ) -> Surface:
        """Circle of ``radius`` (m) approximated by ``n`` segments, vertices on the circle."""
        return cls.regular_polygon(n, radius, center=center, name=name)

    @classmethod
    def from_points(
        cls, points: ArrayLike, holes: Sequence[ArrayLike] = (), *, name: str = "surface"
    ) -> Surface:
        """Polygon from a point list (m), optionally with hole point lists."""
        return cls(points, holes, name=name)

    @classmethod
    def convex_many(cls, contours: ArrayLike, names: Sequence[str]) -> list[Surface]:
        """Surfaces from a stack of contours (K, N, 2) (m), validated together.

        Contours that are finite, free of repeated points and strictly convex are accepted in
        one vectorised check; any other goes through the full constructor (which may
        accept it, or raise GeometryError naming it).
        """
        P = np.asarray(contours, dtype=np.float64)
        if P.ndim != 3 or P.shape[2] != 2 or P.shape[1] < 3 or len(names) != len(P):
            raise GeometryError(
                f"convex_many needs (K, N >= 3, 2) contours and K names, got {P.shape}"
            )
        step = np.abs(np.roll(P, -1, axis=1) - P).max(axis=2)
        ok = np.isfinite(P).all(axis=(1, 2)) & (step > EPS).all(axis=1) & convex_mask(P)
        area = 0.5 * (
            P[..., 0] * np.roll(P[..., 1], -1, axis=1) - np.roll(P[..., 0], -1, axis=1) * P[..., 1]
        ).sum(axis=1)
        scale = np.maximum(1.0, np.ptp(P, axis=1).max(axis=1))
        ok &= np.abs(area) > EPS * scale**2
        out = []
        for k, name in enumerate(names):
            if not ok[k]:
                out.append(cls(P[k], name=name))
                continue
            m = (P[k] if area[k] > 0 else P[k][::-1]).copy()
            m.flags.writeable = False
            s = object.__new__(cls)
            for key, value in (
                ("main", m),
                ("holes", ()),
                ("name", name),
                ("_tri", None),
                ("_convex", True),
            ):
                object.__setattr__(s, key, value)
            out.append(s)
        return out

    # ---------------------------------------------------------------- properties
    @property
    def contours(self) -> tuple[NDArray[np.float64], ...]:
        """Main contour first, then the holes (each (N, 2), m)."""
        return (self.main, *self.holes)

    @property
    def area(self) -> float:
        """Area (m^2): main contour minus holes, by the thesis's edge formula."""
        return signed_area(self.main) + sum(signed_area(h) for h in self.holes)

    @property
    def perimeter(self) -> float:
        """Total length (m) of all contours."""
        return float(sum(np.linalg.norm(next_points(c) - c, axis=1).sum() for c in self.contours))

    @property
    def n_edges(self) -> int:
        """Number of edges over all contours."""
        return sum(len(c) for c in self.contours)

    def edges(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """All contour edges as (starts, ends), each (E, 2) m, in contour orientation.

        With the main contour counter-clockwise and holes clockwise, the material lies to
        the left of every edge.
        """
        starts = np.concatenate(self.contours)
        ends = np.concatenate([next_points(c) for c in self.contours])
        return starts, ends

    def triangulate(self) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Triangulation (vertices (N, 2), faces (M, 3)), counter-clockwise seen from +z. Cached."""
        tri = self._tri  # type: ignore[attr-defined]
        if tri is None and self._convex:  # type: ignore[attr-defined]
            k = len(self.main)  # convex, counter-clockwise: a fan is a conforming triangulation
            faces = np.column_stack(
                [np.zeros(k - 2, np.int64), np.arange(1, k - 1), np.arange(2, k)]
            )
            verts = self.main.copy()
            verts.flags.writeable = False
            faces.flags.writeable = False
            tri = (verts, faces)
            object.__setattr__(self, "_tri", tri)
        if tri is None:
            verts = np.concatenate(self.contours)
            ends = np.cumsum([len(c) for c in self.contours]).astype(np.uint32)
            faces = mapbox_earcut.triangulate_float64(verts, ends).astype(np.int64).reshape(-1, 3)
            a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
            cross = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (
                c[:, 0] - a[:, 0]
            )
            faces[cross < 0] = faces[cross < 0][:, ::-1]
            faces = _conforming(verts, faces, [len(c) for c in self.contours])
            verts.flags.writeable = False
            faces.flags.writeable = False
            tri = (verts, faces)
            object.__setattr__(self, "_tri", tri)
        return tri

    # ---------------------------------------------------------------- transforms, io
    def transformed(self, matrix2d: ArrayLike, *, name: str | None = None) -> Surface:
        """This surface mapped by a 2-D affine map given as a (2, 3) or (3, 3) matrix."""
        try:
            a = np.asarray(matrix2d, dtype=np.float64)
        except (TypeError, ValueError, OverflowError) as exc:
            raise GeometryError("a 2-D affine map is a (2, 3) or (3, 3) matrix of numbers") from exc
        if a.shape not in ((2, 3), (3, 3)):
            raise GeometryError(f"a 2-D affine map is (2, 3) or (3, 3), got shape {a.shape}")
        if not np.isfinite(a).all() or (a.shape == (3, 3) and not np.array_equal(a[2], [0, 0, 1])):
            raise GeometryError("a 2-D affine map must be finite with last row (0, 0, 1)")
        if abs(np.linalg.det(a[:2, :2])) < EPS:
            raise GeometryError("the 2-D affine map is singular")

        def f(p: NDArray[np.float64]) -> NDArray[np.float64]:
            return p @ a[:2, :2].T + a[:2, 2]

        return Surface(f(self.main), [f(h) for h in self.holes], name=name or self.name)

    def to_dict(self) -> dict:
        """Plain-JSON form: ``{"main": [[x, y], ...], "holes": [[[x, y], ...], ...]}``."""
        return {"main": self.main.tolist(), "holes": [h.tolist() for h in self.holes]}

    @classmethod
    def from_dict(cls, d: dict, *, name: str = "surface") -> Surface:
        """Inverse of :meth:`to_dict`; validates like the constructor."""
        if not isinstance(d, dict) or "main" not in d:
            raise GeometryError(f"surface '{name}': expected a mapping with 'main' and 'holes'")
        return cls(d["main"], d.get("holes", []), name=name)

    def same_geometry(self, other: Surface) -> bool:
        """True when both surfaces have identical contours (exact comparison)."""
        return len(self.holes) == len(other.holes) and all(
            a.shape == b.shape and np.array_equal(a, b)
            for a, b in zip(self.contours, other.contours, strict=True)
        )

    def __repr__(self) -> str:
        return (
            f"Surface(name={self.name!r}, main={len(self.main)} points, "
            f"holes={len(self.holes)}, area={self.area:.6g} m^2)"
        )


def _conforming(
    verts: NDArray[np.float64], faces: NDArray[np.int64], sizes: list[int]
) -> NDArray[np.int64]:
    """Split triangles whose edges pass through a contour vertex (T-junctions).

    Earcut drops vertices that become collinear once holes are bridged to the main contour,
    leaving a triangle edge that runs through them; the caps of a swept solid would then
    not share edges with its side patches. Every contour edge is a triangle edge after this.
    """
    n = len(verts)
    w = np.array([n, 1], dtype=np.int64)
    offs = np.cumsum([0, *sizes[:-1]])
    ce = np.concatenate(
        [
            np.column_stack([o + np.arange(k), o + (np.arange(k) + 1) % k])
            for o, k in zip(offs, sizes, strict=True)
        ]
    )
    contour = set((np.sort(ce, axis=1) @ w).tolist())
    keys, counts = np.unique(
        np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1) @ w, return_counts=True
    )
    bad = set(keys[counts == 1].tolist()) - contour
    if not bad:
        return faces
    out: list[tuple[int, int, int]] = []
    work = [tuple(int(i) for i in f) for f in faces]
    while work:
        f = work.pop()
        for j in range(3):
            a, b, c = f[j], f[(j + 1) % 3], f[(j + 2) % 3]
            if min(a, b) * n + max(a, b) not in bad:
                continue
            d = verts[b] - verts[a]
            L2 = float(d @ d)
            r = verts - verts[a]
            t = r @ d / L2
            cr = d[0] * r[:, 1] - d[1] * r[:, 0]
            on = np.flatnonzero((t > 1e-12) & (t < 1 - 1e-12) & (np.abs(cr) <= 1e-9 * L2))
            if len(on):
                chain = [a, *on[np.argsort(t[on])].tolist(), b]
                work.extend((chain[i], chain[i + 1], c) for i in range(len(chain) - 1))
                break
        else:
            out.append(f)
    return np.array(out, dtype=np.int64).reshape(-1, 3)
