"""Joint-space motion plans: the frames of one move or of a path through waypoints.

A plan is a :class:`Motion`: the local times (k,) of a motion's frames (s from its
start), its joint values (k, dof; rad/m, the last row exactly the target), which limits
were active for how long (for the cycle-time report) and, for motions that can blend
into the next (profile "jerk", Cartesian moves), the law they follow. The simulator's
modes (thesis §4.4):

- path and playback (eq. 4.27, 4.28): all joints together along the segment, with the
  normalised progress of the time profile (:mod:`workcell.sim.profiles`), sampled every
  dt with one remainder step; the rows are given as a function of a row range, so a long
  motion is never held in memory at once. Profile "jerk": the time-optimal
  synchronised jerk-limited motion of :mod:`workcell.sim.jerk` instead;
- joint-by-joint: the joints one after another (joint 1 first), each with its own
  duration; on the thesis's clock only the joint that moves most (profile "jerk": the
  one that takes longest) advances the time (the other joints' frames share one time),
  on the "sequential" clock every joint does.

:func:`plan_waypoints` goes through joint waypoints, linearly in joints between them at
the robot's speed (a straight line's samples, the thesis's timing).

A move in which no joint moves more than :data:`STILL` (1e-12 rad, or m for a prismatic
joint) is no move: no frames and no time, in every profile. That is a million times
below an encoder count of any robot here, and above where the jerk profile's own
arithmetic ends: ruckig takes a move shorter than its position precision as already at
its target (measured: 5.6e-17 to 5.6e-13 rad over speed limits of 1 mrad/s to 100 rad/s,
accelerations of 1e-4 to 200 rad/s^2 and jerks of 1e-6 to 1e4 rad/s^3), while the
minimum time of a jerk-limited move grows as the cube root of its length (a 1.6e-33 rad
move would "take" 7.1e-12 s). Without one threshold for all, profiles would disagree on
moves that differ from standing still only in the last bits of a float.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell import limits as work_limits
from workcell.sim import profiles
from workcell.sim.jerk import Limits, plan_jerk
from workcell.sim.profiles import step_times

__all__ = [
    "STILL",
    "Motion",
    "Rows",
    "check_frames",
    "frames_of",
    "law_rows",
    "plan_move",
    "plan_waypoints",
]

Array = NDArray[np.float64]
STILL = 1e-12  # rad (m): a move whose joints all move at most this far is no move
Rows = Array | Callable[[int, int], Array]  # joint rows of a plan, or rows(lo, hi)


@dataclass
class Motion:
    """A planned motion of one robot (module doc): frame times ``t`` (k,; s from its
    start), joint ``rows``, ``activity`` (seconds per active limit) and ``law`` (a
    :class:`~workcell.sim.jerk.JerkMove` or :class:`~workcell.sim.pathlaw.PathMotion`, or
    None when it cannot blend)."""

    t: Array
    rows: Rows
    activity: dict[str, float] = field(default_factory=dict)
    law: Any = None

    @property
    def duration(self) -> float:
        """Its duration (s): the last frame's time (0 without frames)."""
        return float(self.t[-1]) if len(self.t) else 0.0

    def rows_of(self, lo: int = 0, hi: int | None = None) -> Array:
        """Rows lo:hi as an array."""
        hi = len(self.t) if hi is None else hi
        return self.rows(lo, hi) if callable(self.rows) else np.asarray(self.rows[lo:hi])


def frames_of(duration: float, dt: float, what: str) -> Array:
    """The sample times of a motion of ``duration`` (s) every ``dt`` (s), after checking
    the work budget (``max_frames_per_command``, naming ``what``) before they are made. A
    duration that overflows (a speed, override or acceleration of 1e-320) is over
    ``max_sim_time``."""
    check_frames(duration, dt, 0, what)
    return step_times(duration, dt)  # (which checks again, without the command's name)


def check_frames(duration: float, dt: float, extra: int, what: str) -> None:
    """The work budget of a motion of ``duration`` (s) sampled every ``dt`` (s) plus
    ``extra`` frames: ``max_frames_per_command``, and ``max_sim_time`` for a duration that
    overflowed (a speed, override or acceleration of 1e-320). Counted in floats: a count
    of 1e300 frames is refused, never turned into an integer."""
    if not math.isfinite(duration):
        work_limits.check(
            "max_sim_time",
            duration,
            f"{what}: the motion's duration (its speed, override or acceleration is too small)",
        )
    work_limits.check("max_frames_per_command", duration / dt + extra, what)


def law_rows(law: Any, t: Array, target: Array) -> Rows:
    """Rows of a law (anything with ``positions(t)``) at times t, built on demand (rows(lo,
    hi): a long motion is never held at once), the last one exactly ``target``."""
    last = len(t) - 1

    def rows(lo: int, hi: int) -> Array:
        Q = law.positions(t[lo:hi])
        if hi > last:
            Q[last - lo] = target
        return Q

    return rows


