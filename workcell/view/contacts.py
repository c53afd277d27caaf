"""Contacts of the shown frame, with their points: what the live view paints red.

:func:`contacts` reads MuJoCo's contacts of an ``MjData`` on which ``mj_collision`` has
run (the simulator does so for every frame when it checks collisions) and keeps, like
:meth:`~workcell.sim.contacts.ContactMonitor.penetrations`, the pairs of different
things overlapping by more than the tolerance and not excluded (a held part and its
gripper): for each pair its deepest contact, with the contact point (m, world) and the
depth (m), deepest first. With ``only`` (a physics replay's frames, whose run has decided
which pairs collide) just those pairs, at any overlap.
"""

from __future__ import annotations

from collections.abc import Collection
from typing import NamedTuple

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.sim.contacts import ContactMonitor

__all__ = ["Contact", "contacts"]


class Contact(NamedTuple):
    """Two things (labels, sorted) in contact at ``point`` (m, world), ``depth`` m deep."""

    a: str
    b: str
    depth: float
    point: NDArray[np.float64]


def contacts(monitor: ContactMonitor, data: mujoco.MjData, *,
             only: Collection[tuple[str, str]] | None = None) -> list[Contact]:  # fmt: skip
    """The overlapping pairs of ``data``'s current contacts (module doc)."""
    pairs = None if only is None else {(min(a, b), max(a, b)) for a, b in only}
    n = data.ncon
    if n == 0 or pairs == set():
        return []
    con = data.contact
    dist = con.dist[:n]
    hits = np.flatnonzero(dist < (0.0 if pairs is not None else -monitor.tolerance))
    if len(hits) == 0:
        return []
    body = monitor.model.geom_bodyid
    best: dict[tuple[str, str], Contact] = {}
    for k in hits:
        g1, g2 = int(con.geom1[k]), int(con.geom2[k])
        b1, b2 = int(body[g1]), int(body[g2])
        if pairs is None and (min(b1, b2), max(b1, b2)) in monitor.excluded:
            continue
        la, lb = sorted((monitor.labels[g1], monitor.labels[g2]))
        if la == lb or (pairs is not None and (la, lb) not in pairs):
            continue
        depth = -float(dist[k])
        if depth > (best[(la, lb)].depth if (la, lb) in best else 0.0):
            best[(la, lb)] = Contact(la, lb, depth, con.pos[k].copy())
    return sorted(best.values(), key=lambda c: -c.depth)
