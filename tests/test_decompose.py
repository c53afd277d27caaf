"""Convex decomposition (CoACD) and its on-disk cache."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.spatial import Delaunay

from workcell import Model, solids, spatial
from workcell import decompose as dec
from workcell.errors import GeometryError
from workcell.meshgeoms import collision_pieces, is_convex


def bin_model() -> Model:
    """A 200 x 150 x 100 mm bin with 10 mm walls and floor (a difference of two boxes)."""
    m = Model()
    solids.box(m, "outer", size=(0.2, 0.15, 0.1))
    solids.box(m, "inner", size=(0.18, 0.13, 0.1))
    solids.difference(
        m, "bin", "outer", "inner", transforms=[None, spatial.translation(0.01, 0.01, 0.01)]
    )
    return m


def inside(pieces: list[trimesh.Trimesh], points: np.ndarray) -> np.ndarray:
    """Which points lie in some piece (each piece is convex: a Delaunay test is exact)."""
    hit = np.zeros(len(points), dtype=bool)
    for p in pieces:
        hit |= Delaunay(p.vertices).find_simplex(points) >= 0
    return hit


def test_cache_dir_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.setenv(dec.CACHE_ENV, str(tmp_path / "c"))
    assert dec.cache_dir() == tmp_path / "c"
    monkeypatch.delenv(dec.CACHE_ENV)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path))
    assert dec.cache_dir() == tmp_path / ".cache" / "workcell" / "coacd"
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "x"))
    assert dec.cache_dir() == tmp_path / "x" / "workcell" / "coacd"


def test_bin_pieces_follow_the_surface_and_leave_the_cavity_open():
    m = bin_model()
    mesh = m.world_mesh(("block", "bin"))
    c = collision_pieces(m, "bin")
    assert c.method == "coacd"
    assert len(c.pieces) >= 5
    assert all(is_convex(p) for p in c.pieces)
    total = sum(p.volume for p in c.pieces)
    assert (
        mesh.volume * (1 - 1e-6) <= total <= 1.01 * mesh.volume
    )  # exact: 0.2*0.15*0.1 - 0.18*0.13*0.09
    assert mesh.volume == pytest.approx(0.2 * 0.15 * 0.1 - 0.18 * 0.13 * 0.09, rel=1e-12)
    rng = np.random.default_rng(0)
    cavity = rng.uniform([0.0105, 0.0105, 0.0105], [0.1895, 0.1395, 0.0995], size=(2000, 3))
    wall = rng.uniform([0.0005, 0.0005, 0.0005], [0.0095, 0.1495, 0.0995], size=(500, 3))
    assert not inside(c.pieces, cavity).any()  # nothing fills the bin
    assert inside(c.pieces, wall).all()  # every bit of the wall is covered
    assert inside([mesh.convex_hull], cavity).all()  # (the hull, MuJoCo's default, fills it)
    # no piece sticks out of the bin by more than 50 um (trimesh: positive inside)
    corners = np.vstack([p.vertices for p in c.pieces])
    assert -trimesh.proximity.signed_distance(mesh, corners).min() < 5e-5


def test_decomposition_is_cached_by_mesh(monkeypatch):
    mesh = bin_model().world_mesh(("block", "bin"))
    first = dec.decompose(mesh, 0.05)  # decomposed here, or by an earlier test
    assert (dec.cache_dir() / f"{dec.cache_key(mesh, 0.05)}.npz").is_file()

    def no_coacd(*args, **kwargs):
        raise AssertionError("CoACD ran although the pieces are cached")

    monkeypatch.setattr("workcell.native.run", no_coacd)
    again = dec.decompose(mesh, 0.05)
    assert len(again) == len(first)
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a.vertices, b.vertices)
    # another bound is another entry; a moved mesh is another mesh
    assert dec.cache_key(mesh, 0.02) != dec.cache_key(mesh, 0.05)
    moved = mesh.copy().apply_translation([1e-6, 0, 0])
    assert dec.cache_key(moved, 0.05) != dec.cache_key(mesh, 0.05)


def test_unwritable_cache_warns_and_still_decomposes(monkeypatch, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv(dec.CACHE_ENV, str(blocker / "sub"))
    pieces = [trimesh.creation.box(extents=(1, 1, 1)), trimesh.creation.icosphere()]
    arrays = [(p.vertices, p.faces) for p in pieces]
    monkeypatch.setattr("workcell.native.run", lambda jobs, **kw: [arrays])  # not CoACD's part
    mesh = bin_model().world_mesh(("block", "bin"))
    with pytest.warns(UserWarning, match="cannot write the convex decomposition cache"):
        got = dec.decompose(mesh, 0.05)
    assert len(got) == 2
    for a, b in zip(got, pieces, strict=True):
        np.testing.assert_array_equal(a.vertices, b.vertices)


@pytest.mark.parametrize("bad", [0.0, -0.1, 1.5, float("nan"), "0.05"])
def test_bad_concavity_is_refused(bad):
    mesh = bin_model().world_mesh(("block", "bin"))
    with pytest.raises(GeometryError, match=r"concavity .* in \(0, 1\]"):
        dec.decompose(mesh, bad)
