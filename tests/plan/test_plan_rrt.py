"""OMPL paths on toy problems whose free space is known exactly.

The toy: a point in the unit square [0, 1]^2 (radii 1: a unit of joint moves it a
metre), a wall x in [0.5 - w/2, 0.5 + w/2] with a gap at y in [0.45, 0.55]. Every
returned segment is re-checked by sampling it at 1e-4 spacing, independently of the
planner's checks.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from workcell.plan.rrt import checks_needed, plan_path, segment_valid

LO, HI = np.zeros(2), np.ones(2)
RADII = np.ones(2)


def wall(width: float, gap: bool = True):
    def valid(q: np.ndarray) -> bool:
        in_wall = abs(q[0] - 0.5) <= width / 2
        in_gap = gap and 0.45 <= q[1] <= 0.55
        return not in_wall or in_gap

    return valid


def dense_ok(valid, path: np.ndarray, spacing: float = 1e-4) -> bool:
    for a, b in itertools.pairwise(path):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / spacing)))
        if not all(valid(a + (b - a) * t) for t in np.linspace(0, 1, n + 1)):
            return False
    return True


def test_checks_needed_bounds_the_displacement():
    a, b = np.array([0.0, 0.0, 0.0]), np.array([0.3, -0.2, 0.0])
    radii = np.array([0.5, 2.0, 9.0])
    n = checks_needed(a, b, radii, 0.01)
    assert n == int(np.ceil((0.3 * 0.5 + 0.2 * 2.0) / 0.01))  # 55
    calls = []
    assert segment_valid(lambda q: calls.append(q.copy()) or True, a, b, radii, 0.01)
    t = sorted(float(q[0] / 0.3) for q in calls)
    np.testing.assert_allclose(t, np.arange(1, n) / n)  # every interior point, once
    assert 0.25 <= calls[0][0] / 0.3 <= 0.75  # coarse first: the first check is inside


def test_a_thin_wall_the_default_resolution_misses_is_not_crossed():
    valid = wall(0.002)
    start, goal = np.array([0.1, 0.1]), np.array([0.9, 0.1])
    assert not dense_ok(valid, np.array([start, goal]))
    ours = plan_path(valid, start, goal, LO, HI, radii=RADII, clearance=0.001, time_limit=5, seed=0)
    assert ours is not None
    assert dense_ok(valid, ours)
    # OMPL's own motion checks (1 % of the extent, 0.014 here) go straight through
    theirs = plan_path(
        valid,
        start,
        goal,
        LO,
        HI,
        radii=RADII,
        clearance=0.001,
        time_limit=5,
        seed=0,
        resolution=0.01,
    )
    assert theirs is not None
    assert not dense_ok(valid, theirs)


def test_same_seed_same_path_and_a_free_segment_is_returned_as_is():
    valid = wall(0.05)
    start, goal = np.array([0.1, 0.9]), np.array([0.9, 0.2])
    runs = [
        plan_path(valid, start, goal, LO, HI, radii=RADII, clearance=0.002, time_limit=5, seed=s)
        for s in (3, 3, 4)
    ]
    np.testing.assert_array_equal(runs[0], runs[1])
    assert all(dense_ok(valid, p) for p in runs)
    assert runs[0][0].tolist() == start.tolist()
    assert runs[0][-1].tolist() == goal.tolist()
    free = plan_path(
        valid,
        start,
        np.array([0.2, 0.1]),
        LO,
        HI,
        radii=RADII,
        clearance=0.002,
        time_limit=5,
        seed=0,
    )
    assert free.tolist() == [start.tolist(), [0.2, 0.1]]


@pytest.mark.slow
def test_no_way_through_runs_out_of_time():
    valid = wall(0.05, gap=False)
    start, goal = np.array([0.1, 0.5]), np.array([0.9, 0.5])
    assert (
        plan_path(valid, start, goal, LO, HI, radii=RADII, clearance=0.002, time_limit=0.3, seed=0)
        is None
    )
