"""Time profiles of a joint-space motion: the thesis's constant speed and two smoother ones.

(The fourth profile, ``"jerk"``, is not a normalised progress: each joint's own speed,
acceleration and jerk limits set a time-optimal motion, see :mod:`workcell.sim.jerk`.
The three below are the *thesis profiles*: the robot's one speed sets their time.)

A motion covers ``distance`` (rad or m, the largest joint motion) with peak speed
``speed`` (rad/s); every joint follows the same normalised progress s(t) in [0, 1]:

- ``"linear"`` (thesis eq. 4.27): s = t / T, T = distance / speed; the speed jumps at the
  ends.
- ``"trapezoid"``: constant acceleration ``acceleration`` (rad/s^2) up to ``speed``,
  cruise, constant deceleration; T = distance / speed + speed / acceleration, or, when
  the motion is too short to reach the speed, a triangle with T = 2 sqrt(distance /
  acceleration).
- ``"quintic"``: s = 10 tau^3 - 15 tau^4 + 6 tau^5 (tau = t / T), zero speed and
  acceleration at both ends; T = 1.875 distance / speed so its peak speed is ``speed``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from workcell import limits

__all__ = ["PROFILES", "THESIS_PROFILES", "activity", "duration", "progress", "step_times"]

_REMAINDER_TOL = 1e-9  # a remainder below this fraction of dT is no step

THESIS_PROFILES = ("linear", "trapezoid", "quintic")
PROFILES = (*THESIS_PROFILES, "jerk")
Array = NDArray[np.float64]


def duration(profile: str, distance: float, speed: float, acceleration: float) -> float:
    """Duration (s) of a motion of ``distance`` at peak ``speed`` (see the module doc)."""
    if distance <= 0:
        return 0.0
    if not (speed > 0 and (profile != "trapezoid" or acceleration > 0)):
        return math.inf  # a speed that underflowed (1e-320 x an override): it never ends
    if profile == "linear":
        return distance / speed
    if profile == "quintic":
        return 1.875 * distance / speed
    if distance >= speed * speed / acceleration:
        return distance / speed + speed / acceleration
    return 2.0 * math.sqrt(distance / acceleration)


def activity(profile: str, distance: float, speed: float, acceleration: float) -> dict[str, float]:
    """Seconds during which the robot's speed or acceleration is what the motion runs at
    (the thesis profiles' "limits": ``"robot speed"``, ``"robot acceleration"``)."""
    T = duration(profile, distance, speed, acceleration)
    if profile != "trapezoid" or T == 0.0:
        return {"robot speed": T}
    v = min(speed, math.sqrt(distance * acceleration))
    accelerating = 2.0 * v / acceleration
    return {"robot acceleration": accelerating, "robot speed": T - accelerating}


def progress(
    profile: str, t: Array, T: float, distance: float, speed: float, acceleration: float
) -> Array:
    """Normalised progress s(t) in [0, 1] at times ``t`` (s) in [0, T] (module doc)."""
    t = np.clip(np.asarray(t, dtype=np.float64), 0.0, T)
    if profile == "linear":
        return t / T
    if profile == "quintic":
        tau = t / T
        return tau**3 * (10.0 + tau * (-15.0 + 6.0 * tau))
    a = acceleration
    v = min(speed, math.sqrt(distance * a))  # the peak speed actually reached
    ta = v / a  # acceleration phase (s)
    x = np.where(
        t < ta,
        0.5 * a * t * t,
        np.where(t <= T - ta, 0.5 * a * ta * ta + v * (t - ta), distance - 0.5 * a * (T - t) ** 2),
    )
    return np.clip(x / distance, 0.0, 1.0)


def step_times(T: float, dt: float) -> Array:
    """Sample times in (0, T] of a motion of duration T sampled every dt (thesis eq. 4.27).

    ``T = m dt + Delta T``: the m full steps ``dt, 2 dt, ..., m dt`` then the remainder
    step ending at T exactly; when ``Delta T`` is zero (below 1e-9 dt) the last full step
    is the end and its time is set to T exactly. T = 0 gives no samples.
    """
    if not T > 0:
        return np.empty(0)
    limits.check("max_frames_per_command", T / dt, f"a motion of {T:.4g} s sampled every {dt:g} s")
    m = math.floor(T / dt)
    rem = T - m * dt
    t = dt * np.arange(1, m + 1, dtype=np.float64)
    if rem > _REMAINDER_TOL * dt:
        return np.append(t, T)
    if len(t) == 0:  # T is below the tolerance itself: one step
        return np.array([T])
    t[-1] = T
    return t
