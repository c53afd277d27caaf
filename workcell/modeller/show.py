"""Readable text views of the datamodel (the thesis's ``show`` query, two levels of detail)."""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

if TYPE_CHECKING:
    from workcell.modeller.entities import _Entity
    from workcell.modeller.model import Model

__all__ = ["describe_transform", "show_entity", "show_model"]


def describe_transform(T: NDArray[np.float64]) -> str:
    """Short text for a 4x4 transform: translation (m), rotation (xyz extrinsic, deg), scale."""
    A = T[:3, :3]
    scale = np.linalg.norm(A, axis=0)
    parts = []
    if np.abs(T[:3, 3]).max() > 0:
        parts.append("T=({:.6g}, {:.6g}, {:.6g})".format(*T[:3, 3]))
    R = A / scale
    if np.linalg.det(R) < 0:
        parts.append("reflected")
        R = R @ np.diag([1.0, 1.0, -1.0])
    if np.abs(R.T @ R - np.eye(3)).max() < 1e-9:
        with warnings.catch_warnings():  # gimbal lock (e.g. R_y = -90): scipy still returns
            warnings.simplefilter("ignore", UserWarning)  # angles that rebuild R exactly
            ang = Rotation.from_matrix(R).as_euler("xyz", degrees=True)
        if np.abs(ang).max() > 1e-9:
            parts.append("R=({:.6g}, {:.6g}, {:.6g}) deg".format(*ang))
    else:
        parts.append("sheared")
    if np.abs(scale - 1).max() > 1e-12:
        parts.append("S=({:.6g}, {:.6g}, {:.6g})".format(*scale))
    return " ".join(parts) or "identity"


def _head(e: _Entity) -> str:
    bits = [f"{e.level} {e.name}", f"pointed_by={e.pointed_by}"]
    if e.surface is not None:
        s = e.surface
        bits.append(f"{len(s.main)} points, {len(s.holes)} holes, area {s.area:.6g} m^2")
    else:
        kind = f"{e.boolean} of " if e.boolean else ""
        bits.append(f"{kind}{e.rels.n} relation{'s' * (e.rels.n != 1)}")
    if e.colour is not None:
        bits.append("colour=({:.3g}, {:.3g}, {:.3g}, {:.3g})".format(*e.colour))
    if e.movable:
        bits.append("movable")
    return ", ".join(bits)


def show_entity(model: Model, e: _Entity, *, detail: bool = False) -> str:
    """One entity: summary line, its users, and with ``detail`` every relation."""
    lines = [_head(e)]
    if e.users:
        lines.append("  used by: " + ", ".join(f"{u.label} x{k}" for u, k in e.users.items()))
    if detail and e.surface is not None:
        for i, c in enumerate(e.surface.contours):
            label = "main" if i == 0 else f"hole {i - 1}"
            pts = " ".join(f"({x:.6g}, {y:.6g})" for x, y in c[:12])
            lines.append(f"  {label}: {pts}{' ...' if len(c) > 12 else ''}")
    if detail:
        limit = 200
        for i in range(min(e.rels.n, limit)):
            t = e.rels.targets[i]
            lines.append(
                f"  {e.rels.names[i]} -> {t.level} {t.name}: {describe_transform(e.rels.T[i])}"
            )
        if e.rels.n > limit:
            lines.append(f"  ... and {e.rels.n - limit} more relations")
    return "\n".join(lines)


def show_model(model: Model, *, detail: bool = False) -> str:
    """All levels: counts, and one summary line per entity (with ``detail``, per relation too)."""
    lines = []
    for level, names in model.list().items():
        lines.append(f"{level}s ({len(names)}):")
        for n in names:
            text = show_entity(model, model._get((level, n)), detail=detail)
            lines.extend("  " + ln for ln in text.splitlines())
    return "\n".join(lines)
