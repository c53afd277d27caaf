"""Jerk-limited joint motions (profile ``"jerk"``), computed offline with ruckig.

A joint move from rest to rest is the time-optimal motion under every joint's speed,
acceleration and jerk limits (the seven-phase profile: jerk up, constant acceleration,
jerk down, cruise, and the mirror image), with all joints synchronised so that they
finish together: its duration is the largest single-joint minimum time. Joints reach
their targets on a straight line in joint space (ruckig's phase synchronisation) unless
that would break a limit, in which case each joint keeps its own profile shape (time
synchronisation) and the duration is the same.

A blend between two moves is a ruckig motion from one state (positions, speeds,
accelerations) to another, again time-optimal under the limits.

ruckig is the community build, used point to point only: its intermediate-waypoint
mode sends the trajectory to a web service, so this module never constructs it with
waypoints (``Ruckig(dof)`` without a control cycle: offline calculation).

:class:`Limits` carries the limits of one robot with the speed override applied (speeds
x f, accelerations x f^2, jerks x f^3, so a motion keeps its path and takes 1/f the time).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from ruckig import InputParameter, Result, Ruckig, RuckigError, Synchronization, Trajectory

from workcell import limits as work_limits
from workcell.errors import ProgramError
from workcell.robots.robot import Robot

__all__ = ["JerkMove", "Limits", "joint_limits", "plan_jerk", "require_finite"]

Array = NDArray[np.float64]
_ACTIVE = 0.999  # a limit counts as active at >= this fraction of it
_KINDS = ("speed", "acceleration", "jerk")


@dataclass(frozen=True)
class Limits:
    """Per-joint limits with the override applied: ``speed`` (rad/s or m/s),
    ``acceleration`` (rad/s^2 or m/s^2), ``jerk`` (rad/s^3 or m/s^3); inf where unknown."""

    speed: Array
    acceleration: Array
    jerk: Array

    def of(self, kind: str) -> Array:
        """The limits of ``kind`` ("speed", "acceleration" or "jerk")."""
        return {"speed": self.speed, "acceleration": self.acceleration, "jerk": self.jerk}[kind]


def joint_limits(robot: Robot, override: float = 1.0) -> Limits:
    """The robot's joint limits under the speed override ``override`` (0 < f <= 1)."""
    f = float(override)
    return Limits(robot.max_speeds * f, robot.max_accelerations * f * f, robot.max_jerks * f**3)


def require_finite(
    limits: Limits, robot: str, command: str, kinds: tuple[str, ...] = _KINDS
) -> None:
    """ProgramError naming the first joint without a finite limit of one of ``kinds``."""
    for kind in kinds:
        bad = np.flatnonzero(~np.isfinite(limits.of(kind)))
        if len(bad):
            i = int(bad[0])
            raise ProgramError(
                f"{command} '{robot}': profile 'jerk' needs finite speed, acceleration and "
                f"jerk limits on every joint; joint {i + 1} has no {kind} limit (give the "
                f"robot's joints max_speed, max_acceleration and max_jerk, e.g. with "
                f"Robot.with_(joints=...), or use a thesis profile: linear, trapezoid, quintic)"
            )


class JerkMove:
    """A ruckig trajectory of ``dof`` joints over local time [0, ``duration``] (s)."""

    def __init__(self, traj: Trajectory, limits: Limits, q0: Array, q1: Array) -> None:
        self.traj = traj
        self.limits = limits
        self.q0, self.q1 = q0, q1
        self.duration = float(traj.duration)

    def positions(self, t: Array) -> Array:
        """Joint values (k, dof) at local times ``t`` (s), clipped to [0, duration]."""
        at = self.traj.at_time
        out = np.empty((len(t), len(self.q0)))
        for i, ti in enumerate(np.clip(t, 0.0, self.duration)):
            out[i] = at(float(ti))[0]
        return out

    def state(self, t: float) -> tuple[Array, Array, Array]:
        """(q, qdot, qddot) at local time ``t`` (s)."""
        p, v, a = self.traj.at_time(float(min(max(t, 0.0), self.duration)))
        return np.array(p), np.array(v), np.array(a)

    def activity(self) -> dict[str, float]:
        """Seconds each limit is active: ``"j<i> speed|acceleration|jerk"`` (module doc of
        :mod:`workcell.sim.motion`: the one active longest is what set the time)."""
        out: dict[str, float] = {}
        lim = self.limits
        for section in self.traj.profiles:
            for i, pr in enumerate(section):
                t, j, a, v = pr.t, pr.j, pr.a, pr.v
                for k in range(len(t)):
                    if t[k] <= 0.0:
                        continue
                    if abs(j[k]) >= _ACTIVE * lim.jerk[i]:
                        kind = "jerk"
                    elif abs(a[k]) >= _ACTIVE * lim.acceleration[i] and j[k] == 0.0:
                        kind = "acceleration"
                    elif abs(v[k]) >= _ACTIVE * lim.speed[i] and a[k] == 0.0 and j[k] == 0.0:
                        kind = "speed"
                    else:
                        continue
                    key = f"j{i + 1} {kind}"
                    out[key] = out.get(key, 0.0) + float(t[k])
        return out


