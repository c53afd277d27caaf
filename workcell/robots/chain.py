"""Serial chains: a joint is a fixed origin transform, an axis and a kind (thesis §4.2, generalised).

Link frames. Frame 0 is the robot's base frame; link frame i is rigidly attached to the
link that joint i moves. At joint value q,

    F_i = F_{i-1} @ origin_i @ M_i(q_i)

- ``origin_i`` (4x4, rigid): where link frame i sits in link frame i-1 when q_i = 0;
- ``M_i(q)``: the joint's motion, expressed in link frame i. A revolute joint turns by q
  (rad, right-handed) about the line through ``axis_point`` (m) with direction ``axis``
  (unit); a prismatic joint translates by q (m) along ``axis``. Both vectors are given in
  link frame i (the line is the same before and after the motion).

This is the URDF joint (``<origin xyz rpy>`` = ``origin``, ``<axis>`` = ``axis``,
``axis_point`` = 0, the child link frame = link frame i) and the MJCF hinge or slide
(the body's ``pos``/``quat`` = ``origin``, the joint's ``axis`` and ``pos`` =
``axis``/``axis_point``, the body frame = link frame i). Standard and modified
Denavit-Hartenberg rows are two builders of it (:meth:`Joint.from_dh`):

- modified (Craig): ``Rx(alpha) Tx(a) Rz(theta) Tz(d)`` with theta = q + offset. The
  joint turns about z of frame i: ``origin = Rx(alpha) Tx(a) Rz(offset) Tz(d)``, axis z
  through the origin; link frame i is DH frame i.
- standard: ``A = Rz(theta) Tz(d) Tx(a) Rx(alpha)`` turns about z of frame i-1. With
  ``origin = A(q = 0)`` and the motion ``origin^-1 Rz(q) origin`` (a turn about z_{i-1}
  expressed in frame i: ``axis = R^T z``, ``axis_point = -R^T t``), link frame i is DH
  frame i again, so link solids, tools and grippers keep their DH placements.

Every motion is linear in two numbers (u, v): a turn about a unit axis a through point p
is ``R = a a^T + cos q (I - a a^T) + sin q [a]x`` with translation ``p - R p``, and a slide
is ``I + q [0 a; 0 0]``, so ``origin @ M(q) = C0 + u C1 + v C2`` with (u, v) = (cos q,
sin q) or (q, 0) (:func:`linear_terms`): batched forward kinematics is two scaled
additions per joint, then matrix products. Units: metres, radians, seconds.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.errors import GeometryError, KinematicsError
from workcell.spatial import as_transform, rot_x, rot_z, translation

__all__ = ["DH", "Joint", "joints_from_table", "linear_terms"]

Array = NDArray[np.float64]
Kind = Literal["revolute", "prismatic"]
Convention = Literal["standard", "modified"]


@dataclass(frozen=True)
class DH:
    """The Denavit-Hartenberg row a joint was built from (a record; FK never reads it).

    ``convention`` standard or modified; ``a``, ``d`` (m), ``alpha``, ``theta``, ``offset``
    (rad; ``offset`` in m for a prismatic joint, whose ``theta`` is fixed).
    """

    convention: Convention
    a: float
    alpha: float
    d: float
    theta: float
    offset: float


def _readonly(a: Array) -> Array:
    a.setflags(write=False)
    return a


def _vector3(value: ArrayLike, what: str) -> Array:
    try:
        v = np.array(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise KinematicsError(f"{what} must be 3 finite numbers, got {value!r}") from exc
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise KinematicsError(f"{what} must be 3 finite numbers, got {value!r}")
    return v


@dataclass(frozen=True, eq=False)
class Joint:
    """One joint of a serial chain and the link it moves (see the module doc).

    ``kind`` revolute (q in rad) or prismatic (q in m); ``origin`` (4x4 rigid) link frame i
    in link frame i-1 at q = 0; ``axis`` (3,) the motion's direction in link frame i
    (normalised here); ``axis_point`` (3,, m) a point of a revolute joint's axis line in
    link frame i. ``limits`` (lo, hi) bound q; ``max_speed`` (rad/s or m/s),
    ``max_acceleration`` (rad/s^2 or m/s^2) and ``max_jerk`` (rad/s^3 or m/s^3) bound its
    derivatives (inf where none is known). ``dh`` records the DH row the joint was built
    from, when it was (:meth:`from_dh`).
    """

    name: str
    origin: Array = field(default_factory=lambda: np.eye(4))
    axis: Array = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    kind: Kind = "revolute"
    limits: tuple[float, float] = (-np.pi, np.pi)
    max_speed: float = float("inf")
    max_acceleration: float = float("inf")
    max_jerk: float = float("inf")
    axis_point: Array = field(default_factory=lambda: np.zeros(3))
    dh: DH | None = None

    def __post_init__(self) -> None:
        put = object.__setattr__
        if self.kind not in ("revolute", "prismatic"):
            raise KinematicsError(
                f"joint '{self.name}': kind must be revolute or prismatic, got {self.kind!r}"
            )
        try:
            lo, hi = (float(v) for v in self.limits)
        except (TypeError, ValueError) as exc:
            raise KinematicsError(
                f"joint '{self.name}': limits must be two numbers (lo, hi), got {self.limits!r}"
            ) from exc
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise KinematicsError(
                f"joint '{self.name}': limits must be finite with lo < hi, got {self.limits}"
            )
        put(self, "limits", (lo, hi))
        for what in ("max_speed", "max_acceleration", "max_jerk"):
            value = getattr(self, what)
            if not value > 0:
                raise KinematicsError(
                    f"joint '{self.name}': {what} must be > 0 (inf: no limit), got {value}"
                )
            put(self, what, float(value))
        try:
            origin = as_transform(self.origin, rigid=True, name=f"joint '{self.name}' origin")
        except GeometryError as exc:
            raise KinematicsError(str(exc)) from exc
        axis = _vector3(self.axis, f"joint '{self.name}' axis")
        norm = float(np.linalg.norm(axis))
        if not norm > 1e-9:
            raise KinematicsError(f"joint '{self.name}': axis must be a non-zero vector")
        point = _vector3(self.axis_point, f"joint '{self.name}' axis_point")
        if self.kind == "prismatic":
            point = np.zeros(3)  # a slide has no axis line, only a direction
        put(self, "origin", _readonly(origin.copy()))
        put(self, "axis", _readonly(axis / norm))
        put(self, "axis_point", _readonly(point))

    # ------------------------------------------------------------------ builders
    @classmethod
    def from_dh(
        cls,
        name: str,
        *,
        a: float = 0.0,
        alpha: float = 0.0,
        d: float = 0.0,
        theta: float = 0.0,
        offset: float = 0.0,
        kind: Kind = "revolute",
        convention: Convention = "standard",
        **limits: object,
    ) -> Joint:
        """A joint from one DH row (module doc): a, d in m; alpha, theta, offset in rad.

        A revolute joint varies theta = q + offset (``theta`` ignored), a prismatic one
        d = q + offset (``d`` ignored). ``limits``: the Joint's ``limits``, ``max_speed``,
        ``max_acceleration``, ``max_jerk``.
        """
        if convention not in ("standard", "modified"):
            raise KinematicsError(
                f"joint '{name}': convention must be standard or modified, got {convention!r}"
            )
        values = {"a": a, "alpha": alpha, "d": d, "theta": theta, "offset": offset}
        for key, v in values.items():
            if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v)):
                raise KinematicsError(
                    f"joint '{name}': DH {key} must be a finite number, got {v!r}"
                )
        rev = kind == "revolute"
        th0, d0 = (offset, d) if rev else (theta, offset)
        zpart = rot_z(th0) @ translation(0, 0, d0)  # Rz and Tz commute
        xpart = translation(a, 0, 0) @ rot_x(alpha)
        row = DH(convention, float(a), float(alpha), float(d), float(theta), float(offset))
        if convention == "modified":
            return cls(name, xpart @ zpart, (0, 0, 1), kind, dh=row, **limits)  # type: ignore[arg-type]
        F = zpart @ xpart
        R, t = F[:3, :3], F[:3, 3]
        return cls(name, F, R.T[:, 2], kind, axis_point=-R.T @ t, dh=row, **limits)  # type: ignore[arg-type]

    # ------------------------------------------------------------------ motion
    def motion(self, q: float) -> Array:
        """M(q) (4x4): the joint's motion in its own link frame (rad or m)."""
        a, p = self.axis, self.axis_point
        M = np.eye(4)
        if self.kind == "prismatic":
            M[:3, 3] = q * a
            return M
        c, s = math.cos(q), math.sin(q)
        K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
        R = np.outer(a, a) * (1.0 - c) + c * np.eye(3) + s * K
        M[:3, :3], M[:3, 3] = R, p - R @ p
        return M

    def transform(self, q: float) -> Array:
        """Link frame i in link frame i-1 at joint value q: ``origin @ motion(q)``."""
        return self.origin @ self.motion(q)

    def max_translation(self) -> float:
        """Largest distance (m) the joint's transform moves the origin of link frame i-1's
        successor, over every q (revolute) or the limits (prismatic): |translation of
        ``transform(q)``|, an exact bound used for reach estimates."""
        R, t = self.origin[:3, :3], self.origin[:3, 3]
        a = self.axis
        if self.kind == "prismatic":
            w = R @ a
            return max(float(np.linalg.norm(t + q * w)) for q in self.limits)
        p = self.axis_point
        p_perp = p - (p @ a) * a
        A = t + R @ p_perp  # the circle's centre; the moving part turns about w
        w = R @ a
        A_par = float(A @ w)
        A_perp = float(np.linalg.norm(A - A_par * w))
        return math.hypot(A_par, A_perp + float(np.linalg.norm(p_perp)))


