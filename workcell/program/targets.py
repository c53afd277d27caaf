"""Tool targets of the Cartesian moves: a world pose, or a pose built from a part.

A :class:`Target` is resolved to a 4x4 world pose of the robot's tool when its command
runs (the part may have moved since the program was written):

- ``matrix``: the whole pose (4x4, m);
- else the position is ``position`` (m, world), or the part's anchor when ``part`` is
  given (``anchor`` "centroid": the part's centroid, the thesis's grasp point; "top": the
  centre of the top face of its world bounding box), plus ``offset`` (m, world axes);
  without either the tool's current position;
- and the orientation is ``rotation`` (3x3, world), or the tool's current one.

On the wire a target is a 4x4 matrix or an object with these keys.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

import numpy as np

from workcell.errors import ProgramError
from workcell.program import args as a

if TYPE_CHECKING:
    from workcell.program.session import Session

__all__ = ["ANCHORS", "Target", "part_pose", "target", "via_target"]

ANCHORS = ("centroid", "top")


def _rotation(v: object, what: str) -> tuple[tuple[float, ...], ...]:
    """A 3x3 rotation matrix (rows), orthonormal with det +1 within 1e-6."""
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if not isinstance(v, (list, tuple)) or len(v) != 3:
        raise ProgramError(f"{what} must be a 3x3 rotation matrix (3 rows of 3), got {v!r}")
    R = tuple(a.vector(r, f"{what} row {i + 1}", 3) for i, r in enumerate(v))
    M = np.array(R)
    if np.abs(M.T @ M - np.eye(3)).max() > 1e-6 or np.linalg.det(M) < 0:
        raise ProgramError(f"{what} must be a rotation (orthonormal, det +1)")
    return R


_CONVERT = {
    "matrix": a.optional(a.matrix),
    "position": a.optional(a.sized(3)),
    "part": a.optional(a.name),
    "anchor": a.choice(*ANCHORS),
    "offset": a.sized(3),
    "rotation": a.optional(_rotation),
}


@dataclass(frozen=True)
class Target:
    """Where a Cartesian move sends the tool (see the module doc); lengths in metres."""

    matrix: tuple[tuple[float, ...], ...] | None = None
    position: tuple[float, ...] | None = None
    part: str | None = None
    anchor: str = "centroid"
    offset: tuple[float, ...] = (0.0, 0.0, 0.0)
    rotation: tuple[tuple[float, ...], ...] | None = None

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            object.__setattr__(self, f.name, _CONVERT[f.name](v, f"target {f.name}"))
        if self.matrix is not None and (
            self.position is not None or self.part is not None or self.rotation is not None
        ):
            raise ProgramError("target: give a matrix, or position/part and rotation, not both")
        if self.position is not None and self.part is not None:
            raise ProgramError("target: give a position or a part, not both")

    def resolve(self, session: Session, robot: str) -> np.ndarray:
        """The 4x4 world pose of the tool this target asks for, now."""
        if self.matrix is not None:
            return np.array(self.matrix, dtype=np.float64)
        current = None
        if (self.position is None and self.part is None) or self.rotation is None:
            current = session.require_sim().tool_pose(robot)
        T = np.eye(4)
        if self.position is not None:
            p = np.array(self.position)
        elif self.part is not None:
            p = part_anchor(session, self.part, self.anchor)
        else:
            p = current[:3, 3]  # type: ignore[index]
        T[:3, 3] = p + np.array(self.offset)
        T[:3, :3] = current[:3, :3] if self.rotation is None else np.array(self.rotation)  # type: ignore[index]
        return T


def target(v: object, what: str) -> Target:
    """A tool target: a 4x4 matrix, or an object with keys of :class:`Target`."""
    return _target(v, what)


target.label = "matrix4 | target"  # type: ignore[attr-defined]


def via_target(v: object, what: str) -> Target:
    """A point the tool passes: 3 numbers (m, world), or a target (its position counts)."""
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, (list, tuple)) and len(v) == 3:
        return Target(position=a.sized(3)(v, what))
    return _target(v, what)


via_target.label = "number[3] | matrix4 | target"  # type: ignore[attr-defined]


def _target(v: object, what: str) -> Target:
    if isinstance(v, Target):
        return v
    if isinstance(v, dict):
        unknown = sorted(set(v) - set(_CONVERT))
        if unknown:
            raise ProgramError(
                f"{what}: unknown key(s) {', '.join(map(str, unknown))}; valid: {', '.join(_CONVERT)}"
            )
        return Target(**v)
    return Target(matrix=a.matrix(v, what))


def part_pose(session: Session, part: str) -> np.ndarray:
    """World pose (4x4) of a part's frame now: from the simulator for a movable part."""
    cell = session.require_cell()
    if part in cell.static_parts:
        return np.array(cell.static_parts[part].pose)
    sim = session.sim
    if part not in cell.movable_parts and (sim is None or part not in sim.compiled.part_bodies):
        known = ", ".join([*cell.static_parts, *cell.movable_parts]) or "none"
        raise ProgramError(f"no part '{part}' in cell '{cell.name}'; parts: {known}")
    if sim is None:
        return np.array(cell.movable_parts[part].pose)
    b = sim.model.body(sim.compiled.part_bodies[part]).id
    T = np.eye(4)
    T[:3, :3] = sim.data.xmat[b].reshape(3, 3)
    T[:3, 3] = sim.data.xpos[b]
    return T


def part_anchor(session: Session, part: str, anchor: str) -> np.ndarray:
    """World position (m) of a part's ``anchor`` ("centroid" or "top") now."""
    T = part_pose(session, part)
    cell = session.require_cell()
    p: Any = cell.static_parts.get(part) or cell.movable_parts[cell.pattern_of(part)]
    if anchor == "centroid":
        c = cell.model.properties(p.entity).centroid
        return T[:3, :3] @ c + T[:3, 3]
    V = cell.model.world_mesh(p.entity).vertices @ T[:3, :3].T + T[:3, 3]
    lo, hi = V.min(axis=0), V.max(axis=0)
    return np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, hi[2]])
