"""Puma link solids, the parallel gripper and block copying, checked against the DH kinematics.

Reference numbers come from outside the geometry code: joint axes from ``Robot.link_frames``,
containment from scipy's Delaunay triangulation, volumes from trimesh, the Puma 560's
published wrist-to-flange distance d6 = 56.25 mm (Fu, Gonzalez and Lee).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import trimesh
from scipy.spatial import ConvexHull, Delaunay

from workcell import solids, spatial
from workcell.errors import GeometryError, KinematicsError, ModelError
from workcell.modeller.model import Model
from workcell.robots import Joint, Robot, puma260, puma560
from workcell.robots.geometry import copy_blocks, puma_geometry
from workcell.robots.gripper import attach_gripper, parallel_gripper

PUMAS = {"puma560": puma560(), "puma260": puma260()}
D6_PUMA560 = 0.05625  # m, Fu, Gonzalez & Lee, "Robotics" (1987), Puma 560 table


def placed_vertices(robot, g, frames):
    """World vertices of one LinkGeometry at the link frames ``frames``."""
    V = robot.model.world_mesh(("block", g.block)).vertices
    return spatial.transform_points(frames[g.link] @ g.transform, V)


def link_solids(robot, link, frames):
    return [placed_vertices(robot, g, frames) for g in robot.geometry if g.link == link]


def inside_any(vertex_sets, points):
    """Mask of points strictly inside one of the convex solids (Delaunay of their vertices)."""
    hit = np.zeros(len(points), bool)
    for V in vertex_sets:
        hit |= Delaunay(V).find_simplex(points) >= 0
    return hit


@pytest.mark.parametrize("name", PUMAS)
def test_solids_are_valid_convex_and_on_links(name):
    robot = PUMAS[name]
    assert robot.model is not None
    assert {g.link for g in robot.geometry} == set(range(7))
    for g in robot.geometry:
        assert "/" not in g.block
        assert robot.model.validity(("block", g.block)).ok, g.block
        mesh = robot.model.world_mesh(("block", g.block))
        vol = trimesh.Trimesh(mesh.vertices, mesh.faces).volume
        assert vol > 0
        # every Puma solid is convex: it fills its hull (scipy's qhull, not our code)
        assert ConvexHull(mesh.vertices).volume == pytest.approx(vol, rel=1e-9)
        assert g.colour is not None
        assert len(g.colour) == 4


@pytest.mark.parametrize("name", PUMAS)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_each_joint_axis_runs_through_both_links_it_joins(name, seed):
    """Joint k turns about z of frame k-1: link k-1 and link k both hold part of that axis."""
    robot = PUMAS[name]
    q = np.random.default_rng(seed).uniform(robot.lower, robot.upper)
    F = robot.link_frames(q)
    t = np.linspace(-0.6, 0.6, 2401)
    for k in range(1, 7):
        origin, axis = F[k - 1][:3, 3], F[k - 1][:3, 2]
        line = origin + t[:, None] * axis
        for link in (k - 1, k):
            assert inside_any(link_solids(robot, link, F), line).any(), (name, k, link)


@pytest.mark.parametrize("name", PUMAS)
def test_consecutive_links_bounding_boxes_overlap(name):
    robot = PUMAS[name]
    rng = np.random.default_rng(5)
    for _ in range(10):
        F = robot.link_frames(rng.uniform(robot.lower, robot.upper))
        boxes = []
        for link in range(7):
            V = np.concatenate(link_solids(robot, link, F))
            boxes.append((V.min(axis=0), V.max(axis=0)))
        for (lo0, hi0), (lo1, hi1) in itertools.pairwise(boxes):
            assert np.all(lo0 <= hi1)
            assert np.all(lo1 <= hi0)


@pytest.mark.parametrize("name", PUMAS)
def test_upper_arm_and_forearm_span_their_dh_lengths(name):
    """The upper arm covers shoulder to elbow (a2 along x2); the forearm reaches the wrist centre."""
    robot = PUMAS[name]
    F = robot.link_frames(robot.pose("home"))
    a2, d4 = robot.joints[1].dh.a, robot.joints[3].dh.d
    (upper,) = link_solids(robot, 2, F)
    local = spatial.transform_points(spatial.invert(F[2]), upper)
    assert local[:, 0].min() < -a2
    assert local[:, 0].max() > 0
    (fore,) = link_solids(robot, 3, F)
    local = spatial.transform_points(spatial.invert(F[3]), fore)
    assert local[:, 2].max() >= d4 - 1e-12
    # the pedestal stands on the floor of the base frame, below the shoulder height d1
    ped = np.concatenate(link_solids(robot, 0, F))
    assert ped[:, 2].min() == pytest.approx(0.0, abs=1e-12)
    assert ped[:, 2].max() < robot.joints[0].dh.d


def test_puma260_cross_sections_scale_with_the_arm():
    """The 260 is drawn at about 0.46 of the 560's cross-sections (a2 ratio 0.199 / 0.4318)."""

    def thickness(robot, block):
        V = robot.model.world_mesh(("block", block)).vertices
        return np.ptp(V[:, 2])

    ratio = thickness(PUMAS["puma260"], "link2.upper_arm") / thickness(
        PUMAS["puma560"], "link2.upper_arm"
    )
    assert ratio == pytest.approx(0.46, rel=1e-9)


