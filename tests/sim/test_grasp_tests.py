"""The thesis's three grasp tests (workcell.sim.grasp) against hand-computed geometry."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from workcell.sim.grasp import PartBox, describe_failure, grasp_candidates, tool_down
from workcell.spatial import rot_x, rot_y, rot_z, translation

HALF = np.array([0.02, 0.03, 0.01])  # m


def box(name="p", R=None, centroid=(0.0, 0.0, 0.0)):
    R = np.eye(3) if R is None else R
    return PartBox(name, np.asarray(R, dtype=float), HALF, np.asarray(centroid, dtype=float))


@settings(max_examples=60, deadline=None)
@given(
    tilt=st.floats(0.0, math.radians(80)),
    yaw=st.floats(-math.pi, math.pi),
    offset=st.floats(0.0, 0.05),
)
def test_angle_width_distance_match_hand_formulas(tilt, yaw, offset):
    # tool pointing down, turned by yaw about the vertical, then tilted about its own x axis
    tcp = translation(0.0, 0.0, offset) @ tool_down((0, 0, 0), yaw) @ rot_x(tilt)
    (c,) = grasp_candidates(tcp, [box()], opening=1.0, max_distance=1.0, max_angle=math.pi)
    z, y = tcp[:3, 2], tcp[:3, 1]
    # angle: to the nearest of the box axes (either sense); the z axis is tilted by `tilt`
    # from the vertical, so its angle to the box's z axis is tilt (when that is nearest)
    expected_angle = min(math.acos(min(1.0, abs(z[k]))) for k in range(3))
    assert math.isclose(c.angle, expected_angle, abs_tol=1e-7)
    assert c.angle <= tilt + 1e-9
    # width across the grasp: the box's extent along the tool's y axis
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * HALF
    proj = corners @ y
    assert math.isclose(c.width, proj.max() - proj.min(), rel_tol=1e-12, abs_tol=1e-15)
    assert math.isclose(c.distance, offset, abs_tol=1e-12)


def test_each_test_fails_on_its_own_and_is_named():
    down = tool_down((0, 0, 0))
    ok = dict(opening=0.08, max_distance=0.01, max_angle=math.radians(5))
    (c,) = grasp_candidates(down, [box()], **ok)
    assert c.failed is None
    assert math.isclose(c.width, 0.06)
    tilted = down @ rot_y(math.radians(10))
    (c,) = grasp_candidates(tilted, [box()], **ok)
    assert c.failed == "angle"
    assert math.isclose(c.angle, math.radians(10), rel_tol=1e-9)
    (c,) = grasp_candidates(down, [box()], **{**ok, "opening": 0.05})
    assert c.failed == "width"
    far = translation(0.0, 0.0, 0.02) @ down
    (c,) = grasp_candidates(far, [box()], **ok)
    assert c.failed == "distance"
    assert math.isclose(c.distance, 0.02)
    msg = describe_failure("r", [c], **ok)
    assert "'p'" in msg
    assert "distance" in msg
    assert "20 mm" in msg


def test_turned_tool_sees_the_other_width():
    # yaw 90 deg: the fingers close along the box's x axis, 40 mm wide
    (c,) = grasp_candidates(
        tool_down((0, 0, 0), math.pi / 2), [box()], opening=0.05, max_distance=0.01, max_angle=0.1
    )
    assert c.failed is None
    assert math.isclose(c.width, 0.04)


def test_nearest_first_and_rotated_boxes():
    R = rot_z(math.radians(30))[:3, :3]
    parts = [box("far", R, (0.0, 0.0, 0.015)), box("near", R, (0.0, 0.0, 0.005))]
    cands = grasp_candidates(
        tool_down((0, 0, 0), math.radians(30)),
        parts,
        opening=0.07,
        max_distance=0.01,
        max_angle=0.1,
    )
    assert [c.part for c in cands] == ["near", "far"]
    assert cands[0].failed is None
    assert cands[1].failed == "distance"
    assert math.isclose(cands[0].width, 0.06, rel_tol=1e-12)


def test_no_parts():
    assert "no movable part" in describe_failure(
        "r", [], opening=0.08, max_distance=0.01, max_angle=0.1
    )
