"""Validation of 4x4 transforms: is a matrix (or a stack) affine, rigid, usable?

:func:`as_transforms` is the one check every transform a user gives goes through (a fast
path for one 4x4 in plain floats, a vectorised path for stacks that says what is wrong);
:func:`as_transform` names one matrix, :func:`is_affine` / :func:`is_rigid` answer yes or
no, :func:`det3` is the determinants of a stack's 3x3 parts. All are re-exported by
:mod:`workcell.spatial`, where the rest of the transform algebra lives.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell import limits
from workcell.errors import GeometryError

__all__ = ["as_transform", "as_transforms", "det3", "is_affine", "is_rigid"]

Array = NDArray[np.float64]
_LAST_ROW = np.array([0.0, 0.0, 0.0, 1.0])
_LAST_ROW_LIST = [0.0, 0.0, 0.0, 1.0]


def det3(T: ArrayLike) -> Array:
    """Determinants of the upper 3x3 blocks of an (N, 4, 4) or (N, 3, 3) stack, as a . (b x c).

    Cheaper than ``np.linalg.det`` on small stacks, which is called once per block here.
    """
    A = np.asarray(T, dtype=np.float64)
    a, b, c = A[:, :3, 0], A[:, :3, 1], A[:, :3, 2]
    return (
        a[:, 0] * (b[:, 1] * c[:, 2] - b[:, 2] * c[:, 1])
        - a[:, 1] * (b[:, 0] * c[:, 2] - b[:, 2] * c[:, 0])
        + a[:, 2] * (b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0])
    )


def as_transforms(transforms: ArrayLike, *, rigid: bool = False, what: str = "transform") -> Array:
    """Validate one 4x4 (or 3x4) matrix or an (N, 4, 4) stack; return a float64 copy.

    Checks: numbers (not strings or bools), finite, every entry of the top three rows at
    most ``max_coordinate`` (:mod:`workcell.limits`, 1e6: LimitError), last row
    ``(0, 0, 0, 1)`` within 1e-12, non-singular upper 3x3 (``|det| > 1e-12``); with
    ``rigid=True`` also orthonormal with ``det = +1`` within 1e-9. Raises GeometryError
    starting with ``what`` (and, for a stack, the index of the first bad matrix) and
    giving the reason. The returned last rows are exactly (0, 0, 0, 1).
    """
    try:
        numeric = (
            transforms.dtype.kind in "iuf"
            if isinstance(transforms, np.ndarray)
            else np.asarray(transforms).dtype.kind in "iuf"
        )
        A = np.array(transforms, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise GeometryError(f"{what} is not a numeric 4x4 matrix") from exc
    if not numeric:
        raise GeometryError(f"{what} is not a numeric 4x4 matrix (numbers, not strings or bools)")
    single = A.ndim == 2
    if single and A.shape == (3, 4):
        A = np.vstack([A, _LAST_ROW])
    if A.shape == (4, 4) and _valid_single(A.tolist(), rigid):  # the common case, in floats
        A[3] = _LAST_ROW
        return A
    if single:
        A = A[None]
    if A.ndim != 3 or A.shape[1:] != (4, 4):
        raise GeometryError(f"{what} must be 4x4 or 3x4, got shape {np.shape(transforms)}")

    def fail(bad: NDArray[np.bool_], reason: str | Callable[[int], str]) -> None:
        i = int(np.argmax(bad))
        at = "" if single else f" (matrix {i})"
        raise GeometryError(f"{what}{at} {reason(i) if callable(reason) else reason}")

    finite = np.isfinite(A).all(axis=(1, 2))
    if not finite.all():
        fail(~finite, "is not affine: it has non-finite entries (NaN or inf)")
    if len(A):
        limits.check("max_coordinate", float(np.abs(A[:, :3]).max()), f"{what}: an entry")
    off = np.abs(A[:, 3] - _LAST_ROW).max(axis=1) > 1e-12
    if off.any():
        fail(off, lambda i: f"is not affine: its last row must be (0, 0, 0, 1), got {A[i, 3]}")
    A[:, 3] = _LAST_ROW
    det = det3(A)
    if (np.abs(det) <= 1e-12).any():
        fail(np.abs(det) <= 1e-12, lambda i: f"is singular: det of its 3x3 part is {det[i]:.3g}")
    if rigid:
        R = A[:, :3, :3]
        dev = np.abs(np.matmul(R.transpose(0, 2, 1), R) - np.eye(3)).max(axis=(1, 2))
        if (dev > 1e-9).any():
            fail(dev > 1e-9, lambda i: f"is not rigid: R^T R differs from I by {dev[i]:.1e}")
        if (np.abs(det - 1.0) > 1e-9).any():
            fail(np.abs(det - 1.0) > 1e-9, lambda i: f"is not rigid: det(R) = {det[i]:.6g}, not +1")
    return A[0] if single else A


def _valid_single(rows: list[list[float]], rigid: bool) -> bool:
    """Fast check of one 4x4 (nested lists) against :func:`as_transforms`' rules; False
    sends it to the vectorised path, which says what is wrong."""
    r0, r1, r2, last = rows
    (a, b, c, x), (d, e, f, y), (g, h, i, z) = r0, r1, r2
    if not math.isfinite(sum(r0) + sum(r1) + sum(r2) + sum(last)):
        return False  # an entry is not finite (or so large that the sum overflows)
    bound = limits.current().max_coordinate
    if max(a, b, c, x, d, e, f, y, g, h, i, z) > bound:
        return False
    if min(a, b, c, x, d, e, f, y, g, h, i, z) < -bound:
        return False
    if last != _LAST_ROW_LIST and (
        max(abs(last[0]), abs(last[1]), abs(last[2]), abs(last[3] - 1.0)) > 1e-12
    ):
        return False
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    if abs(det) <= 1e-12:
        return False
    if not rigid:
        return True
    dev = max(
        abs(a * a + d * d + g * g - 1.0),
        abs(b * b + e * e + h * h - 1.0),
        abs(c * c + f * f + i * i - 1.0),
        abs(a * b + d * e + g * h),
        abs(a * c + d * f + g * i),
        abs(b * c + e * f + h * i),
    )
    return dev <= 1e-9 and abs(det - 1.0) <= 1e-9


def as_transform(matrix: ArrayLike, *, rigid: bool = False, name: str = "transform") -> Array:
    """Validate a raw 4x4 (or 3x4) matrix and return a float64 copy (see :func:`as_transforms`).

    Raises GeometryError naming ``name`` and the reason.
    """
    M = as_transforms(matrix, rigid=rigid, what=f"transform {name!r}")
    if M.ndim != 2:
        raise GeometryError(f"transform {name!r} must be 4x4 or 3x4, got shape {M.shape}")
    return M


def is_affine(T: ArrayLike, tol: float = 1e-12) -> bool:
    """True when ``T`` is 4x4, finite, has last row (0,0,0,1) and ``|det(3x3)| > tol``."""
    M = np.asarray(T, dtype=np.float64)
    if M.shape != (4, 4) or not np.all(np.isfinite(M)):
        return False
    return bool(np.abs(M[3] - _LAST_ROW).max() <= tol and abs(np.linalg.det(M[:3, :3])) > tol)


def is_rigid(T: ArrayLike, tol: float = 1e-9) -> bool:
    """True when ``T`` is affine with an orthonormal, det +1 rotation part (within ``tol``)."""
    if not is_affine(T, min(tol, 1e-12)):
        return False
    R = np.asarray(T, dtype=np.float64)[:3, :3]
    orthonormal = np.abs(R.T @ R - np.eye(3)).max() <= tol
    return bool(orthonormal and abs(np.linalg.det(R) - 1.0) <= tol)
