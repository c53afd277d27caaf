"""Tests of workcell.modeller.model: the datamodel of thesis ch. 2 (entities, named relations).

Independent values: the thesis's examples (unit cube, 2 x 3 x 1.5 parallelepiped), analytic
mass properties, hand-computed sets, and a small shadow model kept by the stateful test.
"""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest
from helpers import THESIS_ROWS
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, rule
from scipy.spatial.transform import Rotation

import workcell
from workcell import Model, Surface, spatial
from workcell.errors import GeometryError, ModelError, WorkcellError
from workcell.modeller.model import LEVELS
from workcell.modeller.show import describe_transform
from workcell.modeller.world import reoriented_relations

D90 = math.pi / 2
UNIT_SQUARE = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
# the thesis's SRT rows for cube1 (§2), radians


def thesis_cube(m: Model | None = None) -> Model:
    m = m or Model()
    m.create("surface", "square1", Surface(UNIT_SQUARE))
    m.create("block", "cube1")
    for T in THESIS_ROWS:
        m.attach("cube1", "square1", T)
    return m


def snapshot(m: Model):
    pb = {(lv, n): m.pointed_by((lv, n)) for lv in LEVELS for n in m.list(lv)}
    rels = {
        (lv, n): [(r.name, r.target_level, r.target) for r in m.relations((lv, n))]
        for lv in LEVELS
        for n in m.list(lv)
    }
    return m.to_dict(), pb, rels, m.show(detail=True)


def assert_refused(m: Model, fn, exc=WorkcellError, match=None):
    """``fn(m)`` raises ``exc`` and leaves the model exactly as it was."""
    before = snapshot(m)
    with pytest.raises(exc, match=match):
        fn(m)
    after = snapshot(m)
    assert after[0] == before[0]
    assert after[1] == before[1]
    assert after[2] == before[2]
    assert after[3] == before[3]


def independent_pointed_by(m: Model) -> dict[tuple[str, str], int]:
    """Count, by scanning every relation of every owner, how often each entity is a target."""
    counts = {(lv, n): 0 for lv in LEVELS for n in m.list(lv)}
    for lv in LEVELS[1:]:
        for owner in m.list(lv):
            for r in m.relations((lv, owner)):
                counts[(r.target_level, r.target)] += 1
    return counts


def assert_counts_consistent(m: Model):
    expected = independent_pointed_by(m)
    got = {k: m.pointed_by(k) for k in expected}
    assert got == expected


# ============================================================== create / names
class TestCreateAndNames:
    def test_create_at_each_level(self):
        m = Model()
        assert m.create("surface", "s", Surface(UNIT_SQUARE)) == "s"
        assert m.create("block", "b", colour=(1, 0, 0)) == "b"
        assert m.create("object", "o", movable=True) == "o"
        assert m.create("scene", "sc") == "sc"
        assert m.list() == {"surface": ["s"], "block": ["b"], "object": ["o"], "scene": ["sc"]}
        assert m.list("block") == ["b"]
        assert [m.level_of(n) for n in ("s", "b", "o", "sc")] == list(LEVELS)
        info = m.info("b")
        assert (info.level, info.name, info.pointed_by, info.n_relations) == ("block", "b", 0, 0)
        assert info.colour == (1.0, 0.0, 0.0, 1.0)
        assert m.info("o").movable
        assert not m.info("b").movable
        assert m.surface("s").area == pytest.approx(1.0)

    def test_creation_order_kept(self):
        m = Model()
        for n in ["z", "a", "m", "b"]:
            m.create("block", n)
        assert m.list("block") == ["z", "a", "m", "b"]

    def test_duplicate_name_at_one_level_refused(self):
        m = thesis_cube()
        assert_refused(m, lambda m: m.create("block", "cube1"), ModelError, "already exists")
        sq = Surface(UNIT_SQUARE)
        assert_refused(m, lambda m: m.create("surface", "square1", sq), ModelError, "exists")

    def test_same_name_at_two_levels_allowed(self):
        m = Model()
        m.create("surface", "x", Surface(UNIT_SQUARE))
        m.create("block", "x")
        m.create("object", "x")
        assert m.list("surface") == m.list("block") == m.list("object") == ["x"]

    def test_plain_name_resolves_when_unique(self):
        m = thesis_cube()
        m.create("object", "o")
        assert m.attach("o", "cube1") == "tb1"
        assert m.pointed_by("cube1") == 1
        assert m.exists("cube1")
        assert not m.exists("nothing")

    def test_ambiguous_plain_name_names_both_levels(self):
        m = thesis_cube()
        m.create("object", "cube1")
        with pytest.raises(ModelError) as info:
            m.pointed_by("cube1")
        assert "block" in str(info.value)
        assert "object" in str(info.value)
        assert "cube1" in str(info.value)
        assert not m.exists("cube1")
        assert m.exists(("block", "cube1"))
        assert m.exists(("object", "cube1"))
        assert m.pointed_by(("block", "cube1")) == 0
        assert m.info(("object", "cube1")).level == "object"
        # an attach with an ambiguous owner changes nothing
        assert_refused(m, lambda m: m.attach("cube1", "square1"), ModelError, "block and object")
        # the target's level is implied by the owner: cube1 under an object means the block
        m.create("object", "o")
        m.attach("o", "cube1")
        assert m.relations("o")[0].target_level == "block"

    def test_unknown_name_lists_known_names(self):
        m = thesis_cube()
        m.create("object", "table")
        with pytest.raises(ModelError) as info:
            m.info("tabel")
        msg = str(info.value)
        assert "tabel" in msg
        for known in ("cube1", "square1", "table"):
            assert known in msg
        with pytest.raises(ModelError, match=r"no block named 'nope'.*cube1"):
            m.info(("block", "nope"))
        with pytest.raises(ModelError, match="known: none"):
            Model().info("x")

    @pytest.mark.parametrize(
        "ref", [("widget", "cube1"), ("block",), ("block", "cube1", "x"), 5, None, ["cube1"]]
    )
    def test_bad_references(self, ref):
        m = thesis_cube()
        with pytest.raises(ModelError):
            m.info(ref)

    def test_unhashable_name_in_reference(self):
        m = thesis_cube()
        with pytest.raises(ModelError):
            m.info(("block", ["cube1"]))

    @pytest.mark.parametrize("name", ["", "1abc", "a b", "a/b", "é", None, 3, "x;y"])
    def test_invalid_names_refused(self, name):
        m = Model()
        assert_refused(m, lambda m: m.create("block", name), ModelError, "invalid name")

    @pytest.mark.parametrize("name", ["a", "_x", "cube.2", "part-7", "A_b.c-d9"])
    def test_valid_names(self, name):
        m = Model()
        assert m.create("block", name) == name