def test_flange_sits_at_the_tool_of_the_260_and_at_d6_on_the_560():
    for robot, z in ((PUMAS["puma260"], 0.05588), (PUMAS["puma560"], D6_PUMA560)):
        (flange,) = [g for g in robot.geometry if g.link == 6]
        V = spatial.transform_points(
            flange.transform, robot.model.world_mesh(flange.block).vertices
        )
        assert V[:, 2].max() == pytest.approx(z, abs=1e-12)


def test_geometry_refuses_non_puma_robots():
    two = Robot("two", (Joint.from_dh("a", a=0.3), Joint.from_dh("b", a=0.2)))
    with pytest.raises(KinematicsError, match="6-joint"):
        puma_geometry(two, scale=1.0)
    with pytest.raises(KinematicsError, match="scale"):
        puma_geometry(puma560(geometry=False), scale=-1.0)
    with pytest.raises(ModelError, match="gripper"):
        puma_geometry(attach_gripper(puma560(geometry=False), parallel_gripper()), scale=1.0)


# ---------------------------------------------------------------------- gripper
def gripper_vertices(g, role):
    p = g.part(role)
    return spatial.transform_points(p.transform, g.model.world_mesh(("block", p.block)).vertices)


def test_gripper_solids_valid_and_jaws_open_by_max_opening():
    g = parallel_gripper(max_opening=0.06, finger_length=0.04)
    for p in g.geometry:
        assert g.model.validity(("block", p.block)).ok
    left, right = gripper_vertices(g, "left"), gripper_vertices(g, "right")
    assert left[:, 1].min() - right[:, 1].max() == pytest.approx(0.06, abs=1e-12)
    assert g.finger_travel == pytest.approx(0.03)
    palm = gripper_vertices(g, "palm")
    assert palm[:, 2].min() == pytest.approx(0.0, abs=1e-12)  # sits on the mounting face
    assert left[:, 2].max() == pytest.approx(palm[:, 2].max() + 0.04, abs=1e-12)


@pytest.mark.parametrize("opening", [0.08, 0.03])
def test_tcp_lies_between_the_finger_tips(opening):
    g = parallel_gripper(max_opening=opening)
    tcp = g.tcp[:3, 3]
    np.testing.assert_allclose(g.tcp[:3, :3], np.eye(3))
    left, right = gripper_vertices(g, "left"), gripper_vertices(g, "right")
    assert right[:, 1].max() < tcp[1] < left[:, 1].min()
    for V in (left, right):
        assert V[:, 0].min() < tcp[0] < V[:, 0].max()
        assert V[:, 2].min() < tcp[2] < V[:, 2].max()  # level with the fingers
        assert V[:, 2].max() - tcp[2] <= 0.05 / 2  # in the tip half
    np.testing.assert_allclose(g.finger_tips()[:, 1], [opening / 2, -opening / 2])


def test_gripper_rejects_bad_dimensions():
    with pytest.raises(GeometryError, match="max_opening"):
        parallel_gripper(max_opening=0.0)
    with pytest.raises(GeometryError, match="tcp_depth"):
        parallel_gripper(finger_length=0.05, tcp_depth=0.06)