def linear_terms(joints: Sequence[Joint]) -> tuple[Array, Array]:
    """C0 (n, 16) and C12 (n, 2, 16) with ``origin_i @ M_i(q) = C0 + u C1 + v C2`` (module doc).

    (u, v) = (cos q, sin q) for a revolute joint and (q, 0) for a prismatic one; each
    4x4 term is flattened row-major.
    """
    n = len(joints)
    C = np.zeros((n, 3, 4, 4))
    for i, j in enumerate(joints):
        a = j.axis
        M = np.zeros((3, 4, 4))
        if j.kind == "revolute":
            p = j.axis_point
            aa = np.outer(a, a)
            perp = np.eye(3) - aa
            K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
            M[0, :3, :3], M[0, :3, 3], M[0, 3, 3] = aa, p - aa @ p, 1.0
            M[1, :3, :3], M[1, :3, 3] = perp, -perp @ p
            M[2, :3, :3], M[2, :3, 3] = K, -K @ p
        else:
            M[0] = np.eye(4)
            M[1, :3, 3] = a
        C[i] = j.origin @ M
    return C[:, 0].reshape(n, 16), C[:, 1:].reshape(n, 2, 16)


def joints_from_table(
    table: Sequence[Sequence[float]],
    limits_deg: Sequence[tuple[float, float]],
    *,
    max_speed_deg: Sequence[float] | None = None,
    max_acceleration_deg: Sequence[float] | None = None,
    max_jerk_deg: Sequence[float] | None = None,
    names: Sequence[str] | None = None,
    convention: Convention = "standard",
) -> tuple[Joint, ...]:
    """Revolute joints from DH rows (a m, d m, alpha deg, offset deg), limits in degrees.

    Optional per-joint ``max_speed_deg`` (deg/s), ``max_acceleration_deg`` (deg/s^2) and
    ``max_jerk_deg`` (deg/s^3); ``names`` default to j1, j2, ...
    """

    def rad(values: Sequence[float] | None, i: int) -> float:
        return float(np.radians(values[i])) if values is not None else float("inf")

    out = []
    for i, (a, d, alpha, off) in enumerate(table):
        out.append(
            Joint.from_dh(
                names[i] if names else f"j{i + 1}",
                a=float(a),
                d=float(d),
                alpha=float(np.radians(alpha)),
                offset=float(np.radians(off)),
                convention=convention,
                limits=(float(np.radians(limits_deg[i][0])), float(np.radians(limits_deg[i][1]))),
                max_speed=rad(max_speed_deg, i),
                max_acceleration=rad(max_acceleration_deg, i),
                max_jerk=rad(max_jerk_deg, i),
            )
        )
    return tuple(out)
