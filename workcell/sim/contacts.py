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

**Mounting**: a robot stands on what its base touches. :meth:`ContactMonitor.mount`
finds, for each robot, the static things (static parts, the ground) that its link 0
(base) touches or comes within the tolerance of in a state (the start), and allows
contact between them and the robot's link 1 (:attr:`ContactMonitor.allowed`): the first
moving link of a real arm often reaches down to the mounting surface (a Panda's link 1
collision capsule runs 60 mm below its base), and turns there about the vertical. A
thing counts when it touches the base (signed distance within +-the tolerance: one sunk
deeper is a collision, not a mount) at the base's underside (within the tolerance of the
base's lowest point along the base frame's z axis, so a hanging robot stands on its
ceiling and a wall beside the base is no mount). Every other pair of the robot and that
part still collides (an arm link through the table is reported).

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

__all__ = ["DEFAULT_TOLERANCE", "ContactMonitor", "Penetration", "contact_model", "mounts_of"]

DEFAULT_TOLERANCE = 1e-4  # m: deeper overlaps are collisions; shallower ones are touching
_CLEARANCE_CAP = 100.0  # m: mj_geomDistance's distmax
_CENTRE_SHIFT = 1e-11  # m per geom index (contact_model)
_EPA = 1e-6  # m: how far a distance's nearest points may stray (MuJoCo's EPA)
_SHIFT_DIRECTION = np.array([1.0, 2.0**0.5, 3.0**0.5]) / 6.0**0.5  # unit, no symmetry


Penetration = tuple[str, str, float]  # (label, label) sorted, depth (m, > 0)


def contact_model(model: mujoco.MjModel) -> mujoco.MjModel:
    """A copy of ``model`` whose collisions list every overlap with its true signed
    distance (m): geom margins and gaps 0 (module doc), and one contact per pair of convex
    pieces (multi-point contacts off): its ``dist`` is the penetration depth found by
    MuJoCo's EPA, the smallest translation that separates the two, as ``mj_geomDistance``
    measures it (the extra points of multi-point contacts carry depths along an
    approximate normal: 4.9 um deeper on a CoACD piece whose top is not quite flat).
    The tolerance (m) a collision's depth must exceed is :attr:`ContactMonitor.tolerance`.

    Geom k is moved by (k + 1) x 1e-11 m along a fixed direction of its body: MuJoCo's
    collider finds no contact between two convex pieces whose centres coincide exactly
    (two copies of a part at one pose, however deep the overlap), and with these offsets
    no two geoms of different bodies keep a common centre (the shift is at most 1e-7 m
    for 10,000 geoms, a thousandth of the default tolerance)."""
    out = copy.copy(model)
    out.geom_margin[:] = 0.0
    out.geom_gap[:] = 0.0
    k = np.arange(1, model.ngeom + 1, dtype=np.float64)[:, None]
    out.geom_pos[:] += _CENTRE_SHIFT * k * _SHIFT_DIRECTION
    out.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_MULTICCD
    return out


def _lowest(model: mujoco.MjModel, data: mujoco.MjData, geoms: list[int], up: NDArray) -> float:
    """The lowest point of mesh geoms along ``up`` (world, m); +inf for none."""
    low = np.inf
    for g in geoms:
        i = int(model.geom_dataid[g])
        if int(model.geom_type[g]) != int(mujoco.mjtGeom.mjGEOM_MESH) or i < 0:
            continue
        v = model.mesh_vert[model.mesh_vertadr[i] : model.mesh_vertadr[i] + model.mesh_vertnum[i]]
        w = v @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]
        low = min(low, float((w @ up).min()))
    return low


def _body(model: mujoco.MjModel, name: str) -> int | None:
    try:
        return int(model.body(name).id)
    except KeyError:
        return None


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
        self.allowed: set[tuple[str, str]] = set()  # label pairs (sorted) that may touch
        self.mounts: dict[str, list[str]] = {}  # robot -> the static things it stands on

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

    def mount(self, data: mujoco.MjData) -> dict[str, list[str]]:
        """Find what each robot stands on in ``data``'s pose (module doc): set and return
        :attr:`mounts` and add the (link 1, thing) pairs to :attr:`allowed`."""
        m = self.model
        static: dict[str, list[int]] = {}  # label -> geoms of the world body
        for g in self.colliding:
            if int(m.geom_bodyid[g]) == 0:
                static.setdefault(self.labels[g], []).append(int(g))
        self.mounts = {}
        for robot, prefix in self._robots.items():
            base, first = (_body(m, f"{prefix}link{k}") for k in (0, 1))
            if base is None or first is None:
                continue
            own = [int(g) for g in self.colliding if int(m.geom_bodyid[g]) == base]
            own = own or [g for g in range(m.ngeom) if int(m.geom_bodyid[g]) == base]
            up = data.xmat[base].reshape(3, 3)[:, 2]  # the base frame's z: the robot's up
            low = _lowest(m, data, own, up)
            on = [x for x, gs in sorted(static.items()) if self._under(data, own, gs, up, low)]
            self.mounts[robot] = on
            link1 = m.body(first).name
            self.allowed |= {(min(link1, x), max(link1, x)) for x in on}
        return self.mounts

    def _under(
        self, data: mujoco.MjData, own: list[int], geoms: list[int], up: NDArray, low: float
    ) -> bool:
        """Whether the geoms touch the base geoms ``own`` (signed distance within +-the
        tolerance) at the base's underside (within the tolerance of its lowest point
        ``low`` along ``up``)."""
        tol, fromto = self.tolerance, np.zeros(6)
        found = False
        for a in own:
            for b in geoms:
                d = mujoco.mj_geomDistance(self.model, data, a, b, 2 * tol, fromto)
                if d < -tol:
                    return False  # sunk into it: a collision, not a mount
                if d <= tol and float(fromto[:3] @ up) <= low + tol + _EPA:
                    found = True
        return found

    def allowed_geoms(self) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """(the geoms of the robots' link 1, the geoms of what they stand on) of
        :attr:`allowed` (for the physics mode's contact bits)."""
        robot_side = {x for pair in self.allowed for x in pair if self.robot_of(x) is not None}
        other = {x for pair in self.allowed for x in pair} - robot_side
        pick = [
            [int(g) for g in self.colliding if self.labels[g] in s] for s in (robot_side, other)
        ]
        return np.array(pick[0], dtype=np.intp), np.array(pick[1], dtype=np.intp)

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
            if key in self.allowed:
                continue
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


def mounts_of(compiled: CompiledCell, tolerance: float = DEFAULT_TOLERANCE) -> dict[str, list[str]]:
    """Robot -> the static things it stands on in the compiled cell's initial state
    (:meth:`ContactMonitor.mount`; ``tolerance`` in m)."""
    model = contact_model(compiled.model)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    return ContactMonitor(compiled, tolerance, model).mount(data)
