"""Homogeneous transforms: 4x4 float64 numpy arrays, SI units (metres, radians).

Every transform constructor returns a fresh ``(4, 4)`` ``float64`` array ``M`` acting on
column vectors, ``p' = M @ [x, y, z, 1]``. The thesis's ways of giving a transform are all
here: SRT factors (:func:`srt`), Euler angles (:func:`euler`), axis + point + angle
(:func:`axis_angle`), three points of a rigid body at start and end
(:func:`from_point_pairs`) and a raw matrix (:func:`as_transform`).

Quaternions are ``wxyz`` (MuJoCo's order) everywhere in the package; rerun takes ``xyzw``,
and :func:`wxyz_to_xyzw` / :func:`xyzw_to_wxyz` are the one place the orders are converted.
Quarter turns (exact multiples of pi/2) of :func:`rot_x`, :func:`rot_y`, :func:`rot_z`
and :func:`srt` use exact 0/+-1 entries, so e.g. the unit cube's faces land exactly.
Validation (:func:`as_transforms`, :func:`as_transform`, :func:`is_affine`,
:func:`is_rigid`, :func:`det3`) lives in :mod:`workcell.spatial_checks` and is
re-exported here.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from workcell.errors import GeometryError
from workcell.spatial_checks import (
    _valid_single as _valid_single,  # the closed-form IK's fast check uses it from here
)
from workcell.spatial_checks import as_transform, as_transforms, det3, is_affine, is_rigid

__all__ = [
    "angle_between",
    "as_transform",
    "as_transforms",
    "axis_angle",
    "compose",
    "det3",
    "euler",
    "frame_from_points",
    "from_point_pairs",
    "identity",
    "invert",
    "is_affine",
    "is_rigid",
    "matrix_from_quat",
    "pos_quat_from_pose",
    "pose_error",
    "pose_from_pos_quat",
    "quat_from_matrix",
    "rot_x",
    "rot_y",
    "rot_z",
    "rotation_angle",
    "scaling",
    "srt",
    "transform_points",
    "transform_vectors",
    "translation",
    "wxyz_to_xyzw",
    "xyzw_to_wxyz",
]

Array = NDArray[np.float64]
_QUAT_ROT_TOL = 1e-6  # how far from orthonormal a matrix may be to take its quaternion


def _vec(value: ArrayLike, n: int, what: str) -> Array:
    v = np.asarray(value, dtype=np.float64)
    if v.shape != (n,):
        raise GeometryError(f"{what} must have {n} components, got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise GeometryError(f"{what} must be finite, got {v.tolist()}")
    return v


def _mat4(T: ArrayLike, what: str = "transform") -> Array:
    M = np.asarray(T, dtype=np.float64)
    if M.shape != (4, 4):
        raise GeometryError(f"{what} must be a (4, 4) matrix, got shape {M.shape}")
    return M


def _cos_sin(angle: float) -> tuple[float, float]:
    """cos and sin of ``angle`` (rad), exact for multiples of pi/2."""
    a = float(angle)
    if not np.isfinite(a):
        raise GeometryError(f"angle must be finite, got {a}")
    k = round(a / (np.pi / 2))
    if k != 0 and abs(a - k * (np.pi / 2)) <= 1e-15 * abs(k):
        return ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[k % 4]
    return float(np.cos(a)), float(np.sin(a))


def _rigid_from(R: ArrayLike, t: ArrayLike = (0.0, 0.0, 0.0)) -> Array:
    M = np.eye(4)
    M[:3, :3] = R
    M[:3, 3] = t
    return M


def identity() -> Array:
    """The 4x4 identity transform."""
    return np.eye(4)


def translation(x: float = 0, y: float = 0, z: float = 0) -> Array:
    """Pure translation by ``(x, y, z)`` metres."""
    return _rigid_from(np.eye(3), _vec((x, y, z), 3, "translation"))


def rot_x(angle: float) -> Array:
    """Right-hand rotation by ``angle`` radians about the x axis."""
    c, s = _cos_sin(angle)
    return _rigid_from([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(angle: float) -> Array:
    """Right-hand rotation by ``angle`` radians about the y axis."""
    c, s = _cos_sin(angle)
    return _rigid_from([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(angle: float) -> Array:
    """Right-hand rotation by ``angle`` radians about the z axis."""
    c, s = _cos_sin(angle)
    return _rigid_from([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def scaling(sx: float, sy: float | None = None, sz: float | None = None) -> Array:
    """Scale by ``(sx, sy, sz)`` (dimensionless; ``sy``, ``sz`` default to ``sx``).

    Raises GeometryError for a zero or non-finite factor (negative factors mirror).
    """
    s = _vec((sx, sx if sy is None else sy, sx if sz is None else sz), 3, "scale")
    if np.any(s == 0.0):
        raise GeometryError(f"scale factors must be non-zero, got {s.tolist()}")
    return np.diag([*s, 1.0])


def srt(
    scale: float | ArrayLike = (1, 1, 1),
    rotation: ArrayLike = (0, 0, 0),
    translation: ArrayLike = (0, 0, 0),
    *,
    degrees: bool = False,
) -> Array:
    """The thesis's SRT factors: ``M = T @ Rz @ Ry @ Rx @ S``.

    A point is first scaled by ``scale`` (one number or ``(sx, sy, sz)``), then rotated
    about the fixed x, then y, then z axes by ``rotation = (rx, ry, rz)`` (radians, or
    degrees when ``degrees=True``), then translated by ``translation`` (metres).
    """
    s = _vec(np.full(3, scale, dtype=np.float64) if np.ndim(scale) == 0 else scale, 3, "scale")
    r = _vec(rotation, 3, "rotation")
    if degrees:
        r = np.deg2rad(r)
    t = _vec(translation, 3, "translation")
    return compose(_rigid_from(np.eye(3), t), rot_z(r[2]), rot_y(r[1]), rot_x(r[0]), scaling(*s))


def euler(
    angles: ArrayLike,
    seq: str = "xyz",
    *,
    degrees: bool = False,
    translation: ArrayLike = (0, 0, 0),
) -> Array:
    """Rotation from Euler ``angles`` (rad, or deg with ``degrees``), then ``translation`` (m).

    ``seq`` follows :meth:`scipy.spatial.transform.Rotation.from_euler`: lowercase axes are
    extrinsic (fixed), uppercase intrinsic (moving), e.g. ``"xyz"`` or ``"ZYX"``.
    """
    if not (
        isinstance(seq, str)
        and 1 <= len(seq) <= 3
        and (seq.islower() or seq.isupper())
        and set(seq.lower()) <= set("xyz")
    ):
        raise GeometryError(
            f"invalid Euler sequence {seq!r}: use 1-3 of x, y, z, all lowercase (extrinsic) "
            "or all uppercase (intrinsic)"
        )
    a = _vec(np.atleast_1d(np.asarray(angles, dtype=np.float64)), len(seq), f"angles for {seq!r}")
    try:
        R = Rotation.from_euler(seq, a, degrees=degrees).as_matrix().reshape(3, 3)
    except ValueError as exc:
        raise GeometryError(f"invalid Euler sequence {seq!r}: {exc}") from exc
    return _rigid_from(R, _vec(translation, 3, "translation"))


def axis_angle(axis: ArrayLike, angle: float, point: ArrayLike = (0, 0, 0)) -> Array:
    """Right-hand rotation by ``angle`` rad about the line through ``point`` (m) along ``axis``.

    ``axis`` is normalised; a zero axis raises GeometryError.
    """
    u = _vec(axis, 3, "axis")
    n = np.linalg.norm(u)
    if n <= 1e-12:
        raise GeometryError(f"rotation axis must be non-zero, got {u.tolist()}")
    p = _vec(point, 3, "point")
    R = Rotation.from_rotvec(u / n * float(angle)).as_matrix()
    return _rigid_from(R, p - R @ p)


def frame_from_points(origin: ArrayLike, x_point: ArrayLike, xy_point: ArrayLike) -> Array:
    """Right-handed rigid frame at ``origin``, x toward ``x_point``, xy plane through ``xy_point``.

    Points in metres. Coincident or collinear points raise GeometryError.
    """
    o = _vec(origin, 3, "origin")
    a = _vec(x_point, 3, "x_point") - o
    b = _vec(xy_point, 3, "xy_point") - o
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    if min(na, nb) <= 1e-12 * max(1.0, np.abs(o).max()):
        raise GeometryError("frame points are coincident: need three distinct points")
    z = np.cross(a, b)
    if np.linalg.norm(z) <= 1e-9 * na * nb:
        raise GeometryError("frame points are collinear: the xy plane is undefined")
    x = a / na
    z /= np.linalg.norm(z)
    return _rigid_from(np.column_stack([x, np.cross(z, x), z]), o)


def from_point_pairs(start: ArrayLike, end: ArrayLike) -> Array:
    """Rigid transform ``T`` with ``T @ start[i] == end[i]`` for three body points (rows, m).

    Raises GeometryError when the triangles are not congruent within 1e-9 relative (the
    motion is not rigid) or the points are collinear.
    """
    P, Q = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
    for M, what in ((P, "start"), (Q, "end")):
        if M.shape != (3, 3) or not np.all(np.isfinite(M)):
            raise GeometryError(f"{what} must be 3 finite points (shape (3, 3)), got {M.shape}")
    pairs = ((0, 1), (1, 2), (0, 2))
    dp = np.array([np.linalg.norm(P[i] - P[j]) for i, j in pairs])
    dq = np.array([np.linalg.norm(Q[i] - Q[j]) for i, j in pairs])
    if np.abs(dp - dq).max() > 1e-9 * max(dp.max(), dq.max(), 1e-300):
        raise GeometryError(
            f"start and end points are not congruent (motion is not rigid): side lengths "
            f"{dp.tolist()} vs {dq.tolist()}"
        )
    return frame_from_points(*Q) @ invert(frame_from_points(*P))


def compose(*transforms: ArrayLike) -> Array:
    """Left-to-right product: ``compose(A, B) == A @ B``; no arguments gives the identity."""
    M = np.eye(4)
    for i, T in enumerate(transforms):
        M = M @ _mat4(T, f"transform #{i}")
    return M


def invert(T: ArrayLike) -> Array:
    """Inverse of ``T``: exact ``(R^T, -R^T t)`` when rigid, ``np.linalg.inv`` when affine.

    The general path inverts the 3x3 part, so the last row stays exactly (0, 0, 0, 1).
    """
    M = as_transform(T, name="T")
    A = M[:3, :3].T if is_rigid(M) else np.linalg.inv(M[:3, :3])
    return _rigid_from(A, -A @ M[:3, 3])


def transform_points(T: ArrayLike, points: ArrayLike) -> Array:
    """Apply ``T`` to points (m) of shape ``(3,)`` or ``(N, 3)``; the shape is kept."""
    M, p = _mat4(T), np.asarray(points, dtype=np.float64)
    if p.shape[-1:] != (3,) or p.ndim > 2:
        raise GeometryError(f"points must have shape (3,) or (N, 3), got {p.shape}")
    return p @ M[:3, :3].T + M[:3, 3]


def transform_vectors(T: ArrayLike, vectors: ArrayLike) -> Array:
    """Apply the linear part of ``T`` (no translation) to vectors ``(3,)`` or ``(N, 3)``."""
    M, v = _mat4(T), np.asarray(vectors, dtype=np.float64)
    if v.shape[-1:] != (3,) or v.ndim > 2:
        raise GeometryError(f"vectors must have shape (3,) or (N, 3), got {v.shape}")
    return v @ M[:3, :3].T


def _rotation(T_or_R: ArrayLike, what: str) -> Array:
    M = np.asarray(T_or_R, dtype=np.float64)
    if M.shape not in ((3, 3), (4, 4)):
        raise GeometryError(f"{what} must be a (3, 3) or (4, 4) matrix, got shape {M.shape}")
    R = M[:3, :3]
    if not np.all(np.isfinite(R)):
        raise GeometryError(f"{what} has non-finite entries")
    dev = float(np.abs(R.T @ R - np.eye(3)).max())
    if dev > _QUAT_ROT_TOL:
        raise GeometryError(f"{what} is not a rotation: R^T R differs from I by {dev:.1e}")
    if np.linalg.det(R) < 0:
        raise GeometryError(f"{what} is not a rotation: det(R) < 0 (a reflection)")
    return R


def quat_from_matrix(T_or_R: ArrayLike) -> Array:
    """Unit quaternion ``(w, x, y, z)`` of a rotation (3x3 or the 3x3 part of a 4x4), ``w >= 0``.

    Raises GeometryError unless the part is a rotation within 1e-6.
    """
    x, y, z, w = Rotation.from_matrix(_rotation(T_or_R, "matrix")).as_quat()
    q = np.array([w, x, y, z])
    return -q if w < 0 else q


def matrix_from_quat(q_wxyz: ArrayLike, translation: ArrayLike = (0, 0, 0)) -> Array:
    """4x4 rigid transform from quaternion ``(w, x, y, z)`` (normalised) and translation (m)."""
    q = _vec(q_wxyz, 4, "quaternion")
    n = np.linalg.norm(q)
    if n <= 1e-12:
        raise GeometryError(f"quaternion must be non-zero, got {q.tolist()}")
    R = Rotation.from_quat(wxyz_to_xyzw(q / n)).as_matrix()
    return _rigid_from(R, _vec(translation, 3, "translation"))


def _quat_array(q: ArrayLike) -> Array:
    a = np.asarray(q, dtype=np.float64)
    if a.ndim not in (1, 2) or a.shape[-1] != 4:
        raise GeometryError(f"quaternions must have shape (4,) or (N, 4), got {a.shape}")
    return a


def wxyz_to_xyzw(q: ArrayLike) -> Array:
    """Reorder quaternion(s) ``(w, x, y, z)`` -> ``(x, y, z, w)``; shape (4,) or (N, 4)."""
    return np.roll(_quat_array(q), -1, axis=-1)


def xyzw_to_wxyz(q: ArrayLike) -> Array:
    """Reorder quaternion(s) ``(x, y, z, w)`` -> ``(w, x, y, z)``; shape (4,) or (N, 4)."""
    return np.roll(_quat_array(q), 1, axis=-1)


def pose_from_pos_quat(pos: ArrayLike, q_wxyz: ArrayLike) -> Array:
    """4x4 pose from position (m) and quaternion ``(w, x, y, z)``."""
    return matrix_from_quat(q_wxyz, pos)


def pos_quat_from_pose(T: ArrayLike) -> tuple[Array, Array]:
    """``(position (3,) in m, quaternion (w, x, y, z) with w >= 0)`` of a rigid pose."""
    M = _mat4(T, "pose")
    return M[:3, 3].copy(), quat_from_matrix(M)


def rotation_angle(T: ArrayLike) -> float:
    """Angle (rad, in [0, pi]) of the rotation part of ``T`` (3x3 or 4x4)."""
    return float(Rotation.from_matrix(_rotation(T, "matrix")).magnitude())


def angle_between(R: ArrayLike, R_target: ArrayLike) -> float:
    """Angle (rad, in [0, pi]) of ``R^T R_target`` for two rotation matrices (3x3 or the
    rotation part of 4x4), unvalidated and fast; accurate to ~1e-16 for small angles."""
    M = np.asarray(R)[:3, :3].T @ np.asarray(R_target)[:3, :3]
    s = 0.5 * math.sqrt(
        (M[2, 1] - M[1, 2]) ** 2 + (M[0, 2] - M[2, 0]) ** 2 + (M[1, 0] - M[0, 1]) ** 2
    )
    return math.atan2(s, 0.5 * (M[0, 0] + M[1, 1] + M[2, 2] - 1.0))


def pose_error(A: ArrayLike, B: ArrayLike) -> tuple[float, float]:
    """``(position distance in m, rotation angle of A^-1 B in rad)`` between two poses."""
    MA, MB = _mat4(A, "pose A"), _mat4(B, "pose B")
    dist = float(np.linalg.norm(MA[:3, 3] - MB[:3, 3]))
    return dist, angle_between(_rotation(MA, "pose A"), _rotation(MB, "pose B"))
