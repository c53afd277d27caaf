"""Zones: a move blends into the next one instead of stopping at its end.

A motion command with ``zone`` > 0 (m) runs like any other, to a stop at its target, so
the clock, the frames and every read-back are always those of a robot that stopped
there. The simulator keeps it as the robot's :class:`Pending` move. When the robot's
next command is a motion that can blend (a joint move under profile "jerk", or a
linear, circular or, under profile "jerk", straight-line move) and nothing else has
happened on the timeline since (another robot's move, a gripper, a wait, a setting: they
make the stop final; read-backs do not), the simulator takes back the pending move's
tail and runs the corner instead:

- the zone is clipped to half of either move's tool path (reported in the records);
- :func:`path_blend` (two Cartesian moves): the tool leaves the first path ``zone``
  (arc length) before the corner on the blend curve of :func:`~workcell.sim.paths.
  blend_paths` and joins the second ``zone`` after it; the first move's own part, the
  corner and the second move are timed together (:mod:`workcell.sim.timing`), so the
  robot does not slow down for a corner it can take faster (the tool speed changes from
  one move's to the other's across the corner);
- :func:`joint_blend` (a joint move on either side): the robot leaves the first move at
  its first frame whose remaining tool path is within ``zone`` of the corner, and a
  jerk-limited ruckig motion takes it, time-optimally, to the state (joints, speeds,
  accelerations) of the second move at its last frame still within ``zone`` of its
  start; from there it follows the second move. The corner is at least as fast as
  stopping (stopping is one of the motions between those two states).

A blended move's record ends where the robot leaves its path; the corner belongs to the
next command.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell.cell.workcell import RobotPlacement
from workcell.errors import ProgramError
from workcell.sim.cartesian import path_joints
from workcell.sim.jerk import Limits, plan_jerk
from workcell.sim.pathlaw import PathMotion
from workcell.sim.paths import CartesianPath, blend_paths
from workcell.sim.planning import Motion
from workcell.sim.profiles import step_times
from workcell.sim.timeline import TimelineMark
from workcell.sim.timing import sample_params, timed_frames
from workcell.spatial import invert

__all__ = ["Blend", "Pending", "clip_zone", "joint_blend", "path_blend", "tool_lengths"]

Array = NDArray[np.float64]
_FLOOR = 1e-4  # m: a zone (after clipping) below 0.1 mm is a stop (no corner to round)


@dataclass
class Pending:
    """A robot's last move, kept because it has a zone (module doc).

    ``law`` its own frames follow, from global time ``t0``; ``times`` (global) of its own
    frames (after any blend it came out of), the first at frame ``first`` of the
    timeline (or row ``first`` of the block move ``block_move`` inside a concurrent
    block); ``rested``: its own part starts at rest (no blend before it); ``length``:
    its programmed tool path (m); ``speed``/``acceleration``: its tool limits (m/s,
    m/s^2; None for joint moves and straight lines); ``end``: the timeline when it ended
    (a blend needs the timeline unchanged since); ``program``: its record's ``program``
    (:mod:`workcell.sim.cycle`)."""

    robot: str
    command: str
    detail: str
    zone: float
    law: Any
    t0: float
    times: Array
    first: int
    rested: bool
    t_start: float
    activity: dict[str, float]
    head_activity: dict[str, float]
    length: float
    end: TimelineMark
    speed: float | None = None
    acceleration: float | None = None
    block_move: int | None = None
    program: dict[str, Any] | None = None


@dataclass
class Blend:
    """How to run a corner: keep the pending move's first ``keep`` own frames, then its
    new frames ``a_times``/``a_rows`` (global) up to its new end ``a_end``, then the new
    command's frames ``b_times``/``b_rows``. ``next_*``: the law the new command's own
    frames follow (from global ``next_t0``), starting at row ``next_first`` of b."""

    keep: int
    a_times: Array
    a_rows: Array
    a_end: float
    a_activity: dict[str, float]
    b_times: Array
    b_rows: Array
    b_activity: dict[str, float]
    zone: float
    note: str
    next_law: Any
    next_t0: float
    next_first: int
    extra: dict[str, Any] = field(default_factory=dict)


def clip_zone(zone: float, a_length: float, b_length: float) -> tuple[float, str]:
    """The zone used (m) and a note when it had to be clipped to half of a move."""
    z = min(zone, 0.5 * a_length, 0.5 * b_length)
    if z < zone - 1e-12:
        which = "this move" if 0.5 * b_length <= 0.5 * a_length else "the previous move"
        return z, f"zone {zone * 1e3:.4g} mm clipped to {z * 1e3:.4g} mm (half of {which})"
    return z, ""


def tool_lengths(placement: RobotPlacement, Q: Array, q_before: Array | None = None) -> Array:
    """Cumulative tool-point path length (m) through joint rows Q (k, dof), from
    ``q_before`` (or the first row)."""
    rows = Q if q_before is None else np.vstack([q_before, Q])
    P = placement.robot.fk_batch(rows)[:, :3, 3]
    d = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
    return d if q_before is None else d[1:]


def _merge(*acts: dict[str, float]) -> dict[str, float]:
    out: dict[str, float] = {}
    for a in acts:
        for k, v in a.items():
            out[k] = out.get(k, 0.0) + v
    return out


def _own_remaining(p: Pending, placement: RobotPlacement) -> tuple[Array, Array]:
    """Local times of the pending move's own frames and the tool path (m) left after each."""
    local = p.times - p.t0
    if isinstance(p.law, PathMotion):
        done = p.law.tool_length(local)
        return local, p.law.path.length - done
    lengths = tool_lengths(placement, p.law.positions(local))
    return local, lengths[-1] - lengths


