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


def test_a_grippers_depths_come_from_its_finger_length_and_tcp():
    from workcell.plan.grasps import grip_depths
    from workcell.robots.gripper import parallel_gripper

    # the defaults: fingers 50 mm beyond the palm, the TCP a quarter of them from the tips
    assert grip_depths(parallel_gripper()) == pytest.approx((0.0375, 0.0125), abs=1e-12)
    long = parallel_gripper(finger_length=0.08, tcp_depth=0.01, palm_height=0.02)
    assert grip_depths(long) == pytest.approx((0.07, 0.01), abs=1e-12)


PALM, TIPS, MARGIN = 0.0375, 0.0125, 0.001  # the default gripper's depths (above)


@settings(max_examples=60, deadline=None)
@given(
    height=st.floats(0.004, 0.3),
    width=st.floats(0.01, 0.07),
    yaw=st.floats(-math.pi, math.pi),
)
def test_the_grasp_from_above_keeps_the_palm_off_the_part_and_the_tips_off_its_support(
    height, width, yaw
):
    # a box standing on z = 0.4; the top grasps (tool z down) at each back-off
    size = np.array([width, width, height])
    pose = translation(0.3, -0.1, 0.4) @ rot_z(yaw)
    poses = grasp_poses(
        pose, np.zeros(3), size, size / 2, opening=0.08, backoffs=BACKOFFS,
        palm=PALM, tips=TIPS, margin=MARGIN,
    )  # fmt: skip
    top = [g for g in poses if g.tool[2, 2] < -1 + 1e-9]
    assert len(top) == 2 * 2 * len(BACKOFFS)  # 2 finger directions x 2 senses
    lowest = min(g.tool[2, 3] for g in top)
    palm_face, tip = lowest + PALM, lowest - TIPS  # along the vertical tool axis
    assert palm_face >= 0.4 + height + MARGIN - 1e-12  # over the part's top
    assert tip >= 0.4 + MARGIN - 1e-12  # over the table the part stands on
    # and no higher than that needs: the thesis's grasp point (the centroid) when the
    # part is between 2 x (tips + margin) and 2 x (palm - margin) tall, else one of the
    # two just kept
    centre = 0.4 + height / 2
    if 2 * (TIPS + MARGIN) <= height <= 2 * (PALM - MARGIN):
        assert lowest == pytest.approx(centre, abs=1e-12)
    else:
        assert min(palm_face - (0.4 + height), tip - 0.4) == pytest.approx(MARGIN, abs=1e-12)
    # the fingers hold it: below its top they reach as far as the thesis's grasp at the
    # centroid would, or the whole finger, or the whole part (less the margin)
    held = min(height / 2 + TIPS, PALM + TIPS, height) - MARGIN
    assert 0.4 + height - tip >= held - 1e-12
