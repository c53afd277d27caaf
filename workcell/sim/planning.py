"""Joint-space motion plans: the frames of one move or of a path through waypoints.

A plan is the simulated times (k,) of a motion's frames (s) and its joint values
(k, dof; rad/m), the last row exactly the target. The simulator's modes (thesis §4.4):

- path and playback (eq. 4.27, 4.28): all joints together along the segment, with the
  normalised progress of the time profile (:mod:`workcell.sim.profiles`), sampled every
  dt with one remainder step; the rows are given as a function of a row range, so a long
  motion is never held in memory at once;
- joint-by-joint: the joints one after another (joint 1 first), each with its own
  duration; on the thesis's clock only the joint that moves most advances the time
  (the other joints' frames share one time), on the "sequential" clock every joint does.

:func:`plan_waypoints` goes through joint waypoints, linearly in joints between them at
the robot's speed (a straight line's samples).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from workcell.sim import profiles
from workcell.sim.profiles import step_times

__all__ = ["Rows", "plan_move", "plan_waypoints"]

Array = NDArray[np.float64]
Rows = Array | Callable[[int, int], Array]  # joint rows of a plan, or rows(lo, hi)


def plan_move(
    q0: Array,
    target: Array,
    *,
    start: float,
    speed: float,
    dt: float,
    joint_by_joint: bool = False,
    clock: str = "thesis",
    profile: str = "linear",
    acceleration: float = 2.0,
) -> tuple[Array, Rows]:
    """Frames of one move from ``q0`` to ``target`` starting at simulated time ``start``
    (s), at ``speed`` (rad/s, the joint that moves most), sampled every ``dt`` (s); see the
    module doc. No motion gives no frames."""
    delta = target - q0
    big = float(np.max(np.abs(delta))) if len(delta) else 0.0
    if big == 0.0:
        return np.empty(0), np.empty((0, len(q0)))
    if not joint_by_joint:  # path and playback: eq. 4.27, 4.28
        T = profiles.duration(profile, big, speed, acceleration)
        t = step_times(T, dt)
        s = profiles.progress(profile, t, T, big, speed, acceleration)
        last = len(t) - 1

        def rows(lo: int, hi: int) -> Array:
            Q = q0 + np.outer(s[lo:hi], delta)
            if hi > last:
                Q[last - lo] = target
            return Q

        return start + t, rows
    times, out = [], []
    q = q0.copy()
    now = start
    fastest = int(np.argmax(np.abs(delta)))
    for i in np.flatnonzero(delta):
        di = abs(float(delta[i]))
        Ti = profiles.duration(profile, di, speed, acceleration)
        t = step_times(Ti, dt)
        Q = np.repeat(q[None, :], len(t), axis=0)
        Q[:, i] = q0[i] + delta[i] * profiles.progress(profile, t, Ti, di, speed, acceleration)
        Q[-1, i] = target[i]
        q[i] = target[i]
        if clock == "sequential" or i == fastest:
            times.append(now + t)
            now += Ti
        else:  # thesis: the clock runs only while the joint that moves most moves
            times.append(np.full(len(t), now))
        out.append(Q)
    return np.concatenate(times), np.concatenate(out)


def plan_waypoints(
    q0: Array, waypoints: Array, *, start: float, speed: float, dt: float
) -> tuple[Array, Array]:
    """Path-mode frames from ``q0`` through joint ``waypoints`` (k, dof), linear in joints
    between them, each segment taking max |dq| / ``speed`` (s); starts at ``start`` (s)."""
    times, rows = [np.empty(0)], [np.empty((0, len(q0)))]
    now, prev = start, q0
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
    return np.concatenate(times), np.concatenate(rows)
