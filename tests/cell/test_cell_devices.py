"""Cell devices: signals, sensors, conveyors, sources, sinks; validation (a bad call changes
nothing), JSON round trip, what the compiled model holds (checked in MuJoCo's own model
and in dm_control)."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

from workcell import GeometryError, LimitError, ModelError, limits, solids
from workcell.cell import Workcell, compile_cell, export_cell
from workcell.cell.compile_devices import PARKED_ABOVE, belt_geom
from workcell.cell.devices import BELT_THICKNESS, STOP_HEIGHT, STOP_THICKNESS
from workcell.spatial import translation


def base_cell() -> Workcell:
    cell = Workcell("devices")
    solids.box(cell.model, "b", size=(0.06, 0.06, 0.05))
    cell.add_movable("box", "b", translation(0, 1, 0), density=300.0)
    cell.add_signal("go", True)
    cell.add_signal("count", 3)
    cell.add_signal("level", 0.5)
    return cell


def full_cell() -> Workcell:
    cell = base_cell()
    cell.add_sensor("beam", "beam", start=(1.0, -0.3, 0.55), end=(1.0, 0.3, 0.55))
    cell.add_sensor("here", "presence", center=(0.5, 0, 0.5), size=(0.2, 0.2, 0.2), robots=True)
    cell.add_sensor(
        "range", "proximity", origin=(0, 0, 2), direction=(0, 0, -2), range=3.0, threshold=1.0
    )
    cell.add_conveyor(
        "belt", start=(-1, 0, 0.5), end=(1.5, 0, 0.5), width=0.3, speed=0.25, run_signal="go"
    )
    cell.add_source("feeder", "box", at=(-0.9, -0.03, 0.5), every=4.0, count=3)
    cell.add_sink("out", center=(2, 0, 0.5), size=(0.3, 0.3, 0.3))
    return cell


def test_signals_keep_their_kind_and_sensors_make_bool_signals():
    cell = full_cell()
    assert [cell.signals[k].kind for k in ("go", "count", "level")] == ["bool", "int", "float"]
    assert cell.signal_kind("beam") == "bool"
    assert np.allclose(cell.sensors["range"].params["direction"], [0, 0, -1])
    assert cell.sources["feeder"].copies == ("box_1", "box_2", "box_3")
    assert cell.conveyors["belt"].length == pytest.approx(2.5)


def test_json_round_trip_keeps_every_device(tmp_path):
    cell = full_cell()
    path = tmp_path / "cell.json"
    cell.save(path)
    back = Workcell.load(path)
    assert back.to_dict() == cell.to_dict()
    data = json.loads(path.read_text())
    assert [s["initial"] for s in data["signals"]] == [True, 3, 0.5]
    assert type(back.signals["level"].initial) is float
    assert back.sources["feeder"].count == 3
    assert back.sinks["out"].size.tolist() == [0.3] * 3


def _state(cell: Workcell) -> str:
    return json.dumps(cell.to_dict(), sort_keys=True)


@pytest.mark.parametrize(
    ("call", "error", "words"),
    [
        (lambda c: c.add_signal("go", False), ModelError, "taken"),
        (lambda c: c.add_signal("x", "on"), ModelError, "bool, an int or a finite float"),
        (lambda c: c.add_signal("x", float("nan")), ModelError, "finite"),
        (lambda c: c.add_signal("bad name", 1), ModelError, "letter"),
        (
            lambda c: c.add_sensor("s", "laser", start=(0, 0, 0), end=(1, 0, 0)),
            ModelError,
            "kinds: beam",
        ),
        (lambda c: c.add_sensor("s", "beam", start=(0, 0, 0)), ModelError, "missing end"),
        (
            lambda c: c.add_sensor("s", "beam", start=(0, 0, 0), end=(0, 0, 0)),
            GeometryError,
            "apart",
        ),
        (
            lambda c: c.add_sensor("s", "presence", center=(0, 0, 0), size=(1, 0, 1)),
            GeometryError,
            "> 0",
        ),
        (
            lambda c: c.add_sensor(
                "s", "proximity", origin=(0, 0, 0), direction=(0, 0, 0), range=1, threshold=0.1
            ),
            GeometryError,
            "zero",
        ),
        (
            lambda c: c.add_sensor(
                "s", "proximity", origin=(0, 0, 0), direction=(0, 0, 1), range=1, threshold=2
            ),
            GeometryError,
            "beyond the range",
        ),
        (
            lambda c: c.add_sensor("s", "beam", start=(0, 0, 0), end=(1, 0, 0), robots="yes"),
            ModelError,
            "True or False",
        ),
        (
            lambda c: c.add_conveyor("c", start=(0, 0, 0.5), end=(1, 0, 0.6), width=0.3, speed=0.2),
            GeometryError,
            "one height",
        ),
        (
            lambda c: c.add_conveyor("c", start=(0, 0, 0.5), end=(1, 0, 0.5), width=0.3, speed=0),
            GeometryError,
            "speed",
        ),
        (
            lambda c: c.add_conveyor("c", start=(0, 0, 0.5), end=(1, 0, 0.5), width=-1, speed=1),
            GeometryError,
            "width",
        ),
        (
            lambda c: c.add_conveyor(
                "c", start=(0, 0, 0.5), end=(1, 0, 0.5), width=0.3, speed=1, run_signal="count"
            ),
            ModelError,
            "bool one",
        ),
        (
            lambda c: c.add_conveyor(
                "c", start=(0, 0, 0.5), end=(1, 0, 0.5), width=0.3, speed=1, run_signal="nope"
            ),
            ModelError,
            "signals: go",
        ),
        (
            lambda c: c.add_conveyor("c", start=(0, 0, 1e9), end=(1, 0, 1e9), width=0.3, speed=1),
            LimitError,
            "max_coordinate",
        ),
        (
            lambda c: c.add_source("s", "nothing", at=(0, 0, 0), every=1),
            ModelError,
            "movable parts: box",
        ),
        (lambda c: c.add_source("s", "box", at=(0, 0, 0)), ModelError, "one of every"),
        (
            lambda c: c.add_source("s", "box", at=(0, 0, 0), every=1, on_signal="go"),
            ModelError,
            "one of every",
        ),
        (lambda c: c.add_source("s", "box", at=(0, 0, 0), every=-1), ModelError, "> 0"),
        (lambda c: c.add_source("s", "box", at=(0, 0, 0), every=1, count=0), ModelError, ">= 1"),
        (
            lambda c: c.add_source("s", "box", at=(0, 0, 0), every=1, count=2.5),
            ModelError,
            "whole number",
        ),
        (
            lambda c: c.add_source("s", "box", at=(0, 0, 0), every=1, count=10**6),
            LimitError,
            "max_part_copies",
        ),
        (lambda c: c.add_source("s", "box", at=np.eye(4) * 2, every=1), GeometryError, "at"),
        (lambda c: c.add_sink("k", center=(0, 0, 0), size=(0.1, 0.1)), GeometryError, "3 finite"),
    ],
)
def test_a_bad_device_is_refused_and_changes_nothing(call, error, words):
    cell = base_cell()
    before = _state(cell)
    with pytest.raises(error, match=words):
        call(cell)
    assert _state(cell) == before


def test_copy_names_are_reserved_and_a_part_feeds_one_source():
    cell = base_cell()
    cell.add_source("feeder", "box", at=(0, 0, 0), every=1.0, count=2)
    with pytest.raises(ModelError, match="reserved for a copy made by source 'feeder'"):
        cell.add_signal("box_2", 1)
    cell.add_signal("box_3", 1)  # beyond the count: free
    with pytest.raises(ModelError, match="pattern of source 'feeder'"):
        cell.add_source("other", "box", at=(0, 0, 0), every=1.0)
    with pytest.raises(ModelError, match="source 'feeder' copies it"):
        cell.remove("box")
    other = base_cell()
    other.add_signal("box_7", 1)
    with pytest.raises(ModelError, match="'box_7' is taken"):
        other.add_source("feeder", "box", at=(0, 0, 0), every=1.0)  # pool: max_part_copies


def test_removing_a_signal_a_device_uses_is_refused():
    cell = full_cell()
    with pytest.raises(ModelError, match="conveyor 'belt' uses it"):
        cell.remove("go")
    cell.remove("belt")
    cell.remove("go")
    assert "go" not in cell.signals
    assert cell.kind_of("beam") == "sensor"


def test_a_source_without_count_has_the_limit_as_its_pool():
    with limits.using(max_part_copies=5):
        cell = base_cell()
        src = cell.add_source("feeder", "box", at=(0, 0, 0), every=1.0)
    assert src.pool == 5
    assert src.copies[-1] == "box_5"


def test_the_compiled_belt_stands_where_it_was_given():
    cell = full_cell()
    cc = compile_cell(cell)
    m = cc.model
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    g = m.geom(belt_geom("belt")).id
    half = m.geom_size[g]
    # the slab: top face at the belt's height, its x axis along the belt, length and width
    assert d.geom_xpos[g][2] + half[2] == pytest.approx(0.5, abs=1e-12)
    assert 2 * half[2] == pytest.approx(BELT_THICKNESS)
    assert 2 * half[0] == pytest.approx(2.5)
    assert 2 * half[1] == pytest.approx(0.3)
    assert np.allclose(d.geom_xmat[g].reshape(3, 3)[:, 0], [1, 0, 0], atol=1e-12)
    stop = m.geom("belt.col2").id
    assert d.geom_xpos[stop][0] - m.geom_size[stop][0] == pytest.approx(1.5, abs=1e-12)
    assert 2 * m.geom_size[stop][0] == pytest.approx(STOP_THICKNESS)
    assert d.geom_xpos[stop][2] + m.geom_size[stop][2] == pytest.approx(0.5 + STOP_HEIGHT)
    assert np.allclose(m.geom_surfacevel[g], [0.25, 0, 0, 0, 0, 0])  # "go" starts true


def test_a_belt_has_its_surface_velocity_compiled_when_it_runs_from_the_start():
    cell = base_cell()
    cell.add_signal("off", False)
    cell.add_conveyor("belt", start=(0, 0, 0.5), end=(0, 2, 0.5), width=0.3, speed=0.4)
    cell.add_conveyor(
        "idle", start=(1, 0, 0.5), end=(1, 2, 0.5), width=0.3, speed=0.4, run_signal="off"
    )
    m = compile_cell(cell).model
    assert np.allclose(m.geom_surfacevel[m.geom(belt_geom("belt")).id], [0.4, 0, 0, 0, 0, 0])
    assert np.allclose(m.geom_surfacevel[m.geom(belt_geom("idle")).id], 0.0)


def test_copies_are_parked_bodies_and_the_statistic_is_the_cells(tmp_path):
    cell = full_cell()
    cc = compile_cell(cell)
    m = cc.model
    assert cc.patterns == {"box_1": "box", "box_2": "box", "box_3": "box"}
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    heights = [d.xpos[m.body(c).id][2] for c in ("box_1", "box_2", "box_3")]
    assert min(heights) > PARKED_ABOVE
    # the copies share the pattern's meshes and mass
    assert m.body_mass[m.body("box_1").id] == pytest.approx(m.body_mass[m.body("box").id])
    assert m.geom_dataid[m.geom("box_2.visual").id] == m.geom_dataid[m.geom("box.visual").id]
    without = base_cell()
    without.add_conveyor("belt", start=(-1, 0, 0.5), end=(1.5, 0, 0.5), width=0.3, speed=0.25)
    ref = compile_cell(without).model
    assert m.stat.extent == pytest.approx(ref.stat.extent, rel=1e-9)
    # the exported file keeps the statistic, loads in MuJoCo and in dm_control
    xml = export_cell(cell, tmp_path / "out")
    m2 = mujoco.MjModel.from_xml_path(str(xml))
    assert m2.stat.extent == pytest.approx(m.stat.extent, rel=1e-9)
    from dm_control import mjcf

    physics = mjcf.Physics.from_mjcf_model(mjcf.from_path(str(xml)))
    assert physics.model.nbody == m.nbody
