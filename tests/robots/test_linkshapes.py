"""Collision geometry of imported robot links (robots.linkshapes over decompose's
decompositions): the hull where it fits (checked against the analytic deviation of an
L-shaped prism), CoACD's pieces elsewhere, a time bound per link whose outcome is cached
with the bound, errors naming the link, progress output, and Ctrl-C."""

from __future__ import annotations

import math
import os
import warnings

import numpy as np
import pytest
import trimesh
from robot_files import arm_urdf, l_shape, write, write_meshes
from shapely.geometry import Polygon
from test_native import children_of, ctrl_c_after, torus

from workcell import decompose as dec
from workcell import limits
from workcell.errors import NativeCrashError
from workcell.robots import from_urdf
from workcell.robots.linkshapes import LINK_CONCAVITY, LINK_HULL_FIT, LINK_OPTIONS, LinkBatch

# the L's hull adds the triangle (0.2, 0.1), (0.1, 0.2), (0.1, 0.1): 0.005 of the L's 0.03
# m^2 cross-section, and its hypotenuse's middle lies 0.05 m from the L
L_EXTRA = 0.005 / 0.03
L_FAR = 0.05 / math.sqrt(0.2**2 + 0.2**2 + 0.05**2)


def notched_box() -> trimesh.Trimesh:
    """A 200 x 100 x 100 mm box with a 4 x 4 mm groove along one edge: not convex, but its
    hull strays 2.8 mm (1.2 % of its diagonal) and adds 0.08 % volume."""
    outline = Polygon([(0, 0), (0.2, 0), (0.2, 0.096), (0.196, 0.096), (0.196, 0.1), (0, 0.1)])
    return trimesh.creation.extrude_polygon(outline, 0.1)


def test_hull_deviation_of_an_l_is_its_analytic_value():
    far, extra = dec.hull_deviation(l_shape())
    assert far == pytest.approx(L_FAR, abs=0.002)  # points on the hull: they may miss a bit
    assert extra == pytest.approx(L_EXTRA, rel=1e-9)
    far, extra = dec.hull_deviation(trimesh.creation.box(extents=(0.3, 0.2, 0.1)))
    assert far <= 1e-3
    assert extra == pytest.approx(0.0, abs=1e-12)
    open_l = l_shape()
    open_l.update_faces(np.arange(len(open_l.faces)) != 0)  # one facet off: not closed
    assert dec.hull_deviation(open_l)[1] is None


def test_a_mesh_close_to_its_hull_is_its_hull_and_an_l_is_decomposed(monkeypatch):
    box, ell = notched_box(), l_shape()
    got = dec.decompositions(
        [box, ell], LINK_CONCAVITY, options=LINK_OPTIONS, hull_fit=LINK_HULL_FIT, seconds=60
    )
    assert [d.method for d in got] == ["hull", "coacd"]
    assert got[0].pieces[0].volume == pytest.approx(box.convex_hull.volume, rel=1e-12)
    assert len(got[1].pieces) >= 2  # the L's notch stays open
    assert sum(p.volume for p in got[1].pieces) == pytest.approx(ell.volume, rel=0.1)
    assert all(d.seconds > 0 for d in got)

    def no_child(*args, **kwargs):
        raise AssertionError("a child ran although both are cached")

    monkeypatch.setattr("workcell.native.run", no_child)
    again = dec.decompositions(
        [box, ell], LINK_CONCAVITY, options=LINK_OPTIONS, hull_fit=LINK_HULL_FIT, seconds=60
    )
    assert [(d.method, d.seconds, len(d.pieces)) for d in again] == [
        ("hull", 0.0, 1),
        ("coacd", 0.0, len(got[1].pieces)),
    ]
    # the options and the hull test are part of the key; the defaults' key is unchanged
    keys = {
        dec.cache_key(ell, 0.1),
        dec.cache_key(ell, 0.1, LINK_OPTIONS),
        dec.cache_key(ell, 0.1, {**LINK_OPTIONS, "resolution": 400}),
        dec.cache_key(ell, 0.1, LINK_OPTIONS, LINK_HULL_FIT),
        dec.cache_key(ell, 0.1, LINK_OPTIONS, dec.HullFit(0.05, 0.2)),
    }
    assert len(keys) == 5
    assert dec.cache_key(ell, 0.1) == dec.cache_key(ell, 0.1, {}, None)


def test_unknown_coacd_options_are_refused():
    with pytest.raises(dec.GeometryError, match=r"unknown CoACD option\(s\) \['thresh'\]"):
        dec.decompositions([l_shape()], options={"thresh": 0.2})
    with pytest.raises(dec.GeometryError, match="must be a finite number"):
        dec.decompositions([l_shape()], options={"resolution": float("nan")})


