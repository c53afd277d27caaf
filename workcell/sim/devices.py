"""The cell's devices on every frame (kinematic and playback mode): belts, sources, sinks,
sensors and the signals they drive.

:class:`CellLogic` belongs to one :class:`~workcell.sim.simulator.Simulator` of a cell
with devices (:mod:`workcell.cell.devices`; a cell without any has none and its
simulator runs as before). The simulator calls :meth:`CellLogic.frame` on each frame it
computes, after the robots' joints and the parts they carry are posed
(:mod:`workcell.sim.frames`), in this order:

1. **belts**: each running belt (its run signal true, or none) moves every movable part
   resting on it (no gripper holds it; its centroid over the belt; its lowest point on
   the belt's top, within :data:`RESTING`) by ``speed x dt`` along the belt, ``dt`` the
   simulated time since the previous frame, exactly, up to the end stop (the part's
   leading point stops at the belt's end). A belt's state during a frame is the one its
   signal had after the previous frame;
2. **sinks** remove (park) each part no gripper holds whose centroid is inside them;
3. **sources** make their copies due (timed ones at t = 0, every, 2 every, ... at the
   first frame at or after each time; signal ones at a rising edge of their signal);
4. **sensors** are evaluated on the frame's state (:mod:`workcell.sim.sensors`): beams
   and proximity rays with MuJoCo's ``mj_ray`` on the visual geometry (a beam sees only
   moving bodies: parts and robot links, a proximity ray every surface, the floor too),
   presence boxes on the parts' centroids; robot bodies are skipped unless the sensor
   asks for them.

Every change of a signal is a ``signal`` event (its data: ``signal``, ``value``,
``source``: "sensor", or the command that set it), a copy made a ``source`` event, a part
removed a ``sink`` event, each at its frame. With belts, sources or sinks, a movable part
no gripper holds keeps, from frame to frame, the pose this module gives it (the rows a
command emits carry only the robots; :meth:`carry_over`). Everything this module keeps
follows from the timeline (the last frame and the events), so :meth:`rebuild` restores
it when a command is undone.

Signals: ``values`` by name (declared ones at their initial value, sensors' false until
evaluated on frame 0). ``watch`` holds (signal, value) pairs that someone waits for; a
frame that gives a watched signal its value sets :attr:`stop` (the frame runner stops
after it, :mod:`workcell.sim.signals`). Units: m, s, m/s.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell.cell.compile_devices import PARKED_ABOVE
from workcell.cell.devices import TIME_EPS, SignalValue, format_value, same_value
from workcell.plan.support import geom_vertices
from workcell.sim.sensors import SensorReader, centroids

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["RESTING", "TIME_EPS", "CellLogic", "SensorReader", "format_value", "same_value"]

Array = NDArray[np.float64]
RESTING = 1e-3  # m: a part whose lowest point is this close to a belt's top rests on it
_QUAT_ID = np.array([1.0, 0.0, 0.0, 0.0])


class CellLogic:
    """Devices of one simulator, evaluated frame by frame (module doc)."""

    def __init__(self, sim: Simulator) -> None:
        self.sim = sim
        cell, cc, m = sim.cell, sim.compiled, sim.model
        self.initial: dict[str, SignalValue] = {s.name: s.initial for s in cell.signals.values()}
        self.initial.update(dict.fromkeys(cell.sensors, False))
        self.values: dict[str, SignalValue] = dict(self.initial)
        self.parts = list(cc.part_bodies)
        self.index = {p: i for i, p in enumerate(self.parts)}
        self.bodies = np.array([sim._part_body[p] for p in self.parts], dtype=np.intp)
        self.adr = np.array([sim._free_adr[p] for p in self.parts], dtype=np.intp)
        self.cols = (self.adr[:, None] + np.arange(7)).ravel()
        self.c_local = np.array([sim._centroids[p] for p in self.parts]).reshape(-1, 3)
        self.parking = np.array([cc.parking[p] for p in self.parts]).reshape(-1, 3)
        self.present = np.ones(len(self.parts), dtype=bool)
        self._verts: dict[int, Array] = {}
        self.belts = [_Belt(c) for c in cell.conveyors.values()]
        self.sources = list(cell.sources.values())
        self.sinks = list(cell.sinks.values())
        self.sensors = list(cell.sensors.values())
        self.patterns = {s.part for s in self.sources}
        self.movers = bool(self.belts or self.sources or self.sinks)
        self.made = {s.name: 0 for s in self.sources}
        self.edge = {s.name: False for s in self.sources}
        self.sunk = {s.name: 0 for s in self.sinks}
        self.warned: set[str] = set()
        self.reader = SensorReader(sim, m, sim.data)
        self.distances = self.reader.distances
        self.watch: dict[str, list[SignalValue]] = {}
        self.stop = False
        self.t_prev = 0.0

    @classmethod
    def of(cls, sim: Simulator) -> CellLogic | None:
        """The logic of ``sim``'s cell, or None when it has no devices."""
        cell = sim.cell
        if not (cell.signals or cell.sensors or cell.conveyors or cell.sources or cell.sinks):
            return None
        return cls(sim)

    # ------------------------------------------------------------------ set-up
    def start(self) -> None:
        """Frame 0: park the sources' patterns and every copy, then evaluate the devices
        at t = 0 (timed sources make their first copy, sensors read the cell)."""
        qpos = self.sim.data.qpos
        for p in [*self.patterns, *self.sim.compiled.patterns]:
            i = self.index[p]
            self._park(qpos, i)
        mujoco.mj_kinematics(self.sim.model, self.sim.data)
        self.t_prev = 0.0
        self.frame(0.0, 0)

    def rebuild(self) -> None:
        """Take every value back from the timeline (after an undo): signals from the
        events, copies made and parts removed from the events, what is present from the
        current pose, the time of the last frame."""
        self.values = dict(self.initial)
        self.made = dict.fromkeys(self.made, 0)
        self.sunk = dict.fromkeys(self.sunk, 0)
        for e in self.sim.timeline.events:
            d = e.data or {}
            if e.kind == "signal" and "signal" in d:
                self.values[d["signal"]] = d["value"]
            elif e.kind == "source" and d.get("source") in self.made:
                self.made[d["source"]] += 1
            elif e.kind == "sink" and d.get("sink") in self.sunk:
                self.sunk[d["sink"]] += 1
        self.edge = {s.name: bool(self.values[s.on_signal]) for s in self.sources if s.on_signal}
        self.present = self.sim.data.qpos[self.adr + 2] < PARKED_ABOVE
        self.t_prev = self.sim.sim_time
        self.stop = False

    # ------------------------------------------------------------------ per frame
    def carry_over(self, qpos: Array, row: Array) -> None:
        """``qpos`` = the frame ``row``, but with the movable parts' poses of the previous
        frame (what ``qpos`` holds now): only this module and the grippers move parts."""
        keep = qpos[self.cols]
        qpos[:] = row
        qpos[self.cols] = keep

    def frame(self, t: float, index: int) -> None:
        """Evaluate the devices on frame ``index`` at simulated time ``t`` (s); the
        simulator's data holds the frame (kinematics done) and is updated in place."""
        sim = self.sim
        m, d = sim.model, sim.data
        dt, self.t_prev = t - self.t_prev, t
        moved = False
        if self.movers:
            held = self._held()
            if dt > 0 and self.belts:
                moved = self._belts(dt, held)
                if moved:
                    mujoco.mj_kinematics(m, d)
            changed = False
            if self.sinks:
                changed = self._sinks(t, index, held)
            if self.sources:
                changed = self._sources(t, index) or changed
            if changed:
                mujoco.mj_kinematics(m, d)
        if self.sensors:
            self._sense(t, index)

    def set(
        self,
        name: str,
        value: SignalValue,
        t: float,
        index: int,
        data: dict[str, Any],
        *,
        always: bool = False,
    ) -> bool:
        """Give signal ``name`` its ``value`` at frame ``index`` (time ``t``, s): a
        ``signal`` event with ``data`` (and ``signal``, ``value``) when it changes, or
        ``always``; :attr:`stop` when someone waits for the new value. Returns whether it
        changed."""
        changed = not same_value(self.values.get(name), value)
        if not (changed or always):
            return False
        self.values[name] = value
        who = data.get("robot") if data.get("command") else None
        by = "sensor" if data.get("source") == "sensor" else data.get("command", "set")
        if not changed:
            by += ", unchanged"
        self.sim.timeline.add_event(
            t, who, "signal", f"{name} = {format_value(value)} ({by})", frame=index,
            data={**data, "signal": name, "value": value},
        )  # fmt: skip
        waited = self.watch.get(name)
        if changed and waited and any(same_value(value, w) for w in waited):
            self.stop = True
        return changed

    def alive(self) -> bool:
        """Whether the cell itself can still change something as time passes: a timed
        source with copies to make, or a part a running belt moves."""
        for s in self.sources:
            if s.every is not None and self.made[s.name] < s.pool:
                return True
        if not self.belts:
            return False
        held = self._held()
        qpos = self.sim.data.qpos.copy()
        moved = self._belts(1e-3, held, dry=True)
        self.sim.data.qpos[:] = qpos
        return moved

    def source_times(self, t0: float, t1: float) -> list[float]:
        """The times (s) in (t0, t1) at which timed sources make their next copies."""
        out: list[float] = []
        for s in self.sources:
            if s.every is None:
                continue
            k0 = max(self.made[s.name], math.floor(t0 / s.every + 1e-9) + 1)
            k = np.arange(k0, max(k0, s.pool))
            ts = k * s.every
            out.extend(ts[(ts > t0 + TIME_EPS) & (ts < t1 - TIME_EPS)].tolist())
        return sorted(out)

    def present_parts(self) -> list[str]:
        """The movable parts in the world (not parked)."""
        return [p for p, here in zip(self.parts, self.present, strict=True) if here]

    # ------------------------------------------------------------------ devices
    def _held(self) -> NDArray[np.bool_]:
        held = np.zeros(len(self.parts), dtype=bool)
        for h in self.sim._holds.values():
            held[self.index[h.part]] = True
        return held

    def _centroids(self, idx: NDArray[np.intp]) -> Array:
        return centroids(self.sim.data, self.bodies[idx], self.c_local[idx])

    def _world_verts(self, i: int) -> Array:
        """World vertices of part i's collision pieces."""
        d = self.sim.data
        b = self.bodies[i]
        V = self._verts.get(i)
        if V is None:  # body-frame vertices, once
            m = self.sim.model
            geoms = [g for g in self.sim.contacts.colliding if m.geom_bodyid[g] == b]
            W = np.vstack([geom_vertices(m, d, int(g)) for g in geoms])
            R0 = d.xmat[b].reshape(3, 3)
            V = self._verts[i] = (W - d.xpos[b]) @ R0
        return V @ d.xmat[b].reshape(3, 3).T + d.xpos[b]

    def _belts(self, dt: float, held: NDArray[np.bool_], *, dry: bool = False) -> bool:
        """Move the parts resting on running belts by speed x dt (module doc); with
        ``dry``, only say whether one would move."""
        qpos = self.sim.data.qpos
        idx = np.flatnonzero(self.present & ~held)
        if len(idx) == 0:
            return False
        C = self._centroids(idx)
        moved = False
        for belt in self.belts:
            if belt.signal is not None and not self.values.get(belt.signal):
                continue
            rel = C - belt.start
            s, w = rel @ belt.u, rel @ belt.n
            over = (s >= 0) & (s <= belt.length) & (np.abs(w) <= belt.half_width)
            for i in idx[over]:
                V = self._world_verts(int(i))
                if abs(float(V[:, 2].min()) - belt.top) > RESTING:
                    continue
                room = belt.end_u - float((V @ belt.u).max())
                ds = min(belt.speed * dt, room)
                if ds <= 1e-12:
                    continue
                moved = True
                if dry:
                    return True
                a = self.adr[i]
                qpos[a : a + 3] += ds * belt.u
        return moved

    def _sinks(self, t: float, index: int, held: NDArray[np.bool_]) -> bool:
        idx = np.flatnonzero(self.present & ~held)
        if len(idx) == 0:
            return False
        C = self._centroids(idx)
        qpos = self.sim.data.qpos
        changed = False
        for sink in self.sinks:
            inside = np.all(np.abs(C - sink.center) <= sink.size / 2, axis=1)
            for i in idx[inside]:
                if not self.present[i]:
                    continue
                part = self.parts[i]
                where = ", ".join(f"{v:.4f}" for v in C[np.searchsorted(idx, i)])
                self._park(qpos, int(i))
                self.sunk[sink.name] += 1
                n = self.sunk[sink.name]
                self.sim.timeline.add_event(
                    t, None, "sink", f"'{part}' removed by sink '{sink.name}' at ({where}) m "
                    f"({n} so far)", frame=index, data={"sink": sink.name, "part": part, "count": n},
                )  # fmt: skip
                changed = True
        return changed

    def _sources(self, t: float, index: int) -> bool:
        changed = False
        for s in self.sources:
            due = 0
            if s.every is not None:
                k = self.made[s.name]
                while k + due < s.pool and (k + due) * s.every <= t + TIME_EPS:
                    due += 1
                due = min(due, 1)  # one copy per frame at most
            else:
                v = bool(self.values.get(s.on_signal))  # type: ignore[arg-type]
                if v and not self.edge[s.name]:
                    due = 1
                self.edge[s.name] = v
            if due and self.made[s.name] >= s.pool:
                self._exhausted(s, t, index)
                continue
            if due:
                self._make(s, t, index)
                changed = True
        return changed

    def _make(self, s: Any, t: float, index: int) -> None:
        k = self.made[s.name]
        copy = s.copies[k]
        i = self.index[copy]
        qpos = self.sim.data.qpos
        a = self.adr[i]
        qpos[a : a + 3] = s.at[:3, 3]
        qpos[a + 3 : a + 7] = _quat(s.at)
        self.present[i] = True
        self.made[s.name] = k + 1
        self.sim.timeline.add_event(
            t, None, "source", f"'{copy}' made by source '{s.name}' ({k + 1} of {s.pool})",
            frame=index, data={"source": s.name, "part": copy, "count": k + 1},
        )  # fmt: skip

    def _exhausted(self, s: Any, t: float, index: int) -> None:
        if s.name in self.warned:
            return
        self.warned.add(s.name)
        why = (
            f"its count {s.count}"
            if s.count is not None
            else f"the limit max_part_copies = {s.pool} (raise it for more)"
        )
        self.sim.timeline.add_event(
            t, None, "warning", f"source '{s.name}' has made all its copies ({why})", frame=index
        )

    def _park(self, qpos: Array, i: int) -> None:
        a = self.adr[i]
        qpos[a : a + 3] = self.parking[i]
        qpos[a + 3 : a + 7] = _QUAT_ID
        self.present[i] = False

    def _sense(self, t: float, index: int) -> None:
        values = self.values
        for name, value in self.reader.read():
            if values[name] is not value:  # sensors' values are the bools True and False
                self.set(name, value, t, index, {"source": "sensor"})


class _Belt:
    """A conveyor's geometry for the per-frame loop."""

    def __init__(self, c: Any) -> None:
        self.name, self.signal, self.speed = c.name, c.run_signal, c.speed
        self.start, self.u, self.length = c.start, c.direction, c.length
        self.n = np.array([-self.u[1], self.u[0], 0.0])
        self.half_width = c.width / 2
        self.top = c.top
        self.end_u = float(c.end @ self.u)


def _quat(T: Array) -> Array:
    from workcell.spatial import quat_from_matrix

    return quat_from_matrix(T[:3, :3])