def test_attach_gripper_moves_the_tool_to_the_tcp():
    rng = np.random.default_rng(9)
    g = parallel_gripper()
    p260 = PUMAS["puma260"]
    r = attach_gripper(p260, g)
    for _ in range(5):
        q = rng.uniform(r.lower, r.upper)
        np.testing.assert_allclose(r.fk(q), p260.fk(q) @ g.tcp, atol=1e-15)
    # the 560's tool is the wrist centre: the gripper goes on the flange face, d6 out
    p560 = PUMAS["puma560"]
    r = attach_gripper(p560, g)
    q = rng.uniform(r.lower, r.upper)
    np.testing.assert_allclose(
        r.fk(q), p560.fk(q) @ spatial.translation(0, 0, D6_PUMA560) @ g.tcp, atol=1e-15
    )
    explicit = attach_gripper(p560, g, mount=spatial.translation(0, 0, 0.1))
    np.testing.assert_allclose(
        explicit.fk(q), p560.fk(q) @ spatial.translation(0, 0, 0.1) @ g.tcp, atol=1e-15
    )


def test_attached_gripper_solids_ride_on_the_last_link_around_the_tcp():
    robot = attach_gripper(PUMAS["puma260"], parallel_gripper())
    q = robot.pose("home")
    F = robot.link_frames(q)
    tcp = robot.fk(q)[:3, 3]
    blocks = {p.role: p.block for p in robot.gripper.geometry}
    assert blocks == {
        "palm": "gripper.palm",
        "left": "gripper.finger_l",
        "right": "gripper.finger_r",
    }
    by_block = {g.block: g for g in robot.geometry}
    assert all(by_block[b].link == 6 for b in blocks.values())
    Vl = placed_vertices(robot, by_block[blocks["left"]], F)
    Vr = placed_vertices(robot, by_block[blocks["right"]], F)
    y = F[6][:3, 1]  # the jaws close along the gripper's (= flange's) y axis
    assert (Vr @ y).max() < tcp @ y < (Vl @ y).min()
    # the palm touches the flange face
    Vp = placed_vertices(robot, by_block[blocks["palm"]], F)
    z = F[6][:3, 2]
    flange_face = F[6][:3, 3] + 0.05588 * z
    assert ((Vp - flange_face) @ z).min() == pytest.approx(0.0, abs=1e-12)


def test_attach_gripper_leaves_the_robot_alone_and_refuses_a_second():
    p = puma560()
    n_geo, n_blocks = len(p.geometry), len(p.model.list("block"))
    r = attach_gripper(p, parallel_gripper())
    assert len(p.geometry) == n_geo
    assert len(p.model.list("block")) == n_blocks
    assert p.gripper is None
    assert r.gripper is not None
    assert r.model is not p.model
    assert len(r.geometry) == n_geo + 3
    for g in r.geometry:
        assert r.model.validity(("block", g.block), check_self_intersection=False).ok
    with pytest.raises(ModelError, match="already carries"):
        attach_gripper(r, parallel_gripper("other"))


def test_attach_gripper_to_a_robot_without_solids():
    bare = puma560(geometry=False)
    r = attach_gripper(bare, parallel_gripper())
    assert [g.link for g in r.geometry] == [6, 6, 6]
    np.testing.assert_allclose(r.tool, r.gripper.tcp)  # no flange solid: mount at frame 6


# ---------------------------------------------------------------------- copying blocks
def test_copy_blocks_rebuilds_unions_and_refuses_clashes():
    src = Model()
    solids.box(src, "a", size=(0.1, 0.2, 0.3))
    solids.cylinder(src, "c", radius=0.05, height=0.4, n=12)
    solids.union(src, "u", "a", "c")
    dst = Model()
    names = copy_blocks(src, ["u"], dst, prefix="p.")
    assert names["u"] == "p.u"
    assert set(names) == {"a", "c", "u"}
    ref = src.world_mesh("u")
    got = dst.world_mesh("p.u")
    assert trimesh.Trimesh(got.vertices, got.faces).volume == pytest.approx(
        trimesh.Trimesh(ref.vertices, ref.faces).volume, rel=1e-12
    )
    before = dst.list()
    with pytest.raises(ModelError, match="already exists"):
        copy_blocks(src, ["u"], dst, prefix="p.")
    assert dst.list() == before
