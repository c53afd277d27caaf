"""Collisions and clearance between the things of a compiled cell (kinematic mode).

Each collision geom belongs to a *thing label*: the body's name for geoms on a body
(``"puma_1.link3"``, ``"puma_1.gripper.left"``, a movable part ``"cube"``), the static
part's name for geoms of the world body (``"table_1"``), or ``"ground"``. Thing labels
are grouped under *things* for queries: a robot's name stands for all of its bodies.

After ``mj_kinematics`` + ``mj_collision`` (MuJoCo's own narrow phase on the convex
collision pieces), :meth:`ContactMonitor.penetrations` lists the pairs of labels whose
geoms overlap by more than ``tolerance`` (m), skipping pairs the simulator excludes
(a held part against the gripper holding it). :func:`contact_model` gives the
simulator's copy of the model with every geom margin and gap 0, so MuJoCo lists each
overlap (distance <= 0, parts resting on their supports included) with its true signed
distance, and :meth:`ContactMonitor.penetrations` keeps the contacts deeper than the
tolerance. (Negative margins, which would leave the shallow contacts out inside MuJoCo,
are only valid with ``margin + gap >= 0``: with MuJoCo's convex collider, meshes and
boxes against meshes, a touching pair overlapping by d < tolerance came back with
``dist = -(d + tolerance)``, a false collision whenever the bounding-box tests let the
pair through.) Parent/child bodies and links up to two apart never collide (MuJoCo's
parent filter and the robot's ``<exclude>`` pairs); parts resting on a support touch at
depth ~0, under the tolerance.

:meth:`ContactMonitor.clearance` is the minimum signed distance between two things
(negative: penetration depth), from ``mj_geomDistance`` over their geom pairs.
"""

from __future__ import annotations

import copy
from collections.abc import Iterable

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.cell.compile import GROUND, CompiledCell
from workcell.errors import ProgramError

__all__ = ["DEFAULT_TOLERANCE", "ContactMonitor", "Penetration", "contact_model"]

DEFAULT_TOLERANCE = 1e-4  # m: deeper overlaps are collisions; shallower ones are touching
_CLEARANCE_CAP = 100.0  # m: mj_geomDistance's distmax


Penetration = tuple[str, str, float]  # (label, label) sorted, depth (m, > 0)


def contact_model(model: mujoco.MjModel) -> mujoco.MjModel:
    """A copy of ``model`` whose collisions list every overlap with its true signed
    distance (m): geom margins and gaps 0 (module doc), and one contact per pair of convex
    pieces (multi-point contacts off): its ``dist`` is the penetration depth found by
    MuJoCo's EPA, the smallest translation that separates the two, as ``mj_geomDistance``
    measures it (the extra points of multi-point contacts carry depths along an
    approximate normal: 4.9 um deeper on a CoACD piece whose top is not quite flat).
    The tolerance (m) a collision's depth must exceed is :attr:`ContactMonitor.tolerance`."""
    out = copy.copy(model)
    out.geom_margin[:] = 0.0
    out.geom_gap[:] = 0.0
    out.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_MULTICCD
    return out


class ContactMonitor:
    """Labels, exclusions and queries over the collision geoms of ``compiled`` (module doc)."""

    def __init__(
        self,
        compiled: CompiledCell,
        tolerance: float = DEFAULT_TOLERANCE,
        model: mujoco.MjModel | None = None,
    ) -> None:
        m = compiled.model if model is None else model
        self.model = m
        self.tolerance = float(tolerance)
        self._robots = dict(compiled.robot_prefixes)
        labels: list[str] = []
        for g in range(m.ngeom):
            body = int(m.geom_bodyid[g])
            if body != 0:
                labels.append(m.body(body).name)
            else:
                name = m.geom(g).name
                labels.append(GROUND if name == GROUND else name.rsplit(".", 1)[0])
        self.labels = labels
        self.colliding = np.flatnonzero((m.geom_contype != 0) | (m.geom_conaffinity != 0))
        self.excluded: set[tuple[int, int]] = set()  # body id pairs, (low, high)

    # ------------------------------------------------------------------ things
    def robot_of(self, label: str) -> str | None:
        """The robot a label belongs to, or None."""
        for robot, prefix in self._robots.items():
            if label.startswith(prefix):
                return robot
        return None

    def things(self) -> list[str]:
        """Every name :meth:`clearance` accepts: robots, then the other labels."""
        own = {self.labels[g] for g in self.colliding}
        return list(self._robots) + sorted(own)

    def geoms_of(self, thing: str) -> NDArray[np.intp]:
        """Collision geoms of a thing: a robot (all its bodies) or one label."""
        prefix = self._robots.get(thing)
        sel = [
            g
            for g in self.colliding
            if self.labels[g] == thing or (prefix is not None and self.labels[g].startswith(prefix))
        ]
        if not sel:
            raise ProgramError(
                f"no collision geometry named {thing!r}; known: {', '.join(self.things())}"
            )
        return np.array(sel, dtype=np.intp)

    def bodies_of(self, thing: str) -> set[int]:
        """Body ids of a thing's collision geoms."""
        return {int(self.model.geom_bodyid[g]) for g in self.geoms_of(thing)}

    # ------------------------------------------------------------------ queries
    def exclude(self, bodies_a: Iterable[int], bodies_b: Iterable[int]) -> set[tuple[int, int]]:
        """The (low, high) body pairs between two body sets (to add to :attr:`excluded`)."""
        return {(min(a, b), max(a, b)) for a in bodies_a for b in bodies_b}

    def penetrations(self, data: mujoco.MjData) -> list[Penetration]:
        """Label pairs overlapping by more than the tolerance in ``data``'s current contacts
        (call after mj_collision), deepest first, one entry per pair (its deepest contact)."""
        if data.ncon == 0:
            return []
        con = data.contact
        dist = con.dist  # (ncon,) m, signed
        if min(dist.tolist()) >= -self.tolerance:  # touching only: the common case, fast
            return []
        hits = np.flatnonzero(dist < -self.tolerance)
        g1, g2 = con.geom1, con.geom2
        body = self.model.geom_bodyid
        deepest: dict[tuple[str, str], float] = {}
        for k in hits:
            a, b = int(g1[k]), int(g2[k])
            ba, bb = int(body[a]), int(body[b])
            if (min(ba, bb), max(ba, bb)) in self.excluded:
                continue
            la, lb = self.labels[a], self.labels[b]
            if la == lb:
                continue
            key = (la, lb) if la < lb else (lb, la)
            depth = -float(dist[k])
            if depth > deepest.get(key, 0.0):
                deepest[key] = depth
        return sorted(((a, b, d) for (a, b), d in deepest.items()), key=lambda p: -p[2])

    def clearance(self, data: mujoco.MjData, a: str, b: str) -> tuple[float, str, str]:
        """Minimum signed distance (m; negative = penetration depth) between things ``a``
        and ``b`` in ``data``'s current pose, and the two labels where it occurs."""
        ga, gb = self.geoms_of(a), self.geoms_of(b)
        if set(ga.tolist()) & set(gb.tolist()):
            raise ProgramError(f"clearance: {a!r} and {b!r} share geometry")
        best, where = np.inf, ("", "")
        for i in ga:
            for j in gb:
                d = mujoco.mj_geomDistance(self.model, data, int(i), int(j), _CLEARANCE_CAP, None)
                if d < best:
                    best, where = d, (self.labels[i], self.labels[j])
        return float(best), where[0], where[1]