def plan_move(
    q0: Array,
    target: Array,
    *,
    speed: float,
    dt: float,
    joint_by_joint: bool = False,
    clock: str = "thesis",
    profile: str = "linear",
    acceleration: float = 2.0,
    limits: Limits | None = None,
    what: str = "move",
) -> Motion:
    """One move from ``q0`` to ``target`` (module doc) at ``speed`` (rad/s, the joint that
    moves most; thesis profiles) or within ``limits`` (profile "jerk"), sampled every
    ``dt`` (s). No motion (no joint moving more than :data:`STILL`) gives no frames;
    more than the work budget's frames per command raise LimitError naming ``what``."""
    delta = target - q0
    big = float(np.max(np.abs(delta))) if len(delta) else 0.0
    if big <= STILL:
        return Motion(np.empty(0), np.empty((0, len(q0))))
    jerk = profile == "jerk"
    if not joint_by_joint:  # path and playback: eq. 4.27, 4.28
        if jerk:
            law = plan_jerk(q0, target, limits)  # type: ignore[arg-type]
            t = frames_of(law.duration, dt, what)
            return Motion(t, law_rows(law, t, target), law.activity(), law)
        T = profiles.duration(profile, big, speed, acceleration)
        t = frames_of(T, dt, what)
        s = profiles.progress(profile, t, T, big, speed, acceleration)
        last = len(t) - 1

        def rows(lo: int, hi: int) -> Array:
            Q = q0 + np.outer(s[lo:hi], delta)
            if hi > last:
                Q[last - lo] = target
            return Q

        return Motion(t, rows, profiles.activity(profile, big, speed, acceleration))
    moving = np.flatnonzero(delta)
    shapes = {}  # joint -> (duration, positions at times, activity)
    for i in moving:
        di = abs(float(delta[i]))
        if jerk:
            one = Limits(*(x[i : i + 1] for x in (limits.speed, limits.acceleration, limits.jerk)))  # type: ignore[union-attr]
            law1 = plan_jerk(q0[i : i + 1], target[i : i + 1], one)
            act = {k.replace("j1 ", f"j{i + 1} "): v for k, v in law1.activity().items()}
            shapes[i] = (law1.duration, lambda t, law1=law1: law1.positions(t)[:, 0], act)
        else:
            Ti = profiles.duration(profile, di, speed, acceleration)
            shapes[i] = (
                Ti,
                lambda t, i=i, di=di, Ti=Ti: (
                    q0[i] + delta[i] * profiles.progress(profile, t, Ti, di, speed, acceleration)
                ),
                profiles.activity(profile, di, speed, acceleration),
            )
    longest = max(moving, key=lambda i: shapes[i][0]) if jerk else int(np.argmax(np.abs(delta)))
    times, out, activity = [], [], {}
    q = q0.copy()
    now = 0.0
    total = sum(shapes[i][0] for i in moving)
    check_frames(total, dt, len(moving), what)
    for i in moving:
        Ti, at, act = shapes[i]
        t = step_times(Ti, dt)
        Q = np.repeat(q[None, :], len(t), axis=0)
        Q[:, i] = at(t)
        Q[-1, i] = target[i]
        q[i] = target[i]
        if clock == "sequential" or i == longest:
            times.append(now + t)
            now += Ti
            for k, v in act.items():
                activity[k] = activity.get(k, 0.0) + v
        else:  # thesis: the clock runs only while the joint that moves most moves
            times.append(np.full(len(t), now))
        out.append(Q)
    return Motion(np.concatenate(times), np.concatenate(out), activity)


def plan_waypoints(
    q0: Array, waypoints: Array, *, speed: float, dt: float, what: str = "move"
) -> Motion:
    """Path-mode frames from ``q0`` through joint ``waypoints`` (k, dof), linear in joints
    between them, each segment taking max |dq| / ``speed`` (s)."""
    steps = (
        np.abs(np.diff(np.vstack([q0, waypoints]), axis=0)).max(axis=1) if len(waypoints) else []
    )
    with np.errstate(divide="ignore", over="ignore"):
        total = float(np.sum(steps)) / speed if speed > 0 else math.inf
    check_frames(total, dt, len(waypoints), what)
    times, rows = [np.empty(0)], [np.empty((0, len(q0)))]
    now, prev = 0.0, q0
    for q in waypoints:
        d = q - prev
        big = float(np.max(np.abs(d)))
        if big == 0.0:
            continue
        T = big / speed
        t = step_times(T, dt)
        R = prev + np.outer(t / T, d)
        R[-1] = q
        times.append(now + t)
        rows.append(R)
        now += T
        prev = q
    return Motion(np.concatenate(times), np.concatenate(rows), {"robot speed": now})