def joint_blend(
    p: Pending,
    b: Motion,
    b_length: float,
    placement: RobotPlacement,
    limits: Limits,
    dt: float,
) -> Blend | None:
    """The corner of module doc's joint case, or None when there is nothing to gain (the
    zone is smaller than a frame step) or ruckig finds no motion within the limits."""
    if not (np.all(np.isfinite(limits.jerk)) and np.all(np.isfinite(limits.acceleration))):
        return None
    z, note = clip_zone(p.zone, p.length, b_length)
    if z < _FLOOR or b.law is None or len(b.t) < 2:
        return None
    local, left = _own_remaining(p, placement)
    i_in = int(np.argmax(left <= z + 1e-12))
    if i_in >= len(local) - 1:
        return None
    if isinstance(b.law, PathMotion):
        covered = b.law.tool_length(b.t)
    else:
        covered = tool_lengths(placement, b.rows_of(), b.law.q0)
    j_out = int(np.flatnonzero(covered <= z + 1e-12)[-1]) if covered[0] <= z + 1e-12 else -1
    if j_out < 0 or j_out >= len(b.t) - 1:
        return None
    qa, va, aa = p.law.state(float(local[i_in]))
    qb, vb, ab = b.law.state(float(b.t[j_out]))
    try:
        corner = plan_jerk(qa, qb, limits, v0=va, a0=aa, v1=vb, a1=ab)
    except ProgramError:
        return None
    tb = step_times(corner.duration, dt)
    Rb = corner.positions(tb)
    if len(tb):
        Rb[-1] = qb
    if not all(placement.robot.within_limits(q, 1e-9) for q in Rb):
        return None
    t_cut = float(p.times[i_in])
    shift = t_cut + corner.duration - float(b.t[j_out])
    rest_t = b.t[j_out + 1 :] + shift
    rest_rows = b.rows_of(j_out + 1, len(b.t))
    if isinstance(b.law, PathMotion):
        rest_act = b.law.activity(s_from=float(b.law.profile.at(b.t[j_out : j_out + 1])[0][0]))
    else:
        rest_act = b.activity
    return Blend(
        keep=i_in + 1,
        a_times=np.empty(0),
        a_rows=np.empty((0, len(qa))),
        a_end=t_cut,
        a_activity=p.activity,
        b_times=np.concatenate([t_cut + tb, rest_t]),
        b_rows=np.vstack([Rb, rest_rows]),
        b_activity=_merge(corner.activity(), rest_act),
        extra={"head": corner.activity()},
        zone=z,
        note=note,
        next_law=b.law,
        next_t0=shift,
        next_first=len(tb),
    )


