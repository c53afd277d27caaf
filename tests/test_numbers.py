"""Issue 14, item 8: numbers at the boundary.

Coordinates near 1e154 overflowed to a raw OverflowError (the shell died; the server
answered InternalError); huge transforms gave a volume of 0, NaN or inf silently; a
boolean of two equal blocks made an empty part that crashed the compiler; strings and
bools passed as numbers or flags. Each is now refused where it enters, with a
WorkcellError, and changes nothing."""

from __future__ import annotations

import io

import numpy as np
import pytest

from workcell import LimitError, Model, Surface, Workcell, limits, solids, spatial
from workcell.cell import compile_cell
from workcell.client import Client
from workcell.errors import GeometryError, ModelError, WorkcellError
from workcell.program import Session
from workcell.program.server import Server
from workcell.program.shell import run_shell

MAX = limits.DEFAULTS.max_coordinate


@pytest.mark.parametrize("x", [1e154, 1e155, 1e300, 1.0000001e6])
def test_coordinates_beyond_the_maximum_are_refused(x):
    m = Model()
    solids.cube(m, "x", size=1.0)
    m.create("object", "o")
    before = m.to_dict()
    for make in (
        lambda: Surface.from_points([(0, 0), (x, 0), (0, x)]),
        lambda: solids.box(m, "b", size=(x, 1, 1)),
        lambda: solids.cylinder(m, "c", radius=x, height=1.0),
        lambda: solids.sphere(m, "s", radius=x),
        lambda: solids.extrude(m, "e", [(0, 0), (1, 0), (0, 1)], height=x),
        lambda: m.attach("o", "x", spatial.translation(x, 0, 0)),
        lambda: Workcell("w").add_camera("cam", (x, 0, 0), (0, 0, 0)),
    ):
        with pytest.raises(LimitError, match="max_coordinate = 1,000,000 m"):
            make()
    assert m.to_dict() == before


def test_coordinates_up_to_the_maximum_work():
    m = Model()
    solids.box(m, "b", size=(MAX, 1.0, 1.0))
    assert m.properties("b").volume == pytest.approx(MAX)


def test_the_shell_reports_an_overflowing_coordinate_and_goes_on():
    out, err = io.StringIO(), io.StringIO()
    lines = "create surface s points (0,0) (1e155,0) (0,1e155)\ncreate cube c size 2\nlist\n"
    code = run_shell(Session(), stdin=io.StringIO(lines), stdout=out, stderr=err, interactive=False)
    assert "LimitError" in err.getvalue()
    assert "max_coordinate" in err.getvalue()
    assert "OverflowError" not in err.getvalue()
    assert "c" in out.getvalue()  # the next lines ran
    assert code != 0


def test_the_server_answers_an_overflowing_coordinate_with_a_limit_error(tmp_path):
    srv = Server(port=0, root=tmp_path)
    srv.serve_in_thread()
    try:
        with Client(port=srv.port, timeout=30) as c:
            with pytest.raises(LimitError):  # InternalError before
                c.call("create_surface", name="s", points=[[0, 0], [1e155, 0], [0, 1e155]])
            assert c.call("list", "surface") == []
    finally:
        srv.stop()


@pytest.mark.parametrize(
    "T",
    [
        spatial.translation(0, 0, 1e200),  # volume NaN before
        np.diag([1e120, 1e120, 1e120, 1.0]),  # volume inf before
        np.diag([1e-5, 1e-5, 1e-5, 1.0]),  # volume 1e-15: refused as singular
    ],
    ids=["translation 1e200", "scale 1e120", "scale 1e-5"],
)
def test_huge_or_tiny_transforms_are_refused_not_silently_wrong(T):
    m = Model()
    solids.cube(m, "c", size=1.0)
    m.create("object", "o")
    with pytest.raises(WorkcellError, match=r"max_coordinate|singular"):
        m.attach("o", "c", T)
    assert m.relations("o") == []


def test_copies_cannot_grow_past_the_maximum():
    m = Model()
    solids.cube(m, "c", size=1.0)
    m.create("object", "o")
    m.attach("o", "c", spatial.scaling(1e4, 1e4, 1e4))
    m.copy("o", "o2", spatial.scaling(10, 10, 10))  # 1e5: fine
    with pytest.raises(LimitError, match="max_coordinate"):
        m.copy("o", "o3", spatial.scaling(1e3, 1e3, 1e3))  # 1e7 per entry
    assert not m.exists("o3")
    v = m.properties("o2").volume
    assert v == pytest.approx(1e15)
    assert np.isfinite(v)


def test_an_empty_boolean_is_refused_and_never_reaches_the_compiler():
    cell = Workcell("w")
    solids.cube(cell.model, "a", size=0.1)
    solids.cube(cell.model, "b", size=0.1)
    with pytest.raises(GeometryError, match="is empty"):
        solids.difference(cell.model, "d", "a", "b")  # two equal blocks
    cell.model.create_boolean("d", "difference", ["a", "b"])  # the lazy datamodel
    with pytest.raises(GeometryError, match="empty"):
        cell.add_static("p", "d")
    with pytest.raises(GeometryError, match="volume"):
        cell.add_movable("q", "d", density=1000.0)
    # a part made empty after it was added: the compiler says so (ValueError before)
    cell.model.create_boolean("e", "difference", ["a", "b"], [None, spatial.translation(1, 0, 0)])
    cell.add_static("p", "e")
    cell.model.set_transform("e", "op2", np.eye(4))
    with pytest.raises(GeometryError, match=r"part 'p'.*is empty"):
        compile_cell(cell)


@pytest.mark.parametrize(
    "call",
    [
        lambda m: m.set_movable("c", "yes"),
        lambda m: m.set_movable("c", 1),
        lambda m: m.create("block", "x", movable="no"),
        lambda m: solids.cylinder(m, "y", radius="1", height=1.0),
        lambda m: solids.cylinder(m, "y", radius=True, height=1.0),
        lambda m: solids.sphere(m, "y", radius="1"),
        lambda m: solids.box(m, "y", size=("1", 1, 1)),
        lambda m: solids.box(m, "y", size=(True, 1, 1)),
        lambda m: solids.cube(m, "y", size=True),
        lambda m: Surface.circle("1"),
        lambda m: Surface.circle(True),
        lambda m: Surface.circle(1.0, n=4.5),
        lambda m: Surface.rectangle("1", 1),
        lambda m: Surface([("0", "0"), ("1", "0"), ("0", "1")]),
        lambda m: m.attach("o", "c", [["1", "0", "0", "0"]] * 3 + [["0", "0", "0", "1"]]),
        lambda m: solids.revolve(m, "y", [(1, 0), (2, 0), (2, 1)], angle="3"),
        lambda m: Workcell("w").add_camera("cam", ("1", 0, 0), (0, 0, 0)),
    ],
)
def test_strict_types_strings_and_bools_are_not_numbers_or_flags(call):
    m = Model()
    solids.cube(m, "c", size=1.0)
    m.create("object", "o")
    before = m.to_dict()
    with pytest.raises((ModelError, GeometryError)):
        call(m)
    assert m.to_dict() == before
    assert m.info("c").movable is False
