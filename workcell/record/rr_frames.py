"""A timeline's frames and events as rerun columns, for :mod:`workcell.record.rerun_log`.

:class:`Frames` buffers the kept frames, runs ``mujoco.mj_kinematics`` on each in a
scratch ``MjData`` and sends them in batches with ``send_columns``: body poses (a body
parked out of the world, :mod:`workcell.cell.compile_devices`, is shrunk to nothing at
the origin), joint values with their speeds and accelerations, tool path segments. :func:`log_events` sends
the events as text logs and the gripper state series. The entity layout and timelines are
described in :mod:`workcell.record.rerun_log`'s module doc.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np
import pyarrow as pa
import rerun as rr
from numpy.typing import NDArray

from workcell.cell.compile_devices import PARKED_ABOVE
from workcell.record.rr_rates import Rates, acceleration_entity, speed_entity
from workcell.record.rr_scene import EVENTS, Layout, gripper_entity, index_columns
from workcell.spatial import wxyz_to_xyzw

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["Frames", "log_events"]

_LEVELS = {"error": "ERROR", "collision": "WARN", "grasp": "INFO", "release": "INFO"}
_LEVELS |= {"move": "DEBUG", "wait": "DEBUG", "speed": "DEBUG"}
_STRIP_TYPE = rr.components.LineStrip3DBatch._ARROW_DATATYPE

Array = NDArray[np.float64]


def _segments(a: Array, b: Array) -> pa.Array:
    """Line strips of two points ``a[i] -> b[i]`` as an arrow array (rerun's numpy path
    builds the offsets in a Python loop)."""
    n = len(a)
    pts = np.stack([a, b], axis=1).astype(np.float32).reshape(-1)
    inner = pa.FixedSizeListArray.from_arrays(pa.array(pts), type=_STRIP_TYPE.value_type)
    offsets = pa.array(np.arange(0, 2 * n + 1, 2, dtype=np.int32))
    return pa.ListArray.from_arrays(offsets, inner, type=_STRIP_TYPE)


class Frames:
    """Buffers up to ``chunk`` frames (rows and their kinematics), then sends them as columns."""

    def __init__(self, rec: rr.RecordingStream, sim: Simulator, layout: Layout, chunk: int):
        m = self.m = sim.model
        self.rec, self.layout, self.d = rec, layout, mujoco.MjData(m)  # scratch, not sim.data
        self.rows = np.empty((chunk, 2 + m.nq))
        self.index = np.empty(chunk, dtype=np.int64)  # each buffered row's frame index
        self.xpos, self.xquat = np.empty((chunk, m.nbody, 3)), np.empty((chunk, m.nbody, 4))
        self.sites = np.empty((chunk, m.nsite, 3))
        self.n = 0  # frames buffered
        self.tool_end: dict[str, Array] = {}  # last tool point sent, per robot
        self.robots = list(sim.robots)  # in the order of layout.joints
        self.rates = Rates()  # joint speeds and accelerations, carried across batches
        self.parked: set[int] = set()  # bodies parked out of the world at some frame

    def add(self, rows: Array, index: NDArray[np.int64]) -> None:
        """Append timeline rows ``[sim_time, wall_time, *qpos]`` of frames ``index``,
        sending when full."""
        m, d, kin = self.m, self.d, mujoco.mj_kinematics
        qpos, xpos, xquat, sites = d.qpos, d.xpos, d.xquat, d.site_xpos
        XP, XQ, SP = self.xpos, self.xquat, self.sites
        while len(rows):
            k0 = self.n
            take = min(len(self.rows) - k0, len(rows))
            piece, rows = rows[:take], rows[take:]
            self.index[k0 : k0 + take], index = index[:take], index[take:]
            for k, q in enumerate(piece[:, 2:], start=k0):
                qpos[:] = q
                kin(m, d)
                XP[k] = xpos
                XQ[k] = xquat
                SP[k] = sites
            self.rows[k0 : k0 + take] = piece
            self.n += take
            if self.n == len(self.rows):
                self.flush()

    def flush(self) -> None:
        """Send the buffered frames: body poses, joint values, tool path segments."""
        n = self.n
        if n == 0:
            return
        rec, rows = self.rec, self.rows[:n]
        idx = index_columns(self.index[:n], rows[:, 0], rows[:, 1])
        bodies = [b for b, _ in self.layout.moving]
        # float32 (what rerun stores), body-major so each body's rows are contiguous
        pos = np.ascontiguousarray(self.xpos[:n, bodies].transpose(1, 0, 2), dtype=np.float32)
        quat = wxyz_to_xyzw(self.xquat[:n, bodies].reshape(-1, 4)).reshape(n, -1, 4)
        quat = np.ascontiguousarray(quat.transpose(1, 0, 2), dtype=np.float32)
        away = pos[:, :, 2] > PARKED_ABOVE  # parked bodies: shrunk to nothing at the origin
        self.parked |= {i for i in range(len(bodies)) if away[i].any()}
        for i, (_, ent) in enumerate(self.layout.moving):
            if i in self.parked:
                pos[i][away[i]] = 0.0
                scale = np.where(away[i][:, None], 0.0, 1.0).repeat(3, axis=1)
                cols = rr.Transform3D.columns(translation=pos[i], quaternion=quat[i], scale=scale)
            else:
                cols = rr.Transform3D.columns(translation=pos[i], quaternion=quat[i])
            rec.send_columns(ent, indexes=idx, columns=cols)
        for robot, (ent, adr, revolute, _) in zip(self.robots, self.layout.joints, strict=True):
            q = rows[:, 2 + adr]
            v, a = self.rates.rows(robot, rows[:, 0], q)
            for e, x in ((ent, q), (speed_entity(robot), v), (acceleration_entity(robot), a)):
                x = np.where(revolute, np.degrees(x), x).reshape(-1)
                cols = rr.Scalars.columns(scalars=x).partition(np.full(n, len(adr)))
                rec.send_columns(e, idx, cols)
        for robot, site, ent in self.layout.tools:
            P = self.sites[:n, site]
            prev = np.concatenate([self.tool_end.get(robot, P[:1]), P[:-1]])
            self.tool_end[robot] = P[-1:].copy()
            rec.send_columns(ent, idx, rr.LineStrips3D.columns(strips=_segments(prev, P)))
        self.n = 0
        rec.flush()  # let the sinks catch up: unwritten batches would pile up in memory


# ---------------------------------------------------------------------- events
def log_events(
    rec: rr.RecordingStream,
    sim: Simulator,
    layout: Layout,
    frame: NDArray[np.int64],
    wall: Array,
    first: tuple[int, float, float],
    last: tuple[int, float, float],
) -> None:
    """Events as text logs and the gripper state series. ``frame``/``wall``: each event's
    frame and wall clock (s); ``first``/``last``: (frame, sim_time, wall_time) of the ends."""
    events = sim.timeline.events
    if events:
        idx = index_columns(frame, [e.t for e in events], wall)
        text = [f"[{e.robot or 'cell'}] {e.kind}: {e.detail}" for e in events]
        level = [_LEVELS.get(e.kind, "INFO") for e in events]
        rec.send_columns(EVENTS, idx, rr.TextLog.columns(text=text, level=level))
    for robot in layout.grippers:  # a step: rows (before, after) at each change
        rows, state = [(first[0], first[1], first[2], 0.0)], 0.0
        for i, e in enumerate(events):
            if e.robot == robot and e.kind in ("grasp", "release"):
                new = float(e.kind == "grasp")
                rows += [(frame[i], e.t, wall[i], state), (frame[i], e.t, wall[i], new)]
                state = new
        f, t, w, v = zip(*rows, (last[0], last[1], last[2], state), strict=True)
        rec.send_columns(
            gripper_entity(robot), index_columns(f, t, w), rr.Scalars.columns(scalars=v)
        )