def least_time(distance: Array, limits: Limits, *, from_rest: bool = True) -> float:
    """A lower bound (s) of any motion over ``distance`` (per joint, >= 0) within
    ``limits``: each joint needs distance / speed, and from rest also 2 sqrt(distance /
    acceleration) and cbrt(32 distance / jerk) (the bang-bang times); inf when a joint
    that moves has a limit of 0 (an override of 1e-320 underflows to 0)."""
    moving = distance > 0
    if not np.any(moving):
        return 0.0
    d = distance[moving]
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        bounds = [d / limits.speed[moving]]
        if from_rest:
            bounds.append(2.0 * np.sqrt(d / limits.acceleration[moving]))
            bounds.append(np.cbrt(32.0 * d / limits.jerk[moving]))
    t = max(float(np.max(b)) for b in bounds)
    return t if t == t else math.inf  # NaN (0/0 cannot happen: d > 0) taken as never


def plan_jerk(
    q0: Array,
    q1: Array,
    limits: Limits,
    *,
    v0: Array | None = None,
    a0: Array | None = None,
    v1: Array | None = None,
    a1: Array | None = None,
) -> JerkMove:
    """The time-optimal jerk-limited motion from state (q0, v0, a0) to (q1, v1, a1).

    Speeds and accelerations default to zero (rest to rest: phase-synchronised, a
    straight line in joint space). Every limit must be finite (:func:`require_finite`).
    Raises ProgramError when ruckig finds no motion (a state outside the limits).
    """
    n = len(q0)
    rest0 = v0 is None and a0 is None
    work_limits.check(
        "max_sim_time",
        least_time(np.abs(np.asarray(q1, float) - q0), limits, from_rest=rest0),
        "a jerk-limited move, at least (its speed, override or acceleration is too small)",
    )  # before ruckig, which fails on limits that underflowed (an override of 1e-100)
    otg = Ruckig(n)  # offline; never with waypoints (module doc)
    inp = InputParameter(n)
    inp.current_position = q0.tolist()
    inp.target_position = q1.tolist()
    rest = v0 is None and a0 is None and v1 is None and a1 is None
    if v0 is not None:
        inp.current_velocity = v0.tolist()
    if a0 is not None:
        inp.current_acceleration = a0.tolist()
    if v1 is not None:
        inp.target_velocity = v1.tolist()
    if a1 is not None:
        inp.target_acceleration = a1.tolist()
    if rest:
        inp.synchronization = Synchronization.Phase
    traj = Trajectory(n)
    res, error = None, ""
    # ruckig 0.19 fails on some moves that lie exactly on the boundary between two profile
    # shapes (a distance of exactly 2 a^3 / j^2: the acceleration just reaches its limit);
    # the same move with the acceleration and jerk limits a hair lower (1e-9, relative)
    # is off the boundary, keeps every limit and is slower by ~1e-9 of its time
    for shrink in (1.0, 1.0 - 1e-9, 1.0 - 1e-7):
        inp.max_velocity = limits.speed.tolist()
        inp.max_acceleration = (limits.acceleration * shrink).tolist()
        inp.max_jerk = (limits.jerk * shrink).tolist()
        try:
            res = otg.calculate(inp, traj)
        except (RuntimeError, RuckigError) as exc:  # ruckig raises on input it cannot take
            error = str(exc).strip().splitlines()[0]
            continue
        if res in (Result.Working, Result.Finished):
            break
        error = f"ruckig: {res}"
    else:
        raise ProgramError(f"no jerk-limited motion between these states ({error})")
    return JerkMove(traj, limits, np.asarray(q0, float), np.asarray(q1, float))
