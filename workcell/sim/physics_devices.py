"""The cell's devices in physics mode (a part of the run in :mod:`workcell.sim.physics`).

The physics run replays the kinematic plan, and so do its devices:

- **belts** move what rests on them through MuJoCo's geom ``surfacevel`` (checked to
  work in MuJoCo 3.17: a geom's surface velocity, in the geom's frame, drives what touches
  it by friction; the model flag ``flg_surfacevel`` must be on): the belt slab's
  surface velocity is the belt's speed along it while the belt runs in the plan (its run
  signal true in the plan's ``signal`` events, or always without one), else 0; what a
  belt carries is pushed against the end stop, a plate of the compiled model;
- **sources and sinks** act at the plan's times: a copy the plan made appears where the
  plan put it (at rest), a part the plan removed is parked; parked bodies are held at
  their parking places (they would fall);
- **sensors** are read on the physics run's own recorded frames (:class:`SensorReader`):
  each change is a ``signal`` event of the run (data: ``signal``, ``value``, ``source``
  "sensor"), in place of the plan's sensor events (the programs' ``set_signal`` events
  are kept), so the physics run says when its beams really broke.

Times in seconds, speeds m/s.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from workcell.cell.compile_devices import PARKED_ABOVE
from workcell.sim.devices import SensorReader, format_value

if TYPE_CHECKING:
    from workcell.sim.physics import _Run

__all__ = ["PhysicsDevices", "is_sensor_event"]


def is_sensor_event(e: Any) -> bool:
    """A plan's event a physics run makes again itself (a sensor's signal change)."""
    return e.kind == "signal" and (e.data or {}).get("source") == "sensor"


class PhysicsDevices:
    """Belts, part flow and sensors of one physics run (module doc)."""

    def __init__(self, run: _Run) -> None:
        sim, m, cc = run.sim, run.m, run.cc
        self.run = run
        h = run.h
        logic = sim._logic
        self.belts = [
            (m.geom(cc.conveyors[c.name]).id, c.speed, c.run_signal)
            for c in sim.cell.conveyors.values()
        ]
        if self.belts:
            m.flg_surfacevel = 1
        values = dict(logic.initial)
        changes: list[tuple[float, str, Any]] = []
        self.todo: list[tuple[int, str, Any]] = []  # (step, what, payload), in time order
        for e in sim.timeline.events:
            d = e.data or {}
            if e.kind == "signal" and "signal" in d:
                changes.append((e.t, d["signal"], d["value"]))
            elif e.kind in ("source", "sink") and "part" in d:
                self.todo.append((_step(e.t, h), e.kind, (d["part"], e.frame)))
        for t, name, value in changes:
            self.todo.append((_step(t, h), "signal", (name, value)))
        self.todo.sort(key=lambda x: x[0])
        self.values = values
        self.next = 0
        self._belts()
        self.adr = {p: int(m.jnt_qposadr[m.joint(j).id]) for p, j in cc.free_joints.items()}
        self.dof = {p: int(m.jnt_dofadr[m.joint(j).id]) for p, j in cc.free_joints.items()}
        q0 = sim.timeline.frame(0)[2]
        self.parked = {p for p, a in self.adr.items() if q0[a + 2] > PARKED_ABOVE}
        self.parking = {p: cc.parking[p] for p in self.adr}
        self.reader = SensorReader(sim, m, run.d) if sim.cell.sensors else None
        self.read = dict.fromkeys(sim.cell.sensors, False)

    @property
    def steps(self) -> set[int]:
        """The steps at which something changes (the run starts a block there)."""
        return {s for s, _, _ in self.todo}

    def at(self, n: int) -> None:
        """Apply what is due at step ``n``; hold the parked bodies."""
        d, sim = self.run.d, self.run.sim
        belts = False
        while self.next < len(self.todo) and self.todo[self.next][0] <= n:
            _, what, payload = self.todo[self.next]
            self.next += 1
            if what == "signal":
                self.values[payload[0]] = payload[1]
                belts = True
            elif what == "source":
                part, frame = payload
                a, v = self.adr[part], self.dof[part]
                d.qpos[a : a + 7] = sim.timeline.frame(frame)[2][a : a + 7]
                d.qvel[v : v + 6] = 0.0
                self.parked.discard(part)
            else:
                self.parked.add(payload[0])
        if belts:
            self._belts()
        for p in self.parked:
            a, v = self.adr[p], self.dof[p]
            d.qpos[a : a + 3] = self.parking[p]
            d.qpos[a + 3 : a + 7] = (1.0, 0.0, 0.0, 0.0)
            d.qvel[v : v + 6] = 0.0

    def sense(self, t: float) -> None:
        """Read the sensors on the state at ``t`` (s); a ``signal`` event for each change."""
        if self.reader is None:
            return
        for name, value in self.reader.read():
            if value != self.read[name]:
                self.read[name] = value
                data = {"source": "sensor", "signal": name, "value": value}
                detail = f"{name} = {format_value(value)} (sensor)"
                self.run._event(t, None, "signal", detail, data)

    def _belts(self) -> None:
        m = self.run.m
        for g, speed, signal in self.belts:
            on = signal is None or self.values.get(signal) is True
            m.geom_surfacevel[g] = (speed if on else 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def _step(t: float, h: float) -> int:
    return max(math.ceil(t / h - 1e-9), 0)
