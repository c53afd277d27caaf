"""Programs for the study tests, at module level so worker processes can import them."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from workcell.examples import thesis_joints, thesis_pick_place

CRASH_DIR = "WORKCELL_TEST_CRASH_DIR"  # environment: where crash programs keep their notes


def _base_x(sim) -> float:
    return float(sim.cell.robots["puma"].base[0, 3])


def _note(name: str) -> Path:
    folder = Path(os.environ[CRASH_DIR])
    with open(folder / name, "a") as f:
        f.write(f"{os.getpid()}\n")
    return folder / name


def crash_at_far_x(sim) -> None:
    """Example 1's program, but the worker process dies when the base x is above 0.15 m."""
    if _base_x(sim) > 0.15:
        _note(f"attempt-{_base_x(sim):.3f}")
        os._exit(3)
    thesis_joints.program(sim)


def crash_once_at_far_x(sim) -> None:
    """As :func:`crash_at_far_x`, but only at the first attempt of each candidate."""
    x = _base_x(sim)
    if x > 0.15 and not (Path(os.environ[CRASH_DIR]) / f"attempt-{x:.3f}").exists():
        _note(f"attempt-{x:.3f}")
        os._exit(3)
    thesis_joints.program(sim)


def reach_one_pose(sim) -> None:
    """One move_end_effector: the tool pointing down at TARGET (world, m), config 'ru'."""
    T = np.diag([1.0, -1.0, -1.0, 1.0])
    T[:3, 3] = TARGET
    sim.move_end_effector("puma", T, config="ru")


TARGET = (0.40, 0.0, 0.55)


def pick_place(sim) -> None:
    """Example 2's program (for tests that need a function of their own)."""
    thesis_pick_place.program(sim)


def slow_joints(sim) -> None:
    """Example 1's program after 0.1 s of wall time (a study long enough to kill mid-way)."""
    import time

    time.sleep(0.1)
    thesis_joints.program(sim)


def asks_for_5000_frames(sim) -> None:
    """Example 1's program, after checking 5,000 frames against the work limits."""
    from workcell import limits

    limits.check("max_frames", 5000, "this program")
    thesis_joints.program(sim)


def jerk_joint_moves(sim) -> None:
    """Example 1's joint moves, time-optimal and jerk-limited, at full override (which a
    study may pin)."""
    sim.set_profile("jerk")
    sim.set_override("puma", 1.0)
    thesis_joints.program(sim)