# ============================================================== relations
class TestAttach:
    def test_generated_names_per_level(self):
        m = thesis_cube()
        assert [r.name for r in m.relations("cube1")] == [f"ts{i}" for i in range(1, 7)]
        m.create("object", "o")
        m.create("scene", "sc")
        assert [m.attach("o", "cube1") for _ in range(3)] == ["tb1", "tb2", "tb3"]
        assert [m.attach("sc", "o") for _ in range(2)] == ["to1", "to2"]
        rel = m.relation("sc", "to2")
        assert (rel.kind, rel.owner, rel.target, rel.target_level) == (
            "transform_object",
            "sc",
            "o",
            "object",
        )
        assert m.relation("cube1", "ts1").kind == "transform_surface"
        assert m.relation("o", "tb1").kind == "transform_block"

    def test_generated_names_never_reused_after_detach(self):
        m = thesis_cube()
        m.detach("cube1", "ts6")
        assert m.attach("cube1", "square1") == "ts7"

    def test_explicit_relation_names(self):
        m = thesis_cube()
        m.create("object", "o")
        assert m.attach("o", "cube1", name="left") == "left"
        assert m.attach("o", "cube1", name="right") == "right"
        assert [r.name for r in m.relations("o")] == ["left", "right"]
        assert_refused(m, lambda m: m.attach("o", "cube1", name="left"), ModelError, "left")
        assert_refused(m, lambda m: m.attach("o", "cube1", name="9x"), ModelError, "invalid")

    def test_generated_names_skip_explicit_ones(self):
        m = thesis_cube()
        m.create("object", "o")
        m.attach("o", "cube1", name="tb2")
        names = [m.attach("o", "cube1") for _ in range(4)]
        all_names = [r.name for r in m.relations("o")]
        assert len(set(all_names)) == len(all_names) == 5
        assert all(re.fullmatch(r"tb\d+", n) for n in names)

    def test_same_relation_name_in_two_owners(self):
        m = thesis_cube()
        m.create("object", "o1")
        m.create("object", "o2")
        assert m.attach("o1", "cube1", name="base") == "base"
        assert m.attach("o2", "cube1", name="base") == "base"
        assert m.pointed_by("cube1") == 2

    @pytest.mark.parametrize(
        ("owner", "target", "match"),
        [
            (("block", "b"), ("block", "b2"), "points to surfaces"),
            (("block", "b"), ("object", "o"), "points to surfaces"),
            (("block", "b"), "b2", "no surface named 'b2'"),
            (("object", "o"), ("surface", "s"), "points to blocks"),
            (("object", "o"), ("object", "o2"), "points to blocks"),
            (("object", "o"), ("scene", "sc"), "points to blocks"),
            (("scene", "sc"), ("block", "b"), "points to objects"),
            (("scene", "sc"), ("scene", "sc2"), "points to objects"),
            (("surface", "s"), ("surface", "s"), "cannot own relations"),
            (("block", "bool"), ("surface", "s"), "points to blocks"),
        ],
    )
    def test_wrong_target_level_refused(self, owner, target, match):
        m = Model()
        m.create("surface", "s", Surface(UNIT_SQUARE))
        for b in ("b", "b2", "b3"):
            m.create("block", b)
        m.create_boolean("bool", "union", ["b2", "b3"])
        m.create("object", "o")
        m.create("object", "o2")
        m.create("scene", "sc")
        m.create("scene", "sc2")
        assert_refused(m, lambda m: m.attach(owner, target), ModelError, match)

    def test_boolean_block_points_to_blocks(self):
        m = Model()
        for b in ("a", "b", "c"):
            m.create("block", b)
        m.create_boolean("u", "union", ["a", "b"])
        assert [r.name for r in m.relations("u")] == ["op1", "op2"]
        assert all(r.kind == "transform_block" for r in m.relations("u"))
        name = m.attach("u", "c")
        assert m.relation("u", name).target == "c"
        assert m.info("u").boolean == "union"
        assert m.pointed_by("a") == m.pointed_by("c") == 1

    def test_attach_transform_is_stored(self):
        m = thesis_cube()
        T = spatial.srt(scale=(2, 3, 1.5), rotation=(0.1, 0.2, 0.3), translation=(1, 2, 3))
        m.create("object", "o")
        m.attach("o", "cube1", T)
        stored = m.relation("o", "tb1").transform
        assert np.array_equal(stored, T)
        with pytest.raises(ValueError, match="read-only"):
            stored[0, 0] = 5.0
        assert np.array_equal(m.relation("cube1", "ts2").transform, THESIS_ROWS[1])

    def test_attach_many(self):
        m = Model()
        m.create("surface", "s", Surface(UNIT_SQUARE))
        m.create("surface", "t", Surface.regular_polygon(3, 1.0))
        m.create("block", "b")
        Ts = np.stack([spatial.translation(i, 0, 0) for i in range(3)])
        assert m.attach_many("b", "s", Ts) == ["ts1", "ts2", "ts3"]
        assert m.attach_many("b", ["s", "t"], Ts[:2], names=["p", "q"]) == ["p", "q"]
        assert m.pointed_by("s") == 4
        assert m.pointed_by("t") == 1
        assert np.array_equal(m.relation("b", "ts3").transform, Ts[2])
        assert m.relation("b", "q").target == "t"

    def test_attach_many_single_matrix_as_nested_list_is_one_relation(self):
        m = Model()
        m.create("surface", "s", Surface(UNIT_SQUARE))
        m.create("block", "b")
        names = m.attach_many("b", "s", np.eye(4).tolist())
        assert names == ["ts1"]
        assert m.pointed_by("s") == 1
        names = m.attach_many("b", "s", [np.eye(4), np.eye(4)])
        assert names == ["ts2", "ts3"]
        assert m.pointed_by("s") == 3


class TestPointedBy:
    def test_exact_counts_after_attach_detach_copy_remove(self):
        m = thesis_cube()
        assert m.pointed_by("square1") == 6
        m.create("object", "o")
        m.attach("o", "cube1")
        m.attach("o", "cube1")
        assert m.pointed_by("cube1") == 2
        m.detach("cube1", "ts3")
        assert m.pointed_by("square1") == 5
        m.copy("cube1", "cube2")
        assert m.pointed_by("square1") == 10
        m.copy("o", "o2")
        assert m.pointed_by("cube1") == 4
        m.remove("o2")
        assert m.pointed_by("cube1") == 2
        m.remove("cube2")
        assert m.pointed_by("square1") == 5
        assert_counts_consistent(m)
        assert m.info("square1").pointed_by == 5

    def test_remove_refused_while_pointed_to_names_users(self):
        m = thesis_cube()
        m.create("object", "o1")
        m.create("object", "o2")
        m.attach("o1", "cube1")
        m.attach("o2", "cube1")
        m.attach("o2", "cube1")
        before = snapshot(m)
        with pytest.raises(ModelError) as info:
            m.remove("cube1")
        msg = str(info.value)
        assert "cube1" in msg
        assert "o1" in msg
        assert "o2" in msg
        assert "2 relations" in msg
        assert snapshot(m) == before
        assert_refused(m, lambda m: m.remove("square1"), ModelError, "cube1")
        assert_refused(m, lambda m: m.remove("square1", recursive=True), ModelError, "cube1")

    def test_remove_unused(self):
        m = thesis_cube()
        assert m.remove("cube1") == ["cube1"]
        assert m.pointed_by("square1") == 0
        assert m.remove("square1") == ["square1"]
        assert m.list() == {lv: [] for lv in LEVELS}

    def test_remove_recursive_shared_surface(self):
        m = Model()
        m.create("surface", "sq", Surface(UNIT_SQUARE))
        m.create("surface", "tri", Surface([(0, 0), (1, 0), (0, 1)]))
        m.create("surface", "lonely", Surface(UNIT_SQUARE))  # unused, not reachable
        m.create("block", "blkA")
        m.attach_many("blkA", "sq", np.stack([np.eye(4)] * 3))
        m.attach("blkA", "tri")
        m.create("block", "blkB")
        m.attach("blkB", "sq")
        m.create("block", "blkC")  # used only by objY
        m.attach("blkC", "tri")
        m.create("object", "objX")
        m.attach("objX", "blkA")
        m.attach("objX", "blkA")
        m.attach("objX", "blkC")
        m.create("object", "objY")
        m.attach("objY", "blkC")
        m.create("scene", "sc")
        m.attach("sc", "objX")
        # removing sc frees objX, which frees blkA; blkC is still used by objY, so tri stays;
        # sq is still used by blkB
        removed = m.remove("sc", recursive=True)
        assert set(removed) == {"sc", "objX", "blkA"}
        assert removed[0] == "sc"
        assert m.list() == {
            "surface": ["sq", "tri", "lonely"],
            "block": ["blkB", "blkC"],
            "object": ["objY"],
            "scene": [],
        }
        assert m.pointed_by("sq") == 1
        assert m.pointed_by("tri") == 1
        assert m.pointed_by("blkC") == 1
        assert_counts_consistent(m)
        # now objY frees blkC, and then tri
        assert set(m.remove("objY", recursive=True)) == {"objY", "blkC", "tri"}
        assert m.list("surface") == ["sq", "lonely"]

    def test_remove_recursive_through_boolean(self):
        m = Model()
        workcell.solids.cube(m, "a", size=1.0)
        workcell.solids.cube(m, "b", size=0.5)
        m.create_boolean("d", "difference", ["a", "b"])
        removed = m.remove("d", recursive=True)
        assert set(removed) == {"d", "a", "b", "a.square", "b.square"}
        assert m.list() == {lv: [] for lv in LEVELS}

    def test_detach(self):
        m = thesis_cube()
        m.detach("cube1", "ts2")
        assert [r.name for r in m.relations("cube1")] == ["ts1", "ts3", "ts4", "ts5", "ts6"]
        assert np.array_equal(m.relation("cube1", "ts3").transform, THESIS_ROWS[2])
        assert np.array_equal(m.relation("cube1", "ts6").transform, THESIS_ROWS[5])
        assert m.pointed_by("square1") == 5
        assert_refused(m, lambda m: m.detach("cube1", "ts2"), ModelError, "ts1, ts3")
        assert_refused(m, lambda m: m.detach("nocube", "ts1"), ModelError, "cube1")


