"""Joint speeds and accelerations of a recording: finite differences of the frames.

Each robot gets two more plots beside its joint angles: ``/joint_speeds/{robot}``
(deg/s for revolute joints, m/s for prismatic ones) and ``/joint_accelerations/{robot}``
(deg/s^2, m/s^2), one series per joint. Frame k carries the backward difference
``v_k = (q_k - q_{k-1}) / (t_k - t_{k-1})`` and ``a_k = (v_k - v_{k-1}) /
((t_k - t_{k-2}) / 2)`` (the speeds' own times are the frame intervals' midpoints); frame
0 carries zeros, and a frame sharing its simulated time with the one before (the
thesis's joint-by-joint clock, a gripper closing) repeats the previous values. They are
what a plot of the motion's derivatives looks like at the recording's sampling; the
cycle-time report says which limit set each command's time.
"""

from __future__ import annotations

import numpy as np
import rerun as rr
from numpy.typing import NDArray

from workcell.record.rr_scene import entity_part

__all__ = ["ACCELERATIONS", "SPEEDS", "Rates", "acceleration_entity", "speed_entity"]

SPEEDS = "/joint_speeds"
ACCELERATIONS = "/joint_accelerations"
Array = NDArray[np.float64]


def speed_entity(robot: str) -> str:
    """Entity path of a robot's joint speed series."""
    return f"{SPEEDS}/{entity_part(robot)}"


def acceleration_entity(robot: str) -> str:
    """Entity path of a robot's joint acceleration series."""
    return f"{ACCELERATIONS}/{entity_part(robot)}"


class Rates:
    """Differences carried from one batch of frames to the next, per robot."""

    def __init__(self) -> None:
        self._last: dict[str, tuple[float, Array, Array, float, Array]] = {}  # t q v mid a

    @staticmethod
    def log_static(rec: rr.RecordingStream, robot: str, labels: list[str]) -> None:
        """Series names of the robot's two plots (``labels``: its joint series names)."""
        for ent, unit in ((speed_entity(robot), "/s"), (acceleration_entity(robot), "/s^2")):
            names = [lab.replace(")", f"{unit})") for lab in labels]
            rec.log(ent, rr.SeriesLines(names=names), static=True)

    def rows(self, robot: str, t: Array, Q: Array) -> tuple[Array, Array]:
        """Speeds and accelerations (k, n) of frames at times t (k,) with joint values Q."""
        n = Q.shape[1]
        last = self._last.get(robot)
        if last is None:  # the first frame: at rest by definition
            last = (float(t[0]), Q[0], np.zeros(n), float(t[0]), np.zeros(n))
            t, Q, first = t[1:], Q[1:], [np.zeros((1, n))]
        else:
            first = []
        t0, q0, v0, m0, a0 = last
        T = np.concatenate([[t0], t])
        P = np.vstack([q0[None, :], Q])
        dt = np.diff(T)
        ok = dt > 1e-12
        v = np.where(ok[:, None], np.diff(P, axis=0) / np.where(ok, dt, 1.0)[:, None], np.nan)
        mid = np.where(ok, T[:-1] + 0.5 * dt, np.nan)
        # frames sharing a time repeat the previous values: carry the last valid forward
        V = np.vstack([v0[None, :], v])
        M = np.concatenate([[m0], mid])
        idx = np.where(np.concatenate([[True], ok]), np.arange(len(M)), 0)
        idx = np.maximum.accumulate(idx)
        V, M = V[idx], M[idx]
        dm = np.diff(M)
        acc = np.where(
            (dm > 0)[:, None], np.diff(V, axis=0) / np.where(dm > 0, dm, 1.0)[:, None], 0.0
        )
        # a repeated frame repeats the acceleration too
        A = np.vstack([a0[None, :], acc])
        A = A[np.maximum.accumulate(np.where(np.concatenate([[True], ok]), np.arange(len(A)), 0))]
        self._last[robot] = (float(T[-1]), P[-1], V[-1], float(M[-1]), A[-1])
        if len(t) == 0 and not first:
            return np.zeros((0, n)), np.zeros((0, n))
        return np.vstack([*first, V[1:]]), np.vstack([*first, A[1:]])
