"""Record a finished simulation's timeline to rerun: an ``.rrd`` file or a live viewer.

:func:`record` writes the whole :class:`~workcell.sim.timeline.Timeline` of a
:class:`~workcell.sim.simulator.Simulator`; :func:`log_timeline` is its core and logs into
any :class:`rerun.RecordingStream` (file, spawned viewer, connected viewer: one code path).

Layout of the recording (entity paths; names escaped with ``rr.escape_entity_path_part``):

- ``/world``: right-handed, z up, metres;
- ``/world/bodies/{body}``: the body's world pose (``Transform3D``, quaternion xyzw) per
  frame; bodies welded to the world (robot bases) get one static pose, and the world
  body (``/world/bodies/world``: ground, static parts, cameras) none;
- ``/world/bodies/{body}/{geom}``: static geometry in the body frame (``Mesh3D`` from the
  compiled model's meshes with flat face normals, primitives, the ground as a quad);
  collision-only geoms (group 3) are skipped; cameras as ``Pinhole`` frusta (MuJoCo's -z
  view axis, y up);
- ``/world/tool_paths/{robot}``: the tool-centre point's path, one segment per frame
  (previous point -> this point; the blueprint shows all segments up to the cursor);
- ``/joints/{robot}``: the robot's joint values, one named series per joint (``Scalars``
  with one value per joint, in DH order): **degrees** for revolute joints, metres for
  prismatic ones (each series name says its unit, e.g. ``"j2 (deg)"``);
- ``/joint_speeds/{robot}`` and ``/joint_accelerations/{robot}``: their finite-difference
  speeds (deg/s, m/s) and accelerations (deg/s^2, m/s^2), shown in tabs beside the angles
  (:mod:`workcell.record.rr_rates`);
- ``/gripper/{robot}``: 1 while the robot holds a part (from its ``grasp`` event to its
  ``release`` event), else 0; logged at the changes, the start and the end;
- ``/events``: every timeline event as a ``TextLog`` (``error``: ERROR, ``collision``:
  WARN, ``grasp``/``release``: INFO, ``move``/``wait``/``speed``: DEBUG, others: INFO);
- a cell with devices or a run of ``run_programs``: ``/world/sensors``, ``/world/sinks``,
  ``/signals``, ``/programs`` and ``/results`` (the throughput and the Gantt chart), see
  :mod:`workcell.record.rr_devices`; a body parked out of the world (a source's copy not
  made yet, a part a sink removed) is shrunk to nothing.

Timelines: ``frame`` (sequence: the frame index), ``sim_time`` (duration, integer ns: the
simulated clock; frames may share one, e.g. under joint-by-joint mode's thesis clock) and
``wall_time`` (duration, integer ns: the simulator's stopwatch). An event sits on its
``frame`` (the last frame when it happened), at its own simulated time and that frame's
wall time; an event without a frame (-1) on the last frame whose simulated time is <= its
time.

Frames kept: by default 60 per simulated second (``fps``; :func:`kept_frames`): the first
frame at or after each 1/60 s, the first and last frames, and every event's frame, so a
1 kHz run makes a file 1/16 the size while grasps, releases, collisions and errors show
at their exact frame, pose and time (``fps=None`` keeps every frame). Frames that share
one simulated time (joint-by-joint mode's thesis clock) keep only the first.

Body poses come from ``mujoco.mj_kinematics`` on the frame's full ``qpos`` in a scratch
``MjData`` (the simulator's own data is not touched). The timeline is read block by block
(:meth:`~workcell.sim.timeline.Timeline.iter_blocks`, spilled blocks included) and sent in
batches of ``chunk_frames`` frames with ``send_columns``, so memory stays bounded
(:mod:`workcell.record.rr_frames`).
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import mujoco
import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from numpy.typing import ArrayLike, NDArray
from tqdm import tqdm

from workcell.cli_common import check_recording_path
from workcell.errors import RecordError
from workcell.files import atomic_path
from workcell.record.camera import camera_eye, overview_camera
from workcell.record.rr_devices import PROGRAMS, RESULTS, SIGNALS, has_logic, log_devices
from workcell.record.rr_frames import Frames, log_events
from workcell.record.rr_rates import Rates, acceleration_entity, speed_entity
from workcell.record.rr_scene import (
    EVENTS,
    GRIPPERS,
    JOINTS,
    WORLD,
    Layout,
    body_entity,
    entity_part,
    gripper_entity,
    joint_entity,
    log_static,
    tool_path_entity,
)

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = [
    "DEFAULT_CHUNK_FRAMES",
    "DEFAULT_FPS",
    "RecordError",
    "RecordStats",
    "body_entity",
    "check_recording_path",
    "default_blueprint",
    "gripper_entity",
    "joint_entity",
    "kept_frames",
    "log_timeline",
    "record",
    "tool_path_entity",
]

DEFAULT_CHUNK_FRAMES = 8192
DEFAULT_FPS = 60.0  # frames per simulated second a recording keeps (events exact)
DEFAULT_PORT = 9876

Array = NDArray[np.float64]


@dataclass(frozen=True)
class RecordStats:
    """What :func:`record` wrote: ``frames`` and ``events`` logged, ``moving_bodies``
    (bodies with a pose per frame), ``seconds`` (wall time of the recording, s),
    ``path`` and ``bytes`` (the ``.rrd`` file and its size; None when only streamed)."""

    frames: int
    events: int
    moving_bodies: int
    seconds: float
    path: Path | None = None
    bytes: int | None = None


def _check_fps(fps: object) -> None:
    if fps is not None and not (
        isinstance(fps, (int, float)) and not isinstance(fps, bool) and 0 < fps <= 1e6
    ):
        raise RecordError(
            f"fps must be a number of frames per simulated second in (0, 1e6], or None for "
            f"every frame; got {fps!r}"
        )


# ---------------------------------------------------------------------- public
def _overview_eye(sim: Simulator) -> tuple[Array, Array]:
    """Eye and look-at points (m) of the overview camera over the run's first and last
    frames (the camera of the project's pictures: the whole cell in view)."""
    qs = [sim.timeline.frame(0)[2], sim.timeline.frame(-1)[2]]
    return camera_eye(overview_camera(sim.model, qs))


def default_blueprint(
    robots: Sequence[str],
    *,
    grippers: bool = True,
    logic: bool = False,
    eye: tuple[ArrayLike, ArrayLike] | None = None,
) -> rrb.Blueprint:
    """The default layout: the 3D cell (tool paths drawn up to the cursor; seen from
    ``eye`` = (eye point, look-at point), m, when given: :func:`record` gives the overview
    camera's, which frames the whole cell) beside, per robot, tabs of its joint angles,
    speeds and accelerations, the gripper states (with ``grippers``), with ``logic`` tabs
    of the signals, the programs' activity, the Gantt chart and the throughput
    (:mod:`workcell.record.rr_devices`), and the event log; the time panel on
    ``sim_time``."""
    trail = rrb.VisibleTimeRanges(
        timeline="sim_time",
        start=rrb.TimeRangeBoundary.infinite(),
        end=rrb.TimeRangeBoundary.cursor_relative(),
    )
    controls = None
    if eye is not None:
        controls = rrb.EyeControls3D(
            kind=rrb.Eye3DKind.Orbital, position=eye[0], look_target=eye[1], eye_up=(0, 0, 1)
        )
    view3d = rrb.Spatial3DView(
        origin=WORLD,
        name="Workcell",
        overrides={tool_path_entity(r): trail for r in robots},
        eye_controls=controls,
    )
    plots = [
        rrb.Tabs(
            rrb.TimeSeriesView(origin=f"{JOINTS}/{entity_part(r)}", name=f"{r} joints (deg)"),
            rrb.TimeSeriesView(origin=speed_entity(r), name=f"{r} joint speeds (deg/s)"),
            rrb.TimeSeriesView(
                origin=acceleration_entity(r), name=f"{r} joint accelerations (deg/s^2)"
            ),
        )
        for r in robots
    ]
    cell_logic = rrb.Tabs(
        rrb.TimeSeriesView(origin=SIGNALS, name="Signals"),
        rrb.TimeSeriesView(origin=PROGRAMS, name="Programs: moving (2) / waiting (1) / idle (0)"),
        rrb.Spatial2DView(origin=f"{RESULTS}/gantt", name="Gantt chart"),
        rrb.TextDocumentView(origin=f"{RESULTS}/throughput", name="Throughput"),
    )
    side = rrb.Vertical(
        *plots,
        *([rrb.TimeSeriesView(origin=GRIPPERS, name="Gripper closed (1) / open (0)")] * grippers),
        *([cell_logic] * logic),
        rrb.TextLogView(origin=EVENTS, name="Events"),
    )
    return rrb.Blueprint(
        rrb.Horizontal(view3d, side, column_shares=[3, 2]),
        rrb.TimePanel(timeline="sim_time"),
    )


def kept_frames(
    times: Array, fps: float | None, must: NDArray[np.int64] | None = None
) -> NDArray[np.bool_]:
    """Which frames a recording at ``fps`` keeps (a mask over ``times``, the frames'
    simulated times, s): the first frame at or after each multiple of 1/fps from the first
    frame's time, the first and last frames, and the frames in ``must`` (the events'
    frames, so every event shows at its exact pose and time). ``fps`` None: every frame."""
    n = len(times)
    if fps is None or n == 0:
        return np.ones(n, dtype=bool)
    keep = np.zeros(n, dtype=bool)
    count = math.floor((times[-1] - times[0]) * fps + 1e-9) + 1  # samples
    if count <= n:
        samples = times[0] + np.arange(count) / fps
        keep[np.minimum(np.searchsorted(times, samples - 1e-9, side="left"), n - 1)] = True
    else:  # denser than the frames (fps 1e6: 10^10 samples): which frames they hit, O(n)
        # frame i is kept when a sample lies in (times[i-1], times[i]] (shifted by 1e-9)
        below = np.floor((times - times[0] + 1e-9) * fps)  # samples at or before each frame
        keep[1:] = below[1:] > below[:-1]
    keep[[0, n - 1]] = True
    if must is not None and len(must):
        keep[must] = True
    return keep


def log_timeline(
    rec: rr.RecordingStream,
    sim: Simulator,
    *,
    fps: float | None = DEFAULT_FPS,
    chunk_frames: int = DEFAULT_CHUNK_FRAMES,
    progress: bool | None = None,
) -> RecordStats:
    """Log ``sim``'s whole timeline into ``rec`` (see the module doc for the layout).

    ``fps``: frames per simulated second to keep (:func:`kept_frames`: events keep their
    exact frames; None: every frame); ``chunk_frames``: frames per ``send_columns`` batch
    (memory ~ 1.4 kB per frame for a two-robot cell); ``progress``: a tqdm bar on stderr
    (None: only on a terminal and for more than 50,000 frames). Returns what was logged
    (``path``/``bytes`` None).
    """
    if not (isinstance(chunk_frames, (int, np.integer)) and chunk_frames >= 1):
        raise RecordError(f"chunk_frames must be an integer >= 1, got {chunk_frames!r}")
    _check_fps(fps)
    c0 = time.perf_counter()
    tl = sim.timeline
    layout = Layout.of(sim)
    n = len(tl)
    if n == 0:
        raise RecordError("the simulator's timeline has no frames: nothing to record")
    t0, w0, q0 = tl.frame(0)
    d0 = mujoco.MjData(sim.model)
    d0.qpos[:] = q0
    mujoco.mj_kinematics(sim.model, d0)
    log_static(rec, sim, layout, d0)
    for robot, (_, _, _, labels) in zip(sim.robots, layout.joints, strict=True):
        Rates.log_static(rec, robot, labels)
    events = tl.events
    times = tl.sim_times()
    te = np.array([e.t for e in events])
    ef = np.array([getattr(e, "frame", -1) for e in events], dtype=np.int64)
    # each event's own frame, else the last one whose sim_time <= its t
    by_time = np.maximum(np.searchsorted(times, te, side="right") - 1, 0)
    ev_frame = np.where(ef >= 0, np.minimum(ef, n - 1), by_time).astype(np.int64)
    ev_wall = tl.wall_times()[ev_frame] if len(events) else np.zeros(0)
    keep = kept_frames(times, fps, ev_frame)
    frames = Frames(rec, sim, layout, int(chunk_frames))
    show = progress if progress is not None else (sys.stderr.isatty() and n > 50_000)
    last = first = (0, t0, w0)
    with tqdm(total=n, unit="frame", desc="record", leave=False, disable=not show) as bar:
        for start, rows in tl.iter_blocks():
            mine = keep[start : start + len(rows)]
            frames.add(rows[mine], np.flatnonzero(mine) + start)
            last = (start + len(rows) - 1, float(rows[-1, 0]), float(rows[-1, 1]))
            bar.update(len(rows))
        frames.flush()
    log_events(rec, sim, layout, ev_frame, ev_wall, first, last)
    if has_logic(sim):
        log_devices(rec, sim, ev_frame, ev_wall, first, last)
    return RecordStats(int(keep.sum()), len(events), len(layout.moving), time.perf_counter() - c0)


def _spawn_viewer(port: int) -> str:
    """Start a rerun viewer listening on ``port``; return its gRPC URL."""
    rr.spawn(port=port, connect=False)
    return f"rerun+http://127.0.0.1:{port}/proxy"


def record(
    sim: Simulator,
    path: str | os.PathLike[str] | None = None,
    *,
    spawn: bool = False,
    connect: str | None = None,
    port: int = DEFAULT_PORT,
    fps: float | None = DEFAULT_FPS,
    chunk_frames: int = DEFAULT_CHUNK_FRAMES,
    progress: bool | None = None,
    application_id: str = "workcell",
    recording_id: str | None = None,
    images_fps: float | None = None,
    image_camera: str | None = None,
    image_size: tuple[int, int] = (640, 480),
) -> RecordStats:
    """Record a finished simulator's whole timeline with the default blueprint.

    Destinations (any combination, at least one; all on the same code path): ``path``, an
    ``.rrd`` file written atomically (a temp file in the same folder, renamed when
    complete); ``spawn``: start a viewer on ``port`` and stream to it; ``connect``: stream
    to a running viewer's gRPC URL (e.g. ``"rerun+http://127.0.0.1:9876/proxy"``).
    Times: simulated and wall clocks as ns durations, ``frame`` as a sequence; lengths in
    metres, joint angles in degrees. ``fps`` (frames kept per simulated second, default
    60; every event's frame is kept, so events show at their exact pose and time; None:
    every frame), ``chunk_frames`` and ``progress``: see :func:`log_timeline`. ``recording_id``: default a fresh UUID. ``images_fps``: also
    render the run every 1/images_fps simulated seconds from ``image_camera`` (default:
    the overview) at ``image_size`` (width, height pixels) and log the pictures (see
    :mod:`workcell.record.rr_images`). Returns a :class:`RecordStats` (``path`` and
    ``bytes`` set when a file was written).
    """
    if path is None and not spawn and connect is None:
        raise RecordError("record: nowhere to record to; give a path, spawn=True or connect=URL")
    if connect is not None and not (isinstance(connect, str) and "://" in connect):
        raise RecordError(
            f"connect must be a viewer URL such as 'rerun+http://127.0.0.1:9876/proxy', "
            f"got {connect!r}"
        )
    if images_fps is not None and not (
        isinstance(images_fps, (int, float)) and 0 < images_fps < 1000
    ):
        raise RecordError(f"images_fps must be a number in (0, 1000) per s, got {images_fps!r}")
    _check_fps(fps)
    if not (isinstance(port, int) and 0 < port < 65536):
        raise RecordError(f"port must be an integer in 1..65535, got {port!r}")
    target = None if path is None else check_recording_path(path)  # before the work
    with contextlib.ExitStack() as stack:
        tmp = (
            None if target is None else stack.enter_context(atomic_path(target, error=RecordError))
        )
        rec = rr.RecordingStream(application_id, recording_id=recording_id)
        rec.set_log_time_enabled(False)
        try:
            bp = default_blueprint(
                sim.robots,
                grippers=bool(sim.compiled.gripper_bodies),
                logic=has_logic(sim),
                eye=_overview_eye(sim),
            )
            sinks: list[rr.FileSink | rr.GrpcSink] = [rr.FileSink(tmp)] if tmp is not None else []
            sinks += [rr.GrpcSink(_spawn_viewer(port))] if spawn else []
            sinks += [rr.GrpcSink(connect)] if connect is not None else []
            rec.set_sinks(*sinks, default_blueprint=bp)
            stats = log_timeline(rec, sim, fps=fps, chunk_frames=chunk_frames, progress=progress)
            if images_fps is not None:
                from workcell.record.rr_images import log_images

                w, h = image_size
                log_images(rec, sim, fps=images_fps, camera=image_camera, width=w, height=h)
            rec.flush()
        except RuntimeError as exc:
            if not (spawn or connect):
                raise
            url = connect or f"port {port}"
            raise RecordError(f"streaming to the rerun viewer at {url} failed: {exc}") from exc
        finally:
            rec.disconnect()
    size = target.stat().st_size if target is not None else None
    return RecordStats(stats.frames, stats.events, stats.moving_bodies, stats.seconds, target, size)