# ============================================================== modify
class TestModify:
    def test_rename_keeps_relations(self):
        m = thesis_cube()
        m.create("object", "o")
        m.attach("o", "cube1")
        m.rename("square1", "unit_square")
        m.rename("cube1", "cube_one")
        assert m.list("surface") == ["unit_square"]
        assert not m.exists("square1")
        assert not m.exists("cube1")
        assert {r.target for r in m.relations("cube_one")} == {"unit_square"}
        assert m.relation("o", "tb1").target == "cube_one"
        assert m.pointed_by("unit_square") == 6
        assert m.pointed_by("cube_one") == 1
        assert m.properties("o").volume == pytest.approx(1.0, abs=1e-12)
        with pytest.raises(ModelError, match="cube1"):
            m.info("cube1")

    def test_rename_keeps_position(self):
        m = Model()
        for n in ("a", "b", "c"):
            m.create("block", n)
        m.rename("b", "z")
        assert m.list("block") == ["a", "z", "c"]

    def test_rename_refusals(self):
        m = thesis_cube()
        m.create("block", "other")
        assert_refused(m, lambda m: m.rename("cube1", "other"), ModelError, "already exists")
        assert_refused(m, lambda m: m.rename("cube1", "bad name"), ModelError, "invalid")
        assert_refused(m, lambda m: m.rename("nope", "fine"), ModelError, "no entity")
        m.rename("cube1", "square1")  # another level: allowed, then ambiguous by plain name
        assert m.exists(("block", "square1"))
        assert not m.exists("square1")

    def test_rename_relation(self):
        m = thesis_cube()
        m.rename_relation("cube1", "ts1", "front")
        assert [r.name for r in m.relations("cube1")][:2] == ["front", "ts2"]
        assert np.array_equal(m.relation("cube1", "front").transform, THESIS_ROWS[0])
        assert_refused(m, lambda m: m.relation("cube1", "ts1"), ModelError, "front")
        assert_refused(m, lambda m: m.rename_relation("cube1", "ts2", "front"), ModelError)
        assert_refused(m, lambda m: m.rename_relation("cube1", "ts9", "x"), ModelError, "ts9")
        assert_refused(m, lambda m: m.rename_relation("cube1", "ts2", "1x"), ModelError)
        # generated names then skip the new name
        m.rename_relation("cube1", "ts2", "ts7")
        new = m.attach("cube1", "square1")
        names = [r.name for r in m.relations("cube1")]
        assert new != "ts7"
        assert len(set(names)) == len(names)

    def test_set_transform(self):
        m = thesis_cube()
        T = spatial.srt(rotation=(0, 0, 0.3), translation=(5, 0, 0))
        m.set_transform("cube1", "ts5", T)
        assert np.array_equal(m.relation("cube1", "ts5").transform, T)
        assert_refused(
            m, lambda m: m.set_transform("cube1", "ts5", np.zeros((4, 4))), GeometryError
        )
        assert_refused(
            m, lambda m: m.set_transform("cube1", "ts5", np.stack([T, T])), GeometryError
        )
        assert_refused(m, lambda m: m.set_transform("cube1", "nope", T), ModelError)

    def test_set_transform_changes_geometry(self):
        m = thesis_cube()
        assert m.properties("cube1").volume == pytest.approx(1.0, abs=1e-12)
        m.create("object", "o")
        m.attach("o", "cube1")
        m.set_transform("o", "tb1", spatial.scaling(2, 2, 2))
        assert m.properties("o").volume == pytest.approx(8.0, rel=1e-12)

    @pytest.mark.parametrize(
        ("colour", "stored"),
        [
            ((1, 0, 0), (1.0, 0.0, 0.0, 1.0)),
            ((0.1, 0.2, 0.3, 0.4), (0.1, 0.2, 0.3, 0.4)),
            (np.array([0, 1, 0.5]), (0.0, 1.0, 0.5, 1.0)),
            (None, None),
        ],
    )
    def test_set_colour(self, colour, stored):
        m = thesis_cube()
        m.set_colour("cube1", (0.5, 0.5, 0.5))
        m.set_colour("cube1", colour)
        assert m.info("cube1").colour == stored

    @pytest.mark.parametrize(
        "colour",
        [
            (1.5, 0, 0),
            (-0.1, 0, 0),
            (math.nan, 0, 0),
            (1, 0),
            (1, 0, 0, 1, 1),
            "red",
            0.5,
            (),
            (10**400, 0, 0),
        ],
    )
    def test_set_colour_refused(self, colour):
        m = thesis_cube()
        m.set_colour("cube1", (0.5, 0.5, 0.5))
        assert_refused(m, lambda m: m.set_colour("cube1", colour), ModelError, "colour")
        assert_refused(m, lambda m: m.create("block", "b2", colour=colour), ModelError, "colour")

    def test_set_movable(self):
        m = thesis_cube()
        m.set_movable("cube1", True)
        assert m.info("cube1").movable
        m.set_movable("cube1", False)
        assert not m.info("cube1").movable
        assert_refused(m, lambda m: m.set_movable("square1", True), ModelError, "surfaces")
        assert_refused(
            m,
            lambda m: m.create("surface", "s2", Surface(UNIT_SQUARE), movable=True),
            ModelError,
        )

    def test_set_surface_changes_every_user(self):
        m = thesis_cube()
        m.copy("cube1", "cube2", spatial.translation(3, 0, 0))
        assert m.properties("cube1").volume == pytest.approx(1.0, abs=1e-12)
        m.set_surface("square1", Surface([(0, 0), (2, 0), (2, 2), (0, 2)]))
        assert m.surface("square1").area == pytest.approx(4.0)
        # the six placed squares, now 2 x 2, no longer close a solid, but the area is 6 x 4
        assert m.world_mesh("cube2").area == pytest.approx(24.0, rel=1e-12)
        assert m.world_mesh("cube1").bounds[1].tolist() == [2.0, 2.0, 2.0]
        assert_refused(m, lambda m: m.set_surface("square1", UNIT_SQUARE), ModelError)
        assert_refused(
            m, lambda m: m.set_surface(("block", "cube1"), Surface(UNIT_SQUARE)), ModelError
        )


# ============================================================== copy
class TestCopy:
    def test_block_copy_with_scaling_is_the_thesis_parallelepiped(self):
        m = thesis_cube()
        m.copy("cube1", "box", spatial.scaling(2, 3, 1.5))
        p = m.properties("box")
        assert p.volume == pytest.approx(9.0, rel=1e-12)
        assert np.allclose(p.centroid, [1.0, 1.5, 0.75], atol=1e-12)
        # a box a x b x c about its centroid: m/12 (b^2 + c^2, a^2 + c^2, a^2 + b^2), m = 9
        expect = 9 / 12 * np.diag([3**2 + 1.5**2, 2**2 + 1.5**2, 2**2 + 3**2])
        assert np.allclose(p.inertia, expect, rtol=1e-10, atol=1e-12)
        assert p.area == pytest.approx(2 * (6 + 3 + 4.5), rel=1e-12)
        assert m.pointed_by("square1") == 12
        assert m.world_mesh("box").is_watertight
        for r0, r1 in zip(m.relations("cube1"), m.relations("box"), strict=True):
            assert r1.name == r0.name
            assert r1.target == r0.target
            assert np.allclose(r1.transform, spatial.scaling(2, 3, 1.5) @ r0.transform)

    def test_object_with_scaling_tb_is_the_other_parallelepiped(self):
        m = thesis_cube()
        m.create("object", "para")
        m.attach("para", "cube1", spatial.scaling(2, 3, 1.5))
        p = m.properties("para")
        assert p.volume == pytest.approx(9.0, rel=1e-12)
        assert np.allclose(p.centroid, [1.0, 1.5, 0.75], atol=1e-12)
        assert m.pointed_by("cube1") == 1

    def test_copy_without_transform(self):
        m = thesis_cube()
        m.set_colour("cube1", (1, 0, 0))
        m.set_movable("cube1", True)
        m.copy("cube1", "cube2")
        d = m.to_dict()["blocks"]
        assert {k: v for k, v in d[1].items() if k != "name"} == {
            k: v for k, v in d[0].items() if k != "name"
        }
        assert m.properties("cube2").volume == pytest.approx(1.0, abs=1e-12)

    def test_copy_keeps_generated_names_unique(self):
        m = thesis_cube()
        m.rename_relation("cube1", "ts6", "ts8")
        m.detach("cube1", "ts1")
        m.copy("cube1", "cube2")
        for owner in ("cube1", "cube2"):
            for _ in range(3):
                m.attach(owner, "square1")
            names = [r.name for r in m.relations(owner)]
            assert len(set(names)) == len(names), names
        assert [r.name for r in m.relations("cube1")] == [r.name for r in m.relations("cube2")]

    def test_surface_copy_in_plane_scales_area(self):
        m = thesis_cube()
        T = spatial.srt(scale=(2, 3, 5), rotation=(0, 0, 0.7), translation=(1, -2, 0))
        m.copy("square1", "rect", T)
        s = m.surface("rect")
        assert s.area == pytest.approx(6.0, rel=1e-12)
        expect = np.array(UNIT_SQUARE) @ T[:2, :2].T + T[:2, 3]
        assert {tuple(np.round(p, 12)) for p in s.main} == {tuple(np.round(p, 12)) for p in expect}
        m.copy("square1", "mirror", spatial.scaling(-1, 1, 1))
        assert m.surface("mirror").area == pytest.approx(1.0)
        m.copy("square1", "same")
        assert m.surface("same").same_geometry(m.surface("square1"))
        assert m.pointed_by("rect") == 0

    @pytest.mark.parametrize(
        "T",
        [spatial.rot_x(0.1), spatial.rot_y(D90), spatial.translation(0, 0, 1)],
        ids=["rot-x", "rot-y", "shift-z"],
    )
    def test_surface_copy_out_of_plane_refused(self, T):
        m = thesis_cube()
        assert_refused(m, lambda m: m.copy("square1", "s2", T), GeometryError, "plane")

    def test_object_and_scene_copy(self):
        m = thesis_cube()
        m.create("object", "o")
        m.attach("o", "cube1", spatial.translation(1, 0, 0))
        m.create("scene", "sc")
        m.attach("sc", "o", spatial.rot_z(0.5))
        m.copy("o", "o2", spatial.scaling(2, 1, 1))
        assert np.allclose(
            m.relation("o2", "tb1").transform,
            spatial.scaling(2, 1, 1) @ spatial.translation(1, 0, 0),
        )
        m.copy("sc", "sc2", spatial.translation(0, 0, 4))
        assert np.allclose(
            m.relation("sc2", "to1").transform, spatial.translation(0, 0, 4) @ spatial.rot_z(0.5)
        )
        assert m.pointed_by("o") == 2
        assert m.pointed_by("cube1") == 2
        assert m.properties("sc2").centroid[2] == pytest.approx(4.5)
        assert_refused(m, lambda m: m.copy("sc", "sc3", spatial.scaling(2)), GeometryError, "rigid")
        assert_refused(m, lambda m: m.copy("sc", "sc3", np.diag([1, 1, -1, 1.0])), GeometryError)

    def test_copy_refusals(self):
        m = thesis_cube()
        m.create("block", "taken")
        assert_refused(m, lambda m: m.copy("cube1", "taken"), ModelError, "already exists")
        assert_refused(m, lambda m: m.copy("cube1", "bad name"), ModelError, "invalid")
        assert_refused(m, lambda m: m.copy("cube1", "c2", np.zeros((4, 4))), GeometryError)
        assert_refused(m, lambda m: m.copy("nope", "c2"), ModelError)
        assert_refused(m, lambda m: m.copy("square1", "taken2", "junk"), GeometryError)


