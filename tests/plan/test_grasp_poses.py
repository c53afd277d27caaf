"""Grasp poses from a part's box: every one passes the thesis's grasp tests.

Reference: the grasp tests as ``close_gripper`` runs them (:func:`workcell.sim.grasp.
grasp_candidates`, written for the thesis's §4.5 and tested on their own), applied to
the poses generated here; the count of poses from the box's widths by hand.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from workcell.plan.grasps import grasp_poses
from workcell.sim.grasp import PartBox, grasp_candidates
from workcell.spatial import rot_x, rot_z, translation

BACKOFFS = (0.0, 0.01)


@settings(max_examples=60, deadline=None)
@given(
    size=st.tuples(*(st.floats(0.01, 0.12) for _ in range(3))),
    yaw=st.floats(-math.pi, math.pi),
    tilt=st.floats(-math.pi, math.pi),
)
def test_every_pose_passes_the_thesis_tests(size, yaw, tilt):
    size = np.array(size)
    pose = translation(0.3, -0.1, 0.4) @ rot_z(yaw) @ rot_x(tilt)
    lo, hi = -size / 3, 2 * size / 3  # the part frame off-centre in its box
    centroid = (lo + hi) / 2 + np.array([0.001, -0.002, 0.0])
    opening = 0.08
    poses = grasp_poses(pose, lo, hi, centroid, opening=opening, backoffs=BACKOFFS)
    fits = sum(1 for a in range(3) for b in range(3) if a != b and size[b] <= opening)
    assert len(poses) == 2 * 2 * fits * len(BACKOFFS)  # 2 senses of z, 2 of y
    box = PartBox("p", pose[:3, :3], (hi - lo) / 2, (pose @ np.append(centroid, 1.0))[:3])
    for g in poses:
        np.testing.assert_allclose(g.tool[:3, :3].T @ g.tool[:3, :3], np.eye(3), atol=1e-12)
        assert np.linalg.det(g.tool[:3, :3]) == pytest.approx(1.0)
        (c,) = grasp_candidates(
            g.tool, [box], opening=opening + 1e-12, max_distance=g.backoff + 1e-9, max_angle=1e-6
        )
        assert c.failed is None
        assert c.width == pytest.approx(g.width, abs=1e-12)
        assert c.distance == pytest.approx(g.backoff, abs=1e-12)
    # preferred first: tool z from straight down, through sideways, to straight up
    down = [-g.tool[2, 2] for g in poses]
    assert all(a >= b - 1e-9 for a, b in itertools.pairwise(down))


def test_a_part_wider_than_the_opening_everywhere_has_no_grasp():
    assert (
        grasp_poses(np.eye(4), np.zeros(3), np.full(3, 0.1), np.full(3, 0.05), opening=0.08) == []
    )
    # one narrow side: only the grasps across it (z along the two other axes, 2 x 2 each)
    poses = grasp_poses(
        np.eye(4),
        np.zeros(3),
        np.array([0.1, 0.05, 0.1]),
        np.array([0.05, 0.025, 0.05]),
        opening=0.08,
    )
    assert len(poses) == 8
    assert all(abs(g.tool[1, 1]) == pytest.approx(1.0) for g in poses)  # fingers along y
