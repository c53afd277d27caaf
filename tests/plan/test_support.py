"""Vertical drops onto supports and top faces, against geometry worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from workcell.plan.support import drop, top_face


def box(lo, hi) -> np.ndarray:
    """The 8 corners of an axis-aligned box."""
    return np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )


@settings(max_examples=40, deadline=None)
@given(
    gap=st.floats(0.0, 0.5),
    dx=st.floats(-0.09, 0.09),
    dy=st.floats(-0.09, 0.09),
)
def test_a_box_over_a_box_drops_by_the_gap(gap, dx, dy):
    support = box((0, 0, 0), (0.1, 0.1, 0.2))
    part = box((dx, dy, 0.2 + gap), (dx + 0.1, dy + 0.1, 0.25 + gap))  # footprints overlap
    d = drop([part], [("stage", support), ("ground", 0.0)])
    assert d.support == "stage"
    assert d.distance == pytest.approx(gap, abs=1e-9)


def test_beside_a_support_it_falls_to_the_ground():
    wall = box((0.1, 0, 0), (0.2, 0.1, 0.5))
    part = box((0.0, 0.0, 0.3), (0.1, 0.1, 0.35))  # touching the wall's side, not above it
    d = drop([part], [("wall", wall), ("ground", 0.0)])
    assert (d.support, d.distance) == ("ground", pytest.approx(0.3, abs=1e-9))
    above = box((0.0, 0.0, 0.6), (0.1, 0.1, 0.7))
    assert drop([above], [("roof", box((0, 0, 0.8), (0.1, 0.1, 0.9)))]).support is None


def test_edge_on_edge_contact_is_found():
    # a cube turned 45 deg about x (an edge pointing down) over a box turned 45 deg about y
    # (an edge pointing up): the edges cross, no vertex of either touches a face first
    c = 0.05
    r = c * math.sqrt(2) / 2  # half the diagonal of a face
    cube = trimesh.creation.box(extents=(c, c, c))
    part = cube.copy()
    part.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 4, [1, 0, 0]))
    part.apply_translation([0, 0, 1.0])  # lowest edge at z = 1 - r
    base = cube.copy()
    base.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 4, [0, 1, 0]))
    base.apply_translation([0, 0, 0.5])  # highest edge at z = 0.5 + r
    d = drop([part.vertices], [("base", base.vertices)])
    assert d.support == "base"
    assert d.distance == pytest.approx((1.0 - r) - (0.5 + r), abs=1e-9)


def test_top_face_of_a_box_and_of_a_bin():
    b = trimesh.creation.box(extents=(0.2, 0.1, 0.3))
    b.apply_translation([1.0, 2.0, 0.15])
    centre, z = top_face(b)
    np.testing.assert_allclose(centre, [1.0, 2.0, 0.3], atol=1e-12)
    assert z == pytest.approx(0.3)
    outer = trimesh.creation.box(extents=(0.2, 0.2, 0.1))
    inner = trimesh.creation.box(extents=(0.16, 0.16, 0.1))
    inner.apply_translation([0, 0, 0.02])
    rim = outer.difference(inner)
    centre, z = top_face(rim)  # the rim: four strips round the centre
    np.testing.assert_allclose(centre[:2], [0.0, 0.0], atol=1e-9)
    assert z == pytest.approx(0.05)