def test_a_mesh_over_its_time_is_its_hull_and_that_is_remembered_with_the_bound(
    monkeypatch, tmp_path
):
    monkeypatch.setenv(dec.CACHE_ENV, str(tmp_path))  # fake pieces below: kept to this test
    ring = torus()
    [d] = dec.decompositions([ring], seconds=1.0)
    assert d.method == "timeout"
    assert d.pieces[0].volume == pytest.approx(ring.convex_hull.volume, rel=1e-9)
    assert children_of(os.getpid()) == []
    calls = []

    def fake(jobs, **kwargs):
        calls.append(len(jobs))
        return [("coacd", [(ring.convex_hull.vertices, ring.convex_hull.faces)])]

    monkeypatch.setattr("workcell.native.run", fake)
    assert dec.decompositions([ring], seconds=1.0)[0].method == "timeout"  # cached
    assert dec.decompositions([ring], seconds=0.5)[0].method == "timeout"  # less time: same
    assert calls == []
    assert dec.decompositions([ring], seconds=2.0)[0].method == "coacd"  # more time: again
    assert calls == [1]


def test_a_link_over_its_time_warns_and_collides_as_its_hull(tmp_path, capsys):
    ring = torus()
    ring.export(tmp_path / "ring.stl")
    write_meshes(tmp_path)
    text = arm_urdf().replace('<sphere radius="0.05"/>', '<mesh filename="ring.stl"/>')
    f = write(tmp_path, "arm.urdf", text)
    with pytest.warns(UserWarning, match=r"link 'link2' \(line \d+\) collision 1: .*over 1 s"):
        robot = from_urdf(f, link_seconds=1.0)
    col = next(g for g in robot.geometry if g.link == 2 and g.collides)
    hull = max(col.collision, key=lambda p: p.volume)
    assert hull.volume == pytest.approx(ring.convex_hull.volume, rel=1e-6)
    err = capsys.readouterr().err  # piped: one summary line
    assert err.count("\n") == 1
    assert "collision geometry of 1 non-convex link mesh(es)" in err
    assert "1 left as hulls" in err
    with pytest.warns(UserWarning, match="over 1 s"):  # the same from the cache, silently
        from_urdf(f, link_seconds=1.0)
    assert capsys.readouterr().err == ""


def test_a_native_crash_is_a_model_error_naming_the_file_and_the_link(tmp_path):
    torus(200_000).export(tmp_path / "ring.stl")  # CoACD runs out of 400 MiB on it
    write_meshes(tmp_path)
    text = arm_urdf().replace('<sphere radius="0.05"/>', '<mesh filename="ring.stl"/>')
    f = write(tmp_path, "arm.urdf", text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with (
            limits.using(max_native_bytes=400 << 20, max_native_seconds=60),
            pytest.raises(
                NativeCrashError, match=r"arm\.urdf': link 'link2' \(line \d+\) collision 1"
            ),
        ):
            from_urdf(f)
    assert children_of(os.getpid()) == []


def test_ctrl_c_stops_an_import_at_once(tmp_path):
    torus(80_000).export(tmp_path / "ring.stl")
    write_meshes(tmp_path)
    text = arm_urdf().replace('<sphere radius="0.05"/>', '<mesh filename="ring.stl"/>')
    f = write(tmp_path, "arm.urdf", text)

    with ctrl_c_after(2.0), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from_urdf(f)


def test_a_terminal_shows_a_progress_bar(monkeypatch, capsys):
    monkeypatch.setattr("sys.stderr.isatty", lambda: True)
    batch = LinkBatch("test file", "arm")
    batch.add(notched_box().apply_scale(1.01), "link 'a' collision 1")  # not cached yet
    [pieces] = batch.run()
    assert len(pieces) == 1
    err = capsys.readouterr().err
    assert "arm: link collision geometry" in err  # tqdm's bar, with its time estimate
    assert "1/1" in err


def test_the_same_mesh_twice_in_a_batch_is_decomposed_once(monkeypatch, tmp_path):
    monkeypatch.setenv(dec.CACHE_ENV, str(tmp_path))
    finger = l_shape()
    runs = []

    def fake(jobs, **kwargs):
        runs.append(len(jobs))
        return [("coacd", [(p.vertices, p.faces) for p in (finger.convex_hull,)])] * len(jobs)

    monkeypatch.setattr("workcell.native.run", fake)
    left, right, other = dec.decompositions([finger, finger.copy(), notched_box()], seconds=10)
    assert runs == [2]  # the left and the right finger are one mesh
    assert left.pieces is right.pieces
    assert other.method == "coacd"