def _frame_q(law: Any, t: float) -> Array:
    return law.positions(np.array([t]))[0]


def path_blend(
    p: Pending,
    path_b: CartesianPath,
    speed: float | None,
    acceleration: float | None,
    placement: RobotPlacement,
    limits: Limits,
    dt: float,
    *,
    step: float,
    max_jump: float,
    command: str,
) -> Blend | None:
    """The corner of module doc's Cartesian case (the pending move's law is a
    :class:`PathMotion`), or None when it cannot be timed from the pending move's state.
    Raises UnreachableError when the new path cannot be followed."""
    law: PathMotion = p.law
    if p.rested:
        keep, t_anchor = 0, p.t0
        s_a, sd_a = 0.0, 0.0
    else:
        keep, t_anchor = 1, float(p.times[0])
        s, sd, _ = law.profile.at(np.array([t_anchor - p.t0]))
        s_a, sd_a = float(s[0]), float(sd[0])
    a_path = law.path.sub(s_a, law.path.span)
    z, note = clip_zone(p.zone, p.length, path_b.length)
    z = min(z, 0.999 * a_path.span)
    if z < _FLOOR:
        return None
    q_anchor = _frame_q(law, t_anchor - p.t0)
    blended = blend_paths(a_path, path_b, z)
    if blended is None:  # the path turns back: the robot stops there
        return None
    path, s_in, s_out = blended
    s_k = sample_params(path, step)
    poses = path.poses(s_k[1:])
    Q = np.vstack(
        [
            q_anchor,
            path_joints(
                placement, q_anchor, poses, s_k[1:] / path.span, max_jump=max_jump, what=command
            ),
        ]
    )
    big = 1e6
    va, vb = (big if p.speed is None else p.speed), (big if speed is None else speed)
    aa, ab = (
        (big if p.acceleration is None else p.acceleration),
        (big if acceleration is None else acceleration),
    )
    knots = np.array([0.0, s_in, s_out, path.span])
    timed = timed_frames(
        placement.robot, invert(placement.base), path, Q, s_k, dt, command, limits=limits,
        speed=None if p.speed is None and speed is None else (knots, np.array([va, va, vb, vb])),
        acceleration=None
        if p.acceleration is None and acceleration is None
        else (knots, np.array([aa, aa, ab, ab])),
        sd_start=sd_a,
    )  # fmt: skip
    if timed is None:
        return None
    new, t, rows = timed
    if rows is None:  # a very long corner: its frames made here, not checked
        rows = new.positions(t)
        rows[-1] = Q[-1]
    t_in = new.profile.time_at(s_in)
    n_a = int(np.searchsorted(t, t_in, side="right"))
    s_frames = new.profile.at(t)[0]
    first_own = int(np.searchsorted(s_frames, s_out, side="left"))
    glob = t_anchor + t
    return Blend(
        keep=keep,
        a_times=glob[:n_a],
        a_rows=rows[:n_a],
        a_end=t_anchor + t_in,
        a_activity=_merge(p.head_activity, new.activity(0.0, s_in)),
        b_times=glob[n_a:],
        b_rows=rows[n_a:],
        b_activity=new.activity(s_in, math.inf),
        extra={"head": new.activity(s_in, s_out)},
        zone=z,
        note=note,
        next_law=new,
        next_t0=t_anchor,
        next_first=max(first_own - n_a, 0),
    )
