"""The cell's sensors read on a model and its data (:class:`SensorReader`; the simulator's
on every frame, :mod:`workcell.sim.devices`, 4., or a physics run's copy,
:mod:`workcell.sim.physics_devices`): beams and proximity rays with MuJoCo's ``mj_ray``
on the visual geometry (a beam sees only moving bodies: parts and robot links, a
proximity ray every surface, the floor too), presence boxes on the parts' centroids;
robot bodies are skipped unless the sensor asks for them. Units: m.
"""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.cell.compile_devices import PARKED_ABOVE
from workcell.meshgeoms import COLLISION_GROUP

__all__ = ["SensorReader", "centroids"]

Array = NDArray[np.float64]


class SensorReader:
    """Reads the cell's sensors on a model and its data (the simulator's, or a physics
    run's copy: :mod:`workcell.sim.physics_devices`; module doc, 4.): :meth:`read` gives
    each sensor's value, :attr:`distances` the proximity sensors' distances (m). Parked
    parts are left out; robot bodies unless a sensor asks for them."""

    def __init__(self, sim: Any, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        cc = sim.compiled
        self.model, self.data = model, data
        self.sensors = list(sim.cell.sensors.values())
        parts = list(cc.part_bodies)
        self.bodies = np.array([model.body(cc.part_bodies[p]).id for p in parts], dtype=np.intp)
        self.c_local = np.array([sim._centroids[p] for p in parts]).reshape(-1, 3)
        robot_body = np.zeros(model.nbody, dtype=bool)
        prefixes = tuple(cc.robot_prefixes.values())
        for b in range(1, model.nbody):
            robot_body[b] = model.body(b).name.startswith(prefixes) if prefixes else False
        self.robot_body = robot_body
        # a ray passes each robot body at most once on its way to what it sees
        self._hops = int(robot_body.sum()) + 1
        self.tool_sites = np.array(
            [model.site(cc.tool_sites[r]).id for r in cc.tool_sites], dtype=np.intp
        )
        self.groups = np.zeros(6, np.uint8)
        self.groups[:COLLISION_GROUP] = 1  # visual geometry (the floor is group 0)
        self._hit = np.zeros(1, np.int32)
        self._here: Array | None = None
        self.distances: dict[str, float] = {
            s.name: math.inf for s in self.sensors if s.kind == "proximity"
        }

    def read(self) -> list[tuple[str, bool]]:
        """(sensor, value) for every sensor, on the data's current poses."""
        out = []
        self._here = None  # the parts' centroids, once per reading
        for s in self.sensors:
            p = s.params
            if s.kind == "presence":
                value = self._presence(s)
            elif s.kind == "beam":
                value = (
                    self._ray(p["start"], p["end"] - p["start"], 1.0, False, s.robots) is not None
                )
            else:
                x = self._ray(p["origin"], p["direction"], p["range"], True, s.robots)
                dist = math.inf if x is None else x
                self.distances[s.name] = dist
                value = dist <= p["threshold"]
            out.append((s.name, value))
        return out

    def _presence(self, s: Any) -> bool:
        d = self.data
        c, h = s.params["center"], s.params["size"] / 2
        if self._here is None:
            here = d.xpos[self.bodies, 2] < PARKED_ABOVE
            self._here = centroids(d, self.bodies[here], self.c_local[here])
        C = self._here
        if len(C) and np.any(np.all(np.abs(C - c) <= h, axis=1)):
            return True
        if s.robots and len(self.tool_sites):
            P = d.site_xpos[self.tool_sites]
            return bool(np.any(np.all(np.abs(P - c) <= h, axis=1)))
        return False

    def _ray(
        self, start: Array, vec: Array, reach: float, static: bool, robots: bool
    ) -> float | None:
        """The first hit (in units of ``vec``) within ``reach`` along ``start + x vec``,
        skipping robot bodies unless ``robots`` (the ray goes on from where it meets one,
        that body left out, past every robot body if need be); None when nothing is hit."""
        m, d = self.model, self.data
        pnt, travelled, exclude = np.array(start, dtype=np.float64), 0.0, -1
        for _ in range(self._hops):
            x = mujoco.mj_ray(m, d, pnt, vec, self.groups, static, exclude, self._hit)
            if x < 0 or travelled + x > reach:
                return None
            b = int(m.geom_bodyid[self._hit[0]])
            if robots or not self.robot_body[b]:
                return travelled + x
            travelled += x
            pnt = pnt + x * vec
            exclude = b
        return None


def centroids(d: mujoco.MjData, bodies: NDArray[np.intp], c_local: Array) -> Array:
    """World centroids (k, 3) of ``bodies`` whose centroids are ``c_local`` in their frames."""
    R = d.xmat[bodies].reshape(-1, 3, 3)
    return d.xpos[bodies] + np.matmul(R, c_local[:, :, None])[:, :, 0]
