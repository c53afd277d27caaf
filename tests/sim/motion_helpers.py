"""Shared helpers of the motion tests: robots with explicit limits, cells, finite differences.

The limits are set here (not taken from a robot library) so the tests run against
numbers they state themselves.
"""

from __future__ import annotations

import dataclasses
import functools

import mujoco
import numpy as np

from workcell import Workcell, compile_cell
from workcell.robots import puma260
from workcell.sim import Simulator
from workcell.sim.grasp import tool_down
from workcell.spatial import translation

HOME = np.radians([0.0, 0.0, -90.0, 0.0, 90.0, 0.0])
SPEED = np.radians([119.0, 119.0, 164.0, 577.0, 431.0, 397.0])  # the Puma 260's own
ACCELERATION = np.radians([300.0, 300.0, 300.0, 800.0, 800.0, 800.0])  # rad/s^2
JERK = 10.0 * ACCELERATION  # rad/s^3
BASE = translation(0.0, 0.0, 0.4)
CENTRE = np.array([0.34, -0.1, 0.5])  # a tool-down point the arm reaches comfortably (m)


def limited(speed=SPEED, acceleration=ACCELERATION, jerk=JERK):
    """A Puma 260 whose joints have these speed, acceleration and jerk limits."""
    r = puma260()
    joints = tuple(
        dataclasses.replace(j, max_speed=float(v), max_acceleration=float(a), max_jerk=float(k))
        for j, v, a, k in zip(r.joints, speed, acceleration, jerk, strict=True)
    )
    return r.with_(joints=joints)


@functools.cache
def _cell(key: str):
    cell = Workcell(f"motion_{key}")
    inf = np.full(6, np.inf)
    robot = limited() if key == "limited" else limited(acceleration=inf, jerk=inf)
    cell.add_robot("puma", robot, base=BASE, q=HOME)
    return cell, compile_cell(cell)


def make(key: str = "limited", **kw) -> Simulator:
    """A simulator of one Puma 260 on a 0.4 m base with the limits above ("limited"), or
    with speed limits only ("speeds")."""
    cell, cc = _cell(key)
    kw.setdefault("dt", 0.01)
    kw.setdefault("check_collisions", False)
    return Simulator(cell, compiled=cc, **kw)


def pose(offset=(0.0, 0.0, 0.0)) -> np.ndarray:
    """A tool-down pose at CENTRE + offset (m)."""
    return tool_down(CENTRE + np.asarray(offset, dtype=float))


def tool_points(sim: Simulator, robot: str = "puma") -> np.ndarray:
    """World tool-site positions (N, 3) of every frame, from MuJoCo (an independent FK)."""
    m = sim.model
    d = mujoco.MjData(m)
    site = m.site(sim.compiled.tool_sites[robot]).id
    Q = sim.timeline.qpos()
    out = np.empty((len(Q), 3))
    for i, q in enumerate(Q):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        out[i] = d.site_xpos[site]
    return out


def derivatives(t: np.ndarray, Q: np.ndarray):
    """Finite-difference speeds, accelerations and jerks of samples Q (N, n) at times t
    (frames sharing a time are dropped): backward differences on the non-uniform grid."""
    keep = np.concatenate([[True], np.diff(t) > 1e-12])
    t, Q = t[keep], Q[keep]
    v = np.diff(Q, axis=0) / np.diff(t)[:, None]
    tv = 0.5 * (t[1:] + t[:-1])
    a = np.diff(v, axis=0) / np.diff(tv)[:, None]
    ta = 0.5 * (tv[1:] + tv[:-1])
    j = np.diff(a, axis=0) / np.diff(ta)[:, None]
    return v, a, j


def seven_phase_time(D: float, v: float, a: float, j: float) -> float:
    """Minimum time (s) of a rest-to-rest motion over D >= 0 under speed v, acceleration a
    and jerk j limits: the seven-phase profile (jerk +j, 0, -j, cruise, -j, 0, +j).

    Reaching speed v takes v/a + a/j when the acceleration limit is reached on the way
    (v j >= a^2), else 2 sqrt(v/j); the distance covered accelerating and decelerating
    is v times that. Shorter moves never cruise: with the acceleration limit reached
    (D >= 2 a^3 / j^2) the peak speed w solves D = w (w/a + a/j); without it the four
    jerk phases of length tau cover D = 2 j tau^3.
    """
    if D <= 0:
        return 0.0
    t_up = v / a + a / j if v * j >= a * a else 2.0 * np.sqrt(v / j)
    if v * t_up <= D:
        return D / v + t_up
    if 2.0 * a**3 / j**2 <= D:
        w = (-(a * a) / j + np.sqrt(a**4 / j**2 + 4.0 * D * a)) / 2.0
        return 2.0 * (w / a + a / j)
    return 4.0 * (D / (2.0 * j)) ** (1.0 / 3.0)
