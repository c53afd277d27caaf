"""Parts rest on something (kinematic mode): released parts, settling, resting poses.

:class:`RestingCommands` is a mixin of :class:`~workcell.sim.simulator.Simulator`. When
``open_gripper`` releases a part that no other gripper holds, the part's drop onto what is
below it (:func:`workcell.plan.support.drop`: static parts, movable parts not held, the
ground; never robots) is measured:

- more than the contact tolerance above its support, the part is in mid-air: a
  ``warning`` event says how high and above what (the thesis's kinematic simulator leaves
  it there);
- with ``settle=True`` (the default of ``place``) it is dropped straight down onto the
  highest support below it in one frame at the same simulated time, exactly (its lowest
  point on the support, to the LP's precision, ~1e-12 m), and a ``settle`` event says by
  how much. Its orientation is kept: a tilted part does not tip over (physics mode does
  that).

:meth:`RestingCommands._resting_pose` gives where a part, held in a given orientation above
a point, comes to rest when lowered (``place`` releases it there).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from workcell.plan.support import Drop, drop, geom_vertices

__all__ = ["RestingCommands"]

Array = NDArray[np.float64]


class RestingCommands:
    """Drops, settling and resting poses of movable parts (a mixin of Simulator)."""

    def _part_geoms(self, part: str) -> NDArray[np.intp]:
        b = self._part_body[part]
        return np.array(
            [g for g in self.contacts.colliding if self.model.geom_bodyid[g] == b], dtype=np.intp
        )

    def _part_pieces(self, part: str, pose: Array | None = None) -> list[Array]:
        """World vertices of the part's collision pieces, at ``pose`` (its body frame,
        4x4; default: where it is)."""
        m, d = self.model, self.data
        out = []
        P = self.part_pose(part) if pose is None else pose
        T_now = self.part_pose(part)
        to_pose = P @ np.linalg.inv(T_now)
        for g in self._part_geoms(part):
            V = geom_vertices(m, d, int(g))
            out.append(V @ to_pose[:3, :3].T + to_pose[:3, 3])
        return out

    def _supports(self, part: str) -> list[tuple[str, Array | float]]:
        """Every collision piece that may carry ``part``: static and movable parts (not
        the part itself nor held parts), horizontal planes (the ground)."""
        m, d = self.model, self.data
        held = {h.part for h in self._holds.values()}
        skip = {part, *held}
        out: list[tuple[str, Array | float]] = []
        for g in self.contacts.colliding:
            label = self.contacts.labels[g]
            if label in skip or self.contacts.robot_of(label) is not None:
                continue
            if m.geom_type[g] == 0:  # mjGEOM_PLANE
                if d.geom_xmat[g][8] > 1 - 1e-9:
                    out.append((label, float(d.geom_xpos[g][2])))
                continue
            out.append((label, geom_vertices(m, d, int(g))))
        return out

    def _part_drop(self, part: str, pose: Array | None = None) -> Drop:
        """How far ``part`` (at ``pose``, its body frame, default where it is) can move
        straight down before it rests, and on what."""
        if part not in self._part_body:
            self.part_pose(part)  # raises ProgramError naming the parts
        return drop(self._part_pieces(part, pose), self._supports(part))

    def _resting_pose(
        self, part: str, rotation: Array, xy: Array, above: float
    ) -> tuple[Array, Drop]:
        """The pose (4x4) where ``part`` comes to rest when lowered with body rotation
        ``rotation`` (3x3) and its centroid over ``xy`` (m, world) from ``above`` (m, a
        height its lowest point starts from, over everything there), and what it lands on."""
        c = self._centroids[part]
        P = np.eye(4)
        P[:3, :3] = rotation
        P[:3, 3] = np.array([xy[0], xy[1], 0.0]) - rotation @ c
        low = min(float(v[:, 2].min()) for v in self._part_pieces(part, P))
        P[2, 3] += above - low
        found = self._part_drop(part, P)
        if np.isfinite(found.distance):
            P[2, 3] -= found.distance
        return P, found

    def _after_release(self, name: str, part: str, settle: bool) -> None:
        """Warn about, or settle, a part just released by ``name`` that nobody holds."""
        if self._holders[part]:
            return
        d = self._part_drop(part)
        if not np.isfinite(d.distance):
            self.timeline.add_event(
                self.sim_time, name, "warning", f"'{part}' released with nothing below it"
            )
            return
        if settle and d.distance > 1e-9:  # (below: numerical noise, it rests already)
            row = self.data.qpos.copy()
            adr = self._free_adr[part]
            row[adr + 2] -= d.distance
            self._emit(np.array([self.sim_time]), row[None, :], [], name)
            self.timeline.add_event(
                self.sim_time,
                name,
                "settle",
                f"'{part}' dropped {d.distance * 1e3:.4g} mm onto {d.support}",
            )
        elif d.distance > self.contacts.tolerance:
            self.timeline.add_event(
                self.sim_time,
                name,
                "warning",
                f"'{part}' released in mid-air, {d.distance * 1e3:.4g} mm above {d.support}",
            )
