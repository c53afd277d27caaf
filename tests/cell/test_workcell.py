"""Workcell: adding parts, robots and cameras; validation; JSON round trip."""

from __future__ import annotations

import json

import numpy as np
import pytest
from cell_helpers import two_puma_cell

from workcell import GeometryError, ModelError, WorkcellError
from workcell.cell import Workcell
from workcell.spatial import rot_x, translation


def test_json_round_trip_is_exact(tmp_path):
    cell = two_puma_cell()
    path = tmp_path / "cell.json"
    cell.save(path)
    back = Workcell.load(path)
    assert back.to_dict() == cell.to_dict()
    assert json.loads(path.read_text())["format"] == "workcell-cell"
    for name, r in cell.robots.items():
        b = back.robots[name]
        assert np.array_equal(b.q, r.q)
        assert np.array_equal(b.base, r.base)
        assert (b.robot.gripper is None) == (r.robot.gripper is None)
        assert np.array_equal(b.robot.tool, r.robot.tool)
    assert back.robots["puma_2"].robot.gripper.max_opening == 0.06
    for name, p in cell.movable_parts.items():
        assert back.mass(name) == p.density * cell.model.properties(p.entity).volume


def test_default_q_is_home_and_base_composes():
    cell = two_puma_cell()
    r = cell.robots["puma_1"]
    assert np.array_equal(r.q, r.robot.pose("home"))
    q = np.radians([5, 10, -70, 20, 30, 40])
    T = r.tool_pose(q)
    np.testing.assert_allclose(T, translation(0, 0, 0.4) @ r.robot.fk(q), atol=1e-15)


def test_grasp_data_of_a_movable_part():
    cell = two_puma_cell()
    lo, hi = cell.bounding_box("cube")
    np.testing.assert_allclose(lo, [0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(hi, [0.04, 0.04, 0.04], atol=1e-15)
    np.testing.assert_allclose(cell.centroid_frame("cube")[:3, 3], [0.02] * 3, atol=1e-15)
    assert cell.mass("cube") == pytest.approx(2700 * 0.04**3, rel=1e-12)
    # sphere: centroid at the origin by symmetry
    np.testing.assert_allclose(cell.centroid_frame("sphere")[:3, 3], 0, atol=1e-15)


def _state(cell):
    return json.dumps(cell.to_dict(), sort_keys=True)


@pytest.mark.parametrize(
    ("call", "error", "words"),
    [
        (lambda c: c.add_static("cube", "table"), ModelError, ["taken", "movable"]),
        (lambda c: c.add_robot("stage", "puma260"), ModelError, ["taken"]),
        (lambda c: c.add_static("a.b", "table"), ModelError, ["invalid", "no '.'"]),
        (lambda c: c.add_static("a/b", "table"), ModelError, ["invalid"]),
        (lambda c: c.add_camera("1cam", (1, 0, 0), (0, 0, 0)), ModelError, ["invalid"]),
        (
            lambda c: c.add_static("t3", "table", np.diag([2.0, 1, 1, 1])),
            GeometryError,
            ["t3", "not rigid"],
        ),
        (
            lambda c: c.add_movable(
                "m3", "ball", translation(0, 0, 1) @ rot_x(0.1) * 1.01, density=1
            ),
            GeometryError,
            ["m3"],
        ),
        (lambda c: c.add_movable("m3", "ball", density=-1.0), GeometryError, ["density"]),
        (lambda c: c.add_static("t3", "no_such_block"), ModelError, ["unknown entity", "table"]),
        (
            lambda c: c.add_robot("puma_3", "puma260", q=np.radians([0, 0, 0, 0, 130, 0])),
            ModelError,
            ["puma_3", "joint 5", "limits"],
        ),
        (lambda c: c.add_robot("puma_3", "puma999"), ModelError, ["puma260", "puma560"]),
        (
            lambda c: c.add_robot("puma_3", "puma260", gripper={"fingers": 3}),
            ModelError,
            ["fingers", "max_opening"],
        ),
        (lambda c: c.add_camera("cam", (1, 0, 0), (1, 0, 0)), GeometryError, ["cam", "differ"]),
        (lambda c: c.add_camera("cam", (1, 0, 0), (0, 0, 0), fovy=0), GeometryError, ["fovy"]),
    ],
)
def test_invalid_adds_raise_and_change_nothing(call, error, words):
    cell = two_puma_cell()
    before = _state(cell)
    with pytest.raises(error) as info:
        call(cell)
    for w in words:
        assert w in str(info.value), (w, str(info.value))
    assert _state(cell) == before


def test_damaged_files_name_the_place(tmp_path):
    cell = two_puma_cell()
    data = cell.to_dict()
    data["robots"][1]["q"] = [0, 0, 0, 0, 10, 0]
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(data))
    with pytest.raises(ModelError, match=r"robots\[1\] \('puma_2'\).*joint 5"):
        Workcell.load(p)
    del data["movable"][0]["density"]
    p.write_text(json.dumps(data))
    with pytest.raises(ModelError, match=r"movable\[0\] \('cube'\): missing field 'density'"):
        Workcell.load(p)
    p.write_text("{not json")
    with pytest.raises(ModelError, match="not valid JSON"):
        Workcell.load(p)
    p.write_text(json.dumps({"format": "workcell-cell", "version": 99}))
    with pytest.raises(ModelError, match="version"):
        Workcell.load(p)


def test_custom_robot_is_saved_inline(tmp_path):
    from workcell.robots import puma560

    cell = two_puma_cell()
    cell.add_robot("custom", puma560(geometry=False).with_(name="mine"), gripper=True)
    assert cell.robots["custom"].robot.gripper is not None
    cell.save(tmp_path / "c.json")  # its DH chain inline (workcell.cell.robot_json)
    back = Workcell.load(tmp_path / "c.json")
    assert back == cell
    q = np.radians([10, 20, -30, 40, 50, 60])
    assert np.array_equal(back.robots["custom"].robot.fk(q), cell.robots["custom"].robot.fk(q))


def test_errors_are_workcell_errors():
    assert issubclass(ModelError, WorkcellError)
    assert issubclass(GeometryError, WorkcellError)