# ============================================================== scenes and cycles
class TestSceneAndCycles:
    @pytest.mark.parametrize(
        "T",
        [
            spatial.scaling(2, 1, 1),
            np.diag([1.0, 1.0, -1.0, 1.0]),  # a reflection is not a placement
            np.array([[1, 0.1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]),
        ],
        ids=["scale", "reflect", "shear"],
    )
    def test_scene_relations_must_be_rigid(self, T):
        m = thesis_cube()
        m.create("object", "o")
        m.attach("o", "cube1", T)  # fine inside an object
        m.create("scene", "sc")
        assert_refused(m, lambda m: m.attach("sc", "o", T), GeometryError, "rigid")
        m.attach("sc", "o", spatial.srt(rotation=(0.3, -1.2, 2.0), translation=(1, 2, 3)))
        assert_refused(m, lambda m: m.set_transform("sc", "to1", T), GeometryError, "rigid")

    @pytest.mark.parametrize(
        "T",
        [
            np.zeros((4, 4)),
            np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0.1, 0, 0, 1.0]]),
            np.full((4, 4), np.nan),
            np.diag([1.0, 1.0, 0.0, 1.0]),
            np.eye(3),
            np.eye(4)[None].repeat(2, axis=0),
            "identity",
            [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 10**400]],
        ],
        ids=["zero", "projective", "nan", "singular", "3x3", "stack", "string", "overflow"],
    )
    def test_bad_transforms_refused(self, T):
        m = thesis_cube()
        assert_refused(m, lambda m: m.attach("cube1", "square1", T), GeometryError)

    def test_cycles_through_boolean_blocks_refused(self):
        m = Model()
        for b in ("a", "b"):
            workcell.solids.cube(m, b, size=1.0)
        m.create_boolean("u", "union", ["a", "b"])
        m.create_boolean("v", "difference", ["u", "a"])
        assert_refused(m, lambda m: m.attach("u", "u"), ModelError, "cycle")
        assert_refused(m, lambda m: m.attach("u", "v"), ModelError, "cycle")
        assert_refused(m, lambda m: m.attach_many("u", ["a", "v"], [np.eye(4)] * 2), ModelError)
        m.create_boolean("w", "intersection", ["v", "b"])
        assert_refused(m, lambda m: m.attach("u", "w"), ModelError, "cycle")
        assert m.attach("w", "u")  # down the hierarchy is fine

    def test_boolean_refusals(self):
        m = Model()
        for b in ("a", "b"):
            workcell.solids.cube(m, b, size=1.0)
        m.create("object", "o")
        cases = [
            (lambda m: m.create_boolean("x", "xor", ["a", "b"]), "xor"),
            (lambda m: m.create_boolean("x", "union", ["a"]), "at least 2"),
            (lambda m: m.create_boolean("x", "union", ["a", "nope"]), "nope"),
            (lambda m: m.create_boolean("x", "union", ["a", ("object", "o")]), "blocks"),
            (lambda m: m.create_boolean("x", "union", ["a", "b"], [None]), "transforms"),
            (lambda m: m.create_boolean("x", "union", ["a", "b"], [None, np.zeros((4, 4))]), None),
            (lambda m: m.create_boolean("a", "union", ["a", "b"]), "already exists"),
            (lambda m: m.create_boolean("1x", "union", ["a", "b"]), "invalid"),
            (lambda m: m.create_boolean("x", "union", ["a", "b"], colour=(2, 0, 0)), "colour"),
        ]
        for fn, match in cases:
            assert_refused(m, fn, WorkcellError, match)
        m.create_boolean("x", "union", ["a", "b"])
        assert_refused(m, lambda m: m.detach("x", "op1"), ModelError, "at least 2")


# ============================================================== queries
def _hierarchy() -> Model:
    m = Model()
    for s in ("s1", "s2", "s3"):
        m.create("surface", s, Surface(UNIT_SQUARE))
    for b in ("b1", "b2", "b3"):
        m.create("block", b)
    m.attach("b1", "s1")
    m.attach("b1", "s1")
    m.attach("b2", "s1")
    m.attach("b2", "s2")
    for o in ("o1", "o2"):
        m.create("object", o)
    m.attach("o1", "b1")
    m.attach("o1", "b2")
    m.attach("o2", "b2")
    for sc in ("sc1", "sc2"):
        m.create("scene", sc)
    m.attach("sc1", "o1")
    m.attach("sc2", "o1")
    m.attach("sc2", "o2")
    return m


class TestQueries:
    @pytest.mark.parametrize(
        ("ref", "expected"),
        [
            (
                "sc2",
                {
                    ("object", "o1"),
                    ("object", "o2"),
                    ("block", "b1"),
                    ("block", "b2"),
                    ("surface", "s1"),
                    ("surface", "s2"),
                },
            ),
            (
                "sc1",
                {
                    ("object", "o1"),
                    ("block", "b1"),
                    ("block", "b2"),
                    ("surface", "s1"),
                    ("surface", "s2"),
                },
            ),
            ("o2", {("block", "b2"), ("surface", "s1"), ("surface", "s2")}),
            ("b1", {("surface", "s1")}),
            ("b3", set()),
            ("s1", set()),
        ],
    )
    def test_made_of(self, ref, expected):
        got = _hierarchy().made_of(ref)
        assert set(got) == expected
        assert len(got) == len(expected)

    @pytest.mark.parametrize(
        ("ref", "expected"),
        [
            (
                "s1",
                {
                    ("block", "b1"),
                    ("block", "b2"),
                    ("object", "o1"),
                    ("object", "o2"),
                    ("scene", "sc1"),
                    ("scene", "sc2"),
                },
            ),
            (
                "s2",
                {
                    ("block", "b2"),
                    ("object", "o1"),
                    ("object", "o2"),
                    ("scene", "sc1"),
                    ("scene", "sc2"),
                },
            ),
            ("b1", {("object", "o1"), ("scene", "sc1"), ("scene", "sc2")}),
            ("o2", {("scene", "sc2")}),
            ("s3", set()),
            ("sc1", set()),
        ],
    )
    def test_used_in(self, ref, expected):
        got = _hierarchy().used_in(ref)
        assert set(got) == expected
        assert len(got) == len(expected)

    def test_list(self):
        m = _hierarchy()
        assert m.list("surface") == ["s1", "s2", "s3"]
        assert m.list("scene") == ["sc1", "sc2"]
        assert set(m.list()) == set(LEVELS)
        with pytest.raises(ModelError, match="surface, block, object, scene"):
            m.list("blocks")
        got = m.list("block")
        got.append("zzz")  # a copy, not the model's own list
        assert m.list("block") == ["b1", "b2", "b3"]

    def test_pointed_by_in_hierarchy(self):
        m = _hierarchy()
        assert independent_pointed_by(m) == {
            ("surface", "s1"): 3,
            ("surface", "s2"): 1,
            ("surface", "s3"): 0,
            ("block", "b1"): 1,
            ("block", "b2"): 2,
            ("block", "b3"): 0,
            ("object", "o1"): 2,
            ("object", "o2"): 1,
            ("scene", "sc1"): 0,
            ("scene", "sc2"): 0,
        }
        assert_counts_consistent(m)


class TestShow:
    def test_summary_mentions_entity_and_counts(self):
        m = thesis_cube()
        text = m.show("square1")
        assert "surface square1" in text
        assert "pointed_by=6" in text
        assert "cube1" in text
        assert "x6" in text
        text = m.show("cube1")
        assert "block cube1" in text
        assert "pointed_by=0" in text
        assert "6 relations" in text
        assert "ts1" not in text

    def test_detail_lists_relations_and_transforms(self):
        m = thesis_cube()
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # e.g. no gimbal-lock warning for R_y = -90
            text = m.show("cube1", detail=True)
        lines = text.splitlines()
        for i in range(1, 7):
            assert any(ln.strip().startswith(f"ts{i} -> surface square1") for ln in lines)
        ts2 = next(ln for ln in lines if ln.strip().startswith("ts2 "))
        assert "T=(0, 1, 0)" in ts2
        assert "R=(90, 0, 0) deg" in ts2
        ts4 = next(ln for ln in lines if ln.strip().startswith("ts4 "))
        assert "T=(1, 0, 0)" in ts4
        assert "R=(0, -90, 0) deg" in ts4
        ts5 = next(ln for ln in lines if ln.strip().startswith("ts5 "))
        assert ts5.rstrip().endswith("identity")
        text = m.show("square1", detail=True)
        assert "main: (0, 0) (1, 0) (1, 1) (0, 1)" in text

    def test_show_model_and_flags(self):
        m = thesis_cube()
        m.create("object", "robot_base", colour=(1, 0, 0), movable=True)
        m.attach("robot_base", "cube1", name="leg")
        text = m.show()
        for needle in ("surfaces (1):", "blocks (1):", "objects (1):", "scenes (0):"):
            assert needle in text
        assert "robot_base" in text
        assert "movable" in text
        assert "colour=(1, 0, 0, 1)" in text
        assert "leg" not in text
        assert "leg -> block cube1" in m.show(detail=True)
        m.create_boolean("u", "union", ["cube1", "cube1"])
        assert "union of 2 relations" in m.show("u")

    @pytest.mark.parametrize(
        ("T", "expect"),
        [
            (np.eye(4), "identity"),
            (spatial.scaling(2, 3, 1.5), "S=(2, 3, 1.5)"),
            (np.diag([1.0, 1.0, -1.0, 1.0]), "reflected"),
            (np.array([[1, 0.5, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]), "sheared"),
            (spatial.translation(0.25, -1, 3), "T=(0.25, -1, 3)"),
        ],
    )
    def test_describe_transform_cases(self, T, expect):
        assert expect in describe_transform(T)

    @given(
        scale=st.tuples(*[st.floats(0.1, 10)] * 3),
        rot=st.tuples(st.floats(-3, 3), st.floats(-1.5, 1.5), st.floats(-3, 3)),
        pitch_lock=st.booleans(),
        trans=st.tuples(*[st.floats(-100, 100)] * 3),
        reflect=st.booleans(),
    )
    @settings(max_examples=60, deadline=None)
    def test_describe_transform_round_trip(self, scale, rot, pitch_lock, trans, reflect):
        """Rebuild the matrix from the printed T, R, S: srt(S, R, T) must give it back."""
        if pitch_lock:
            rot = (rot[0], math.copysign(D90, rot[1]), rot[2])
        T = spatial.srt(scale=scale, rotation=rot, translation=trans)
        if reflect:
            T = T @ np.diag([1.0, 1.0, -1.0, 1.0])
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            text = describe_transform(T)

        def triple(tag, default):
            found = re.search(tag + r"=\(([^)]*)\)", text)
            return np.array([float(x) for x in found.group(1).split(",")]) if found else default

        s = triple("S", np.ones(3))
        r = np.deg2rad(triple("R", np.zeros(3)))
        t = triple("T", np.zeros(3))
        if "reflected" in text:
            s = s * [1, 1, -1]
        assert ("reflected" in text) == reflect
        rebuilt = np.eye(4)
        rebuilt[:3, :3] = Rotation.from_euler("xyz", r).as_matrix() @ np.diag(s)
        rebuilt[:3, 3] = t
        assert np.allclose(rebuilt, T, rtol=1e-5, atol=1e-3)


# ============================================================== the thesis unit cube
class TestThesisUnitCube:
    def test_volume_centroid_inertia(self):
        m = thesis_cube()
        p = m.properties("cube1")
        assert p.volume == pytest.approx(1.0, abs=1e-12)
        assert p.area == pytest.approx(6.0, abs=1e-12)
        assert np.allclose(p.centroid, [0.5, 0.5, 0.5], atol=1e-12)
        assert np.allclose(p.inertia, np.eye(3) / 6, atol=1e-12)

    def test_world_mesh_is_watertight_and_outward(self):
        m = thesis_cube()
        mesh = m.world_mesh("cube1")
        assert mesh.is_watertight
        assert mesh.is_winding_consistent
        assert mesh.volume == pytest.approx(1.0, abs=1e-12)  # trimesh's own volume: positive
        assert np.allclose(mesh.bounds, [[0, 0, 0], [1, 1, 1]])
        assert m.validity("cube1").ok

    def test_model_reports_the_three_inward_faces(self):
        # front side (+z of the square) of each row: R_x=90 -> -y at y=0 (out); +T_y=1 ->
        # -y at y=1 (in); R_y=-90 -> -x at x=0 (out); +T_x=1 -> -x at x=1 (in); identity ->
        # +z at z=0 (in); T_z=1 -> +z at z=1 (out)
        m = thesis_cube()
        for T, name in zip(THESIS_ROWS, ["ts1", "ts2", "ts3", "ts4", "ts5", "ts6"], strict=True):
            centre = T @ [0.5, 0.5, 0, 1]
            normal = T[:3, 2]
            outward = np.dot(normal, centre[:3] - 0.5) > 0
            assert outward == (name in ("ts1", "ts3", "ts6"))
        assert sorted(reoriented_relations(m._get("cube1"))) == ["ts2", "ts4", "ts5"]

    def test_parallelepiped_by_instancing_in_an_object(self):
        m = thesis_cube()
        m.create("object", "o")
        m.attach("o", "cube1", spatial.srt(scale=(2, 3, 1.5), translation=(10, 0, 0)))
        m.attach("o", "cube1")
        p = m.properties("o")
        assert p.volume == pytest.approx(10.0, rel=1e-12)
        assert np.allclose(p.centroid, (9 * np.array([11, 1.5, 0.75]) + 0.5) / 10)

    def test_solids_cube_needs_no_reorientation(self):
        # solids.cube places the same six rows with the three inward faces turned over
        m = Model()
        workcell.solids.cube(m, "c", size=1.0)
        assert reoriented_relations(m._get("c")) == []


# ============================================================== atomicity
def _rich_model() -> Model:
    m = thesis_cube()
    m.create("surface", "tri", Surface([(0, 0), (1, 0), (0, 1)]))
    workcell.solids.cube(m, "c2", size=2.0)
    m.create_boolean("u", "union", ["cube1", "c2"], [None, spatial.translation(0.5, 0, 0)])
    m.create("object", "o", colour=(0, 1, 0))
    m.attach("o", "cube1")
    m.attach("o", "u", spatial.scaling(2, 1, 1), name="big")
    m.create("scene", "sc")
    m.attach("sc", "o", spatial.rot_z(0.3))
    m.create("object", "cube1")  # same name at a second level: plain "cube1" is ambiguous
    m.create("surface", "kk.square", Surface(UNIT_SQUARE))  # what solids.cube(m, "kk") makes
    return m


R = spatial.rot_z(0.2)
SING = np.zeros((4, 4))
SCALE = spatial.scaling(2, 1, 1)
ATOMIC_CASES = {
    # create
    "create-bad-level": lambda m: m.create("blocks", "x"),
    "create-dup": lambda m: m.create("block", "c2"),
    "create-bad-name": lambda m: m.create("block", "a b"),
    "create-surface-without-surface": lambda m: m.create("surface", "x"),
    "create-surface-bad-type": lambda m: m.create("surface", "x", UNIT_SQUARE),
    "create-block-with-surface": lambda m: m.create("block", "x", Surface(UNIT_SQUARE)),
    "create-movable-surface": lambda m: m.create(
        "surface", "x", Surface(UNIT_SQUARE), movable=True
    ),
    "create-bad-colour": lambda m: m.create("block", "x", colour=(0, 0, 3)),
    # create_boolean
    "bool-op": lambda m: m.create_boolean("x", "minus", [("block", "cube1"), "c2"]),
    "bool-one-operand": lambda m: m.create_boolean("x", "union", ["c2"]),
    "bool-unknown-operand": lambda m: m.create_boolean("x", "union", ["c2", "c9"]),
    "bool-object-operand": lambda m: m.create_boolean("x", "union", ["c2", ("object", "o")]),
    "bool-transform-count": lambda m: m.create_boolean("x", "union", ["c2", "u"], [None] * 3),
    "bool-singular": lambda m: m.create_boolean("x", "union", ["c2", "u"], [None, SING]),
    "bool-dup-name": lambda m: m.create_boolean("u", "union", ["c2", "u"]),
    "bool-bad-name": lambda m: m.create_boolean("-u", "union", ["c2", "u"]),
    "bool-bad-colour": lambda m: m.create_boolean("x", "union", ["c2", "u"], colour="blue"),
    # attach
    "attach-unknown-owner": lambda m: m.attach("nope", "square1"),
    "attach-ambiguous-owner": lambda m: m.attach("cube1", "square1"),
    "attach-surface-owner": lambda m: m.attach("square1", "tri"),
    "attach-unknown-target": lambda m: m.attach("c2", "nope"),
    "attach-wrong-level": lambda m: m.attach(("object", "o"), ("surface", "tri")),
    "attach-block-to-block": lambda m: m.attach("c2", ("block", "cube1")),
    "attach-cycle": lambda m: m.attach("u", "u"),
    "attach-singular": lambda m: m.attach("c2", "tri", SING),
    "attach-nan": lambda m: m.attach("c2", "tri", np.full((4, 4), np.nan)),
    "attach-non-affine": lambda m: m.attach("c2", "tri", np.ones((4, 4))),
    "attach-scene-non-rigid": lambda m: m.attach("sc", "o", SCALE),
    "attach-dup-name": lambda m: m.attach("o", ("block", "cube1"), name="big"),
    "attach-bad-name": lambda m: m.attach("o", ("block", "cube1"), name="b g"),
    # attach_many
    "many-one-bad-transform": lambda m: m.attach_many("c2", "tri", [np.eye(4), R, SING]),
    "many-one-bad-target": lambda m: m.attach_many("c2", ["tri", "nope"], [np.eye(4), R]),
    "many-one-wrong-level": lambda m: m.attach_many("c2", ["tri", ("block", "c2")], [np.eye(4), R]),
    "many-target-count": lambda m: m.attach_many("c2", ["tri"], [np.eye(4), R]),
    "many-name-count": lambda m: m.attach_many("c2", "tri", [np.eye(4), R], names=["a"]),
    "many-names-twice": lambda m: m.attach_many("c2", "tri", [np.eye(4), R], names=["a", "a"]),
    "many-name-taken": lambda m: m.attach_many(
        ("block", "cube1"), "tri", [R, R], names=["new", "ts3"]
    ),
    "many-junk": lambda m: m.attach_many("c2", "tri", "junk"),
    "many-ragged": lambda m: m.attach_many("c2", "tri", ([np.eye(4)], [np.eye(3)])),
    "many-scene-one-non-rigid": lambda m: m.attach_many("sc", "o", np.stack([R, SCALE])),
    # detach
    "detach-unknown-rel": lambda m: m.detach("c2", "ts99"),
    "detach-unknown-owner": lambda m: m.detach("c9", "ts1"),
    "detach-boolean-min": lambda m: m.detach("u", "op2"),
    # remove
    "remove-pointed": lambda m: m.remove(("block", "cube1")),
    "remove-pointed-recursive": lambda m: m.remove("square1", recursive=True),
    "remove-unknown": lambda m: m.remove("zzz"),
    "remove-ambiguous": lambda m: m.remove("cube1"),
    # rename
    "rename-dup": lambda m: m.rename("c2", "u"),
    "rename-bad": lambda m: m.rename("c2", "2c"),
    "rename-unknown": lambda m: m.rename("c9", "c10"),
    # rename_relation
    "rename-rel-dup": lambda m: m.rename_relation("o", "tb1", "big"),
    "rename-rel-unknown": lambda m: m.rename_relation("o", "tb9", "x"),
    "rename-rel-bad": lambda m: m.rename_relation("o", "tb1", ""),
    # set_transform
    "set-transform-singular": lambda m: m.set_transform("o", "big", SING),
    "set-transform-scene": lambda m: m.set_transform("sc", "to1", SCALE),
    "set-transform-stack": lambda m: m.set_transform("o", "big", np.stack([R, R])),
    "set-transform-junk": lambda m: m.set_transform("o", "big", "junk"),
    "set-transform-unknown": lambda m: m.set_transform("o", "nope", R),
    # set_colour / set_movable / set_surface
    "colour-range": lambda m: m.set_colour("c2", (0, 0, 1.01)),
    "colour-len": lambda m: m.set_colour("c2", (0, 0)),
    "colour-junk": lambda m: m.set_colour("c2", {"r": 1}),
    "colour-unknown": lambda m: m.set_colour("c9", (0, 0, 0)),
    "movable-surface": lambda m: m.set_movable("square1", True),
    "movable-unknown": lambda m: m.set_movable("c9", True),
    "set-surface-junk": lambda m: m.set_surface("square1", "square"),
    "set-surface-block": lambda m: m.set_surface(("block", "c2"), Surface(UNIT_SQUARE)),
    # copy
    "copy-dup": lambda m: m.copy("c2", "u"),
    "copy-bad-name": lambda m: m.copy("c2", "u u"),
    "copy-singular": lambda m: m.copy("c2", "c3", SING),
    "copy-surface-out-of-plane": lambda m: m.copy("square1", "sq2", spatial.rot_y(0.3)),
    "copy-surface-singular-in-plane": lambda m: m.copy(
        "square1", "sq2", np.diag([1e-7, 1e-7, 1e9, 1.0])
    ),
    "copy-scene-non-rigid": lambda m: m.copy("sc", "sc2", SCALE),
    "copy-unknown": lambda m: m.copy("c9", "c10"),
    # solid builders
    "cube-clash": lambda m: workcell.solids.cube(m, "c2", size=1.0),
    "cube-surface-clash": lambda m: workcell.solids.cube(m, "kk", size=1.0),  # kk.square exists
    "cube-size-zero": lambda m: workcell.solids.cube(m, "k", size=0.0),
    "cube-size-neg": lambda m: workcell.solids.cube(m, "k", size=-1.0),
    "cube-size-nan": lambda m: workcell.solids.cube(m, "k", size=math.nan),
    "cube-size-str": lambda m: workcell.solids.cube(m, "k", size="1"),
    "cube-bad-name": lambda m: workcell.solids.cube(m, "k k", size=1.0),
    "cube-bad-colour": lambda m: workcell.solids.cube(m, "k", size=1.0, colour=(5, 5, 5)),
    "box-shape": lambda m: workcell.solids.box(m, "k", size=(1, 2)),
    "box-zero": lambda m: workcell.solids.box(m, "k", size=(1, 0, 2)),
    "cylinder-clash": lambda m: workcell.solids.cylinder(m, "u", radius=1, height=1, n=8),
    "cylinder-n": lambda m: workcell.solids.cylinder(m, "k", radius=1, height=1, n=2),
    "cylinder-r": lambda m: workcell.solids.cylinder(m, "k", radius=-1, height=1, n=8),
    "sphere-m": lambda m: workcell.solids.sphere(m, "k", radius=1, m=2, n=2),
    "sphere-clash": lambda m: workcell.solids.sphere(m, "c2", radius=1, m=6, n=2),
    "cone-h": lambda m: workcell.solids.cone(m, "k", radius=1, height=0, n=8),
    "torus-r": lambda m: workcell.solids.torus(m, "k", major_radius=1, minor_radius=-1, m=8, n=6),
    "extrude-clash": lambda m: workcell.solids.extrude(m, "c2", Surface(UNIT_SQUARE), height=1),
    "extrude-flat": lambda m: workcell.solids.extrude(
        m, "k", Surface(UNIT_SQUARE), direction=(1, 0, 0)
    ),
}


@pytest.mark.parametrize("case", sorted(ATOMIC_CASES))
def test_failed_operation_changes_nothing(case):
    fn = ATOMIC_CASES[case]
    m = _rich_model()
    world_before = m.properties(("object", "o")).volume
    assert_refused(m, fn, WorkcellError)
    assert_counts_consistent(m)
    assert m.properties(("object", "o")).volume == pytest.approx(world_before, rel=1e-12)


def test_rich_model_operations_succeed_where_the_cases_fail():
    """The atomic cases fail because of the fault, not the setup: their fixed twins work."""
    m = _rich_model()
    m.create("block", "x")
    m.create_boolean("x2", "union", ["c2", "u"])
    m.attach("c2", "tri", R)
    m.attach_many("c2", "tri", [np.eye(4), R])
    m.attach("sc", "o", R)
    m.detach("o", "big")
    m.remove(("object", "cube1"))
    m.rename("c2", "c3")
    m.set_transform("c3", "ts1", R @ m.relation("c3", "ts1").transform)
    m.set_colour("c3", (0, 0, 1))
    workcell.solids.cube(m, "k", size=1.0)
    m.copy("square1", "sq2", spatial.rot_z(0.3))
    assert_counts_consistent(m)


# ============================================================== stateful
NAMES = ["a", "b", "c", "d"]
CHILD_LEVEL = {"block": "surface", "object": "block", "scene": "object"}
# relation names that a generated name may later want, and one invalid name
CUSTOM = ["ts1", "ts3", "ts4", "tb2", "tb3", "to2", "to3", "bad name"]
SCALES = [0.5, 1.0, 2.0, 3.0]  # exactly 1 or far from it: rigid or clearly not
BAD_NAMES = ["", "1a", "a b"]


def _rand_affine(data, rigid: bool) -> np.ndarray:
    q = np.array(data.draw(st.tuples(*[st.floats(-1, 1)] * 4)))
    if np.linalg.norm(q) < 1e-3:
        q = np.array([0.0, 0.0, 0.0, 1.0])
    T = np.eye(4)
    T[:3, :3] = Rotation.from_quat(q / np.linalg.norm(q)).as_matrix()
    T[:3, 3] = data.draw(st.tuples(*[st.floats(-5, 5)] * 3))
    if not rigid:
        T[:3, :3] = T[:3, :3] @ np.diag(data.draw(st.tuples(*[st.sampled_from(SCALES)] * 3)))
    return T


class ModelMachine(RuleBasedStateMachine):
    """Random valid and invalid operations against a shadow model kept by hand."""

    def __init__(self):
        super().__init__()
        self.m = Model()
        # shadow: level -> name -> {"rels": [[name, (level, target), T]], "boolean": op}
        self.sh: dict[str, dict[str, dict]] = {lv: {} for lv in LEVELS}

    # ---------------------------------------------------------------- shadow helpers
    def _all(self):
        return [(lv, n) for lv in LEVELS for n in self.sh[lv]]

    def _pb(self, key):
        return sum(
            1 for lv in LEVELS[1:] for e in self.sh[lv].values() for r in e["rels"] if r[1] == key
        )

    def _made_of(self, key):
        seen, stack = set(), [key]
        while stack:
            lv, n = stack.pop()
            for r in self.sh[lv][n]["rels"]:
                if r[1] not in seen:
                    seen.add(r[1])
                    stack.append(r[1])
        return seen

    def _future_names(self, owner):
        """Names that attach would generate next for ``owner``: custom names that may clash."""
        if owner[0] == "surface":
            return []
        prefix = {"block": "ts", "object": "tb", "scene": "to"}[owner[0]]
        used = [
            int(r[0][len(prefix) :])
            for r in self.sh[owner[0]][owner[1]]["rels"]
            if re.fullmatch(prefix + r"\d+", r[0])
        ]
        top = max(used, default=0)
        return [f"{prefix}{top + 1}", f"{prefix}{top + 2}"]

    def _check(self, ok: bool, fn):
        """Run fn; it must succeed when ok, else raise a WorkcellError and change nothing."""
        if ok:
            return fn()
        before = snapshot(self.m)
        with pytest.raises(WorkcellError):
            fn()
        assert snapshot(self.m) == before
        return None

    @initialize()
    def base(self):
        """A small model to start from: two surfaces, two blocks, an object and a scene."""
        m, sh = self.m, self.sh
        for n, k in (("a", 4), ("b", 3)):
            m.create("surface", n, Surface.regular_polygon(k, 1.0))
            sh["surface"][n] = {"rels": [], "boolean": None}
        for lv in ("block", "object", "scene"):
            for n in ("a", "b") if lv == "block" else ("a",):
                m.create(lv, n)
                sh[lv][n] = {"rels": [], "boolean": None}
        for owner, target in (
            (("block", "a"), ("surface", "a")),
            (("block", "a"), ("surface", "b")),
            (("block", "b"), ("surface", "a")),
            (("object", "a"), ("block", "a")),
            (("scene", "a"), ("object", "a")),
        ):
            T = spatial.translation(1, 2, 3)
            name = m.attach(owner, target, T)
            sh[owner[0]][owner[1]]["rels"].append([name, target, T])

    # ---------------------------------------------------------------- rules
    @rule(data=st.data(), level=st.sampled_from(LEVELS))
    def create(self, data, level):
        name = data.draw(st.sampled_from(NAMES + BAD_NAMES))
        ok = name not in BAD_NAMES and name not in self.sh[level]
        surf = (
            Surface.regular_polygon(data.draw(st.integers(3, 6)), 1.0)
            if level == "surface"
            else None
        )
        if self._check(ok, lambda: self.m.create(level, name, surf)) is not None:
            self.sh[level][name] = {"rels": [], "boolean": None}

    @rule(data=st.data())
    def create_boolean(self, data):
        blocks = list(self.sh["block"])
        if len(blocks) < 2:
            return
        ops = data.draw(st.lists(st.sampled_from(blocks), min_size=2, max_size=3))
        if data.draw(st.integers(0, 3)) == 0:
            ops = ops[:1]  # too few operands
        name = data.draw(st.sampled_from(NAMES))
        ok = len(ops) >= 2 and name not in self.sh["block"]
        refs = [("block", o) for o in ops]
        if self._check(ok, lambda: self.m.create_boolean(name, "union", refs)) is not None:
            self.sh["block"][name] = {
                "rels": [[f"op{i + 1}", ("block", o), np.eye(4)] for i, o in enumerate(ops)],
                "boolean": "union",
            }

    @rule(data=st.data())
    def attach(self, data):
        ents = self._all()
        if not ents:
            return
        owners = [k for k in ents if k[0] != "surface"]
        owner = data.draw(st.sampled_from(owners if owners and data.draw(st.booleans()) else ents))
        olv = owner[0]
        want = None
        if olv != "surface":
            boolean = self.sh[olv][owner[1]]["boolean"]
            want = "block" if boolean else CHILD_LEVEL[olv]
        fitting = [k for k in ents if k[0] == want]
        if fitting and data.draw(st.integers(0, 3)) > 0:
            target = data.draw(st.sampled_from(fitting))
        else:
            target = data.draw(st.sampled_from(ents))
        rigid = olv == "scene"
        kind = data.draw(st.sampled_from(["good", "good", "good", "singular", "scale", "nan"]))
        T = _rand_affine(data, rigid=rigid)
        if kind == "singular":
            T[:3, 0] = 0.0
        elif kind == "scale":
            T = T @ spatial.scaling(1.5, 1, 1)
        elif kind == "nan":
            T[0, 3] = np.nan
        custom = data.draw(
            st.sampled_from([None, None, None, "r1", *CUSTOM, *self._future_names(owner)])
        )
        ok = olv != "surface"
        if ok:
            e = self.sh[olv][owner[1]]
            ok = target[0] == want
            ok = ok and not (target == owner or owner in self._made_of(target))
            ok = ok and kind in ("good", "scale" if not rigid else "good")
            ok = ok and custom != "bad name"
            ok = ok and (custom is None or custom not in [r[0] for r in e["rels"]])
        got = self._check(ok, lambda: self.m.attach(owner, target, T, name=custom))
        if got is not None:
            rels = self.sh[olv][owner[1]]["rels"]
            assert got not in [r[0] for r in rels]
            if custom is None:
                prefix = "ts" if olv == "block" else ("tb" if olv == "object" else "to")
                assert re.fullmatch(prefix + r"\d+", got)
            else:
                assert got == custom
            rels.append([got, target, T])

    @rule(data=st.data())
    def detach(self, data):
        owners = [k for k in self._all() if k[0] != "surface"]
        if not owners:
            return
        owner = data.draw(st.sampled_from(owners))
        e = self.sh[owner[0]][owner[1]]
        names = [r[0] for r in e["rels"]]
        rel = data.draw(st.sampled_from([*names, "nope"]))
        ok = rel in names and not (e["boolean"] and len(names) <= 2)
        self._check(ok, lambda: self.m.detach(owner, rel))
        if ok:
            e["rels"] = [r for r in e["rels"] if r[0] != rel]

    @rule(data=st.data(), recursive=st.booleans())
    def remove(self, data, recursive):
        ents = self._all()
        if not ents:
            return
        key = data.draw(st.sampled_from(ents))
        ok = self._pb(key) == 0
        doomed = {key}
        if recursive:
            changed = True
            while changed:
                changed = False
                for cand in self._made_of(key) - doomed:
                    users = [
                        (lv, n)
                        for lv in LEVELS[1:]
                        for n, e in self.sh[lv].items()
                        for r in e["rels"]
                        if r[1] == cand
                    ]
                    if all(u in doomed for u in users):
                        doomed.add(cand)
                        changed = True
        got = self._check(ok, lambda: self.m.remove(key, recursive=recursive))
        if ok:
            assert sorted(got) == sorted(n for _, n in doomed)
            for lv, n in doomed:
                del self.sh[lv][n]

    @rule(data=st.data())
    def rename(self, data):
        ents = self._all()
        if not ents:
            return
        key = data.draw(st.sampled_from(ents))
        new = data.draw(st.sampled_from([*NAMES, "e", "f", *BAD_NAMES]))
        ok = new not in BAD_NAMES and new not in self.sh[key[0]]
        if ok:
            self.m.rename(key, new)
            lv, old = key
            self.sh[lv] = {(new if n == old else n): e for n, e in self.sh[lv].items()}
            for lv2 in LEVELS[1:]:
                for e in self.sh[lv2].values():
                    for r in e["rels"]:
                        if r[1] == key:
                            r[1] = (lv, new)
        else:
            self._check(False, lambda: self.m.rename(key, new))

    @rule(data=st.data())
    def rename_relation(self, data):
        owners = [k for k in self._all() if k[0] != "surface" and self.sh[k[0]][k[1]]["rels"]]
        if not owners:
            return
        owner = data.draw(st.sampled_from(owners))
        rels = self.sh[owner[0]][owner[1]]["rels"]
        names = [r[0] for r in rels]
        old = data.draw(st.sampled_from([*names, "zz"]))
        new = data.draw(st.sampled_from(["x", *CUSTOM, *self._future_names(owner)]))
        ok = old in names and new not in names and new != "bad name"
        self._check(ok, lambda: self.m.rename_relation(owner, old, new))
        if ok:
            for r in rels:
                if r[0] == old:
                    r[0] = new

    @rule(data=st.data())
    def set_transform(self, data):
        owners = [k for k in self._all() if k[0] != "surface" and self.sh[k[0]][k[1]]["rels"]]
        if not owners:
            return
        owner = data.draw(st.sampled_from(owners))
        rels = self.sh[owner[0]][owner[1]]["rels"]
        i = data.draw(st.integers(0, len(rels) - 1))
        rigid = owner[0] == "scene"
        T = _rand_affine(data, rigid=rigid and data.draw(st.booleans()))
        is_rigid = np.array_equal(np.linalg.norm(T[:3, :3], axis=0), np.ones(3)) or np.allclose(
            T[:3, :3].T @ T[:3, :3], np.eye(3), rtol=0, atol=1e-12
        )
        ok = not rigid or is_rigid
        self._check(ok, lambda: self.m.set_transform(owner, rels[i][0], T))
        if ok:
            rels[i][2] = T

    @rule(data=st.data())
    def set_colour(self, data):
        ents = self._all()
        if not ents:
            return
        key = data.draw(st.sampled_from(ents))
        colour = data.draw(
            st.sampled_from([(1, 0, 0), (0.2, 0.3, 0.4, 0.5), None, (2, 0, 0), (1,)])
        )
        ok = colour is None or (len(colour) in (3, 4) and max(colour) <= 1)
        self._check(ok, lambda: self.m.set_colour(key, colour))

    @rule(data=st.data())
    def copy(self, data):
        ents = self._all()
        if not ents:
            return
        key = data.draw(st.sampled_from(ents))
        new = data.draw(st.sampled_from([*NAMES, "e", BAD_NAMES[1]]))
        lv = key[0]
        mode = data.draw(st.sampled_from(["none", "rigid", "affine"]))
        if lv == "surface":
            T = None if mode == "none" else spatial.srt(scale=(2, 0.5, 1), rotation=(0, 0, 1.0))
            if mode == "affine":
                T = spatial.rot_x(0.5)  # out of plane
        else:
            T = None if mode == "none" else _rand_affine(data, rigid=mode == "rigid")
        ok = new not in self.sh[lv] and new != BAD_NAMES[1]
        ok = ok and not (lv == "surface" and mode == "affine")
        # an "affine" draw with unit scales is rigid, and a scene accepts it
        ok = ok and not (lv == "scene" and mode == "affine" and not spatial.is_rigid(T))
        if self._check(ok, lambda: self.m.copy(key, new, T)) is not None:
            src = self.sh[lv][key[1]]
            self.sh[lv][new] = {
                "rels": [[n, t, (M if T is None else T @ M)] for n, t, M in src["rels"]],
                "boolean": src["boolean"],
            }

    @rule(data=st.data())
    def copy_then_attach(self, data):
        """Copy an owner, then let attach generate names on the copy (they must stay unique)."""
        owners = [k for k in self._all() if k[0] != "surface" and self.sh[k[0]][k[1]]["rels"]]
        if not owners:
            return
        key = data.draw(st.sampled_from(owners))
        free = [n for n in ("e", "f", "g") if n not in self.sh[key[0]]]
        if not free:
            return
        new = free[0]
        self.m.copy(key, new)
        src = self.sh[key[0]][key[1]]
        self.sh[key[0]][new] = {
            "rels": [[n, t, M] for n, t, M in src["rels"]],
            "boolean": src["boolean"],
        }
        target = src["rels"][0][1]
        for _ in range(data.draw(st.integers(1, 3))):
            got = self.m.attach((key[0], new), target)
            rels = self.sh[key[0]][new]["rels"]
            assert got not in [r[0] for r in rels]
            rels.append([got, target, np.eye(4)])

    # ---------------------------------------------------------------- invariants
    @invariant()
    def matches_shadow(self):
        assert self.m.list() == {lv: list(self.sh[lv]) for lv in LEVELS}
        for lv in LEVELS[1:]:
            for n, e in self.sh[lv].items():
                rels = self.m.relations((lv, n))
                assert [(r.name, (r.target_level, r.target)) for r in rels] == [
                    (r[0], r[1]) for r in e["rels"]
                ]
                for r, s in zip(rels, e["rels"], strict=True):
                    assert np.allclose(r.transform, s[2], rtol=1e-12, atol=1e-12)
                names = [r.name for r in rels]
                assert len(set(names)) == len(names)

    @invariant()
    def pointed_by_is_exact(self):
        independent = independent_pointed_by(self.m)
        for key in self._all():
            assert self.m.pointed_by(key) == independent[key] == self._pb(key)


TestModelMachine = ModelMachine.TestCase
TestModelMachine.settings = settings(
    max_examples=50,
    stateful_step_count=40,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)


def test_attach_groups_equals_attach_many_calls_and_is_atomic():
    from workcell import Model, Surface, spatial

    def fresh():
        m = Model()
        m.create("surface", "a", Surface.rectangle(1, 1))
        m.create("surface", "b", Surface.rectangle(2, 1))
        m.create("block", "blk")
        return m

    Ta = np.stack([spatial.translation(i, 0, 0) for i in range(3)])
    Tb = spatial.rot_x(0.5)
    one, two = fresh(), fresh()
    names = one.attach_groups("blk", [("a", Ta), ("b", Tb), ("a", Ta[:1])])
    expected = two.attach_many("blk", "a", Ta) + two.attach_many("blk", "b", [Tb])
    expected += two.attach_many("blk", "a", Ta[:1])
    assert names == expected == ["ts1", "ts2", "ts3", "ts4", "ts5"]
    assert one.to_dict() == two.to_dict()
    assert one.pointed_by("a") == 4
    assert one.pointed_by("b") == 1
    before = one.to_dict()
    singular = np.diag([1.0, 1.0, 0.0, 1.0])
    for bad in ([("a", Ta), ("nope", Tb)], [("a", Ta), ("b", singular)], [("a", np.ones(5))]):
        with pytest.raises(WorkcellError):
            one.attach_groups("blk", bad)
        assert one.to_dict() == before
        assert one.pointed_by("a") == 4


def test_generated_names_spelled_out_on_demand():
    from workcell import Model, Surface, spatial

    m = Model()
    m.create("surface", "a", Surface.rectangle(1, 1))
    m.create("block", "blk")
    Ts = np.stack([spatial.translation(i, 0, 0) for i in range(4)])
    assert m.attach_groups("blk", [("a", Ts)], return_names=False) is None
    assert m.attach_groups("blk", [("a", Ts[:2])], return_names=False) is None
    assert [r.name for r in m.relations("blk")] == [f"ts{i}" for i in range(1, 7)]
    np.testing.assert_array_equal(m.relation("blk", "ts6").transform, Ts[1])
    m.detach("blk", "ts3")
    assert m.attach("blk", "a") == "ts7"
    assert [r.name for r in m.relations("blk")] == ["ts1", "ts2", "ts4", "ts5", "ts6", "ts7"]
    assert m.pointed_by("a") == 6
