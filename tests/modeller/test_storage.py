"""Tests of workcell.modeller.storage: versioned JSON save/load of the datamodel.

Round trips must be exact (bit for bit), damaged files must raise ModelError naming the
file and the place, and writes must be atomic.
"""

from __future__ import annotations

import copy
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from helpers import THESIS_ROWS
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import workcell
from workcell import Model, Surface, spatial
from workcell.errors import ModelError
from workcell.modeller import storage
from workcell.modeller.model import LEVELS

UNIT_SQUARE = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
D90 = math.pi / 2


def _awkward_model() -> Model:
    m = Model()
    m.create("surface", "square1", Surface(UNIT_SQUARE))
    m.create(
        "surface",
        "odd",
        Surface(
            [(0.0, 0.0), (1 / 3, 0.0), (0.1 + 0.2, 0.7), (1e-300, 1 / 7)],
            name="odd",
        ),
        colour=(0.1 + 0.2, 1 / 3, 0.0),
    )
    m.create(
        "surface",
        "plate",
        Surface([(0, 0), (3, 0), (3, 3), (0, 3)], [[(1, 1), (2, 1), (2, 2), (1, 2)]]),
    )
    m.create("block", "cube1", colour=(1 / 3, 2 / 3, 0.1 + 0.2, 0.7))
    for T in THESIS_ROWS:
        m.attach("cube1", "square1", T)
    m.attach("cube1", "square1", spatial.translation(5, 5, 5))
    m.detach("cube1", "ts7")  # serial 7, the six faces left
    T = np.eye(4)
    T[0, 0], T[0, 1], T[0, 3] = 1 / 3, 1e-300, 0.1 + 0.2
    T[1, 2], T[1, 3], T[2, 3] = 5e-324, -1 / 3, -999999.9999999999  # (max_coordinate 1e6)
    m.create("block", "weird")
    m.attach("weird", "odd", T, name="w1")
    m.attach("weird", "plate", spatial.srt(scale=(0.1, 0.2, 0.3), rotation=(0.1, 0.2, 0.3)))
    workcell.solids.cube(m, "c2", size=0.1 + 0.2)
    m.create_boolean("u", "difference", ["cube1", "c2"], [None, spatial.translation(1 / 3, 0, 0)])
    m.create("object", "o", movable=True)
    m.attach("o", "cube1", spatial.scaling(2, 3, 1.5))
    m.attach("o", "u", name="base")
    m.create("object", "cube1")  # the same name at a second level
    m.create("scene", "cell")
    m.attach("cell", "o", spatial.srt(rotation=(0.1, 0.2, 0.3), translation=(0.1, 0.2, 1 / 3)))
    m.attach("cell", ("object", "cube1"), spatial.rot_z(1 / 3))
    m.rename_relation("cell", "to2", "to5")
    return m


def _state(m: Model):
    pb = {(lv, n): m.pointed_by((lv, n)) for lv in LEVELS for n in m.list(lv)}
    return m.to_dict(), pb, m.show(detail=True)


# ============================================================== round trips
class TestRoundTrip:
    def test_save_load_exact(self, tmp_path):
        m = _awkward_model()
        path = tmp_path / "cell.json"
        m.save(str(path))
        back = Model.load(str(path))
        assert back.to_dict() == m.to_dict()
        assert _state(back) == _state(m)
        assert back == m
        # bit-for-bit transforms, not just equal-looking ones
        for lv in LEVELS[1:]:
            for n in m.list(lv):
                for a, b in zip(m.relations((lv, n)), back.relations((lv, n)), strict=True):
                    assert a.transform.tobytes() == b.transform.tobytes()
        for n in m.list("surface"):
            assert back.surface(("surface", n)).same_geometry(m.surface(("surface", n)))
        t = back.relation("weird", "w1").transform
        assert t[0, 3] == 0.30000000000000004
        assert t[0, 0] == 1 / 3
        assert t[0, 1] == 1e-300
        assert t[1, 2] == 5e-324
        assert t[2, 3] == -999999.9999999999

    def test_file_is_versioned_json(self, tmp_path):
        path = tmp_path / "m.json"
        _awkward_model().save(path)
        data = json.loads(path.read_text(encoding="utf-8"))
        assert data["format"] == "workcell-model"
        assert data["version"] == 1
        assert [b["name"] for b in data["blocks"]] == ["cube1", "weird", "c2", "u"]
        assert "0.30000000000000004" in path.read_text(encoding="utf-8")

    def test_geometry_survives(self, tmp_path):
        m = _awkward_model()
        m.save(tmp_path / "m.json")
        back = Model.load(tmp_path / "m.json")
        for ref in [("block", "u"), ("object", "o"), "cell", "c2"]:
            p0, p1 = m.properties(ref), back.properties(ref)
            assert p1.volume == p0.volume
            assert np.array_equal(p1.centroid, p0.centroid)

    def test_generated_names_continue_after_load(self, tmp_path):
        m = _awkward_model()
        m.save(tmp_path / "m.json")
        back = Model.load(tmp_path / "m.json")
        cube = ("block", "cube1")
        assert back.attach(cube, "square1") == m.attach(cube, "square1") == "ts8"
        assert back.attach("cell", "o") == m.attach("cell", "o")
        assert back.attach(("object", "o"), ("block", "c2")) == m.attach(
            ("object", "o"), ("block", "c2")
        )
        assert back.attach("u", "c2") == m.attach("u", "c2")
        assert back.to_dict() == m.to_dict()

    def test_empty_model(self, tmp_path):
        Model().save(tmp_path / "e.json")
        back = Model.load(tmp_path / "e.json")
        assert back.list() == {lv: [] for lv in LEVELS}

    def test_overwrite_replaces_whole_file(self, tmp_path):
        path = tmp_path / "m.json"
        _awkward_model().save(path)
        Model().save(path)
        assert Model.load(path).list() == {lv: [] for lv in LEVELS}
        assert os.listdir(tmp_path) == ["m.json"]

    def test_dict_round_trip(self):
        m = _awkward_model()
        d = m.to_dict()
        assert Model.from_dict(json.loads(json.dumps(d))).to_dict() == d
        assert Model.from_dict(d).to_dict() == d


# ============================================================== random models (hypothesis)
def _affine(data) -> np.ndarray:
    """A random affine map; strictly diagonally dominant, so never singular."""
    T = np.eye(4)
    A = np.array(data.draw(st.lists(st.floats(-1, 1), min_size=9, max_size=9))).reshape(3, 3)
    diag = data.draw(st.lists(st.floats(2.5, 4), min_size=3, max_size=3))
    signs = data.draw(st.sampled_from([(1, 1, 1), (-1, 1, 1), (1, -1, 1)]))
    A[np.diag_indices(3)] = np.multiply(diag, signs)
    T[:3, :3] = A
    T[:3, 3] = data.draw(
        st.lists(
            st.one_of(st.floats(-1e3, 1e3), st.sampled_from([0.1 + 0.2, 1 / 3, 1e-300, -5e-324])),
            min_size=3,
            max_size=3,
        )
    )
    return T


def _rigid(data) -> np.ndarray:
    q = np.array(data.draw(st.lists(st.floats(-1, 1), min_size=4, max_size=4)))
    if np.linalg.norm(q) < 1e-2:
        q = np.array([0.0, 0.0, 0.0, 1.0])
    T = np.eye(4)
    T[:3, :3] = Rotation.from_quat(q / np.linalg.norm(q)).as_matrix()
    T[:3, 3] = data.draw(st.lists(st.floats(-100, 100), min_size=3, max_size=3))
    return T


def _colour(data):
    return data.draw(
        st.one_of(st.none(), st.lists(st.floats(0, 1), min_size=3, max_size=4).map(tuple))
    )


def _random_model(data) -> Model:
    m = Model()
    surfaces = []
    for i in range(data.draw(st.integers(1, 3))):
        kind = data.draw(st.sampled_from(["rect", "ngon", "holed"]))
        if kind == "rect":
            s = Surface.rectangle(data.draw(st.floats(0.01, 10)), data.draw(st.floats(0.01, 10)))
        elif kind == "ngon":
            s = Surface.regular_polygon(
                data.draw(st.integers(3, 9)),
                data.draw(st.floats(0.01, 10)),
                phase=data.draw(st.floats(-3, 3)),
            )
        else:
            r = data.draw(st.floats(0.1, 0.9))
            s = Surface(Surface.circle(1.0, 12).main, [Surface.circle(r, 7).main])
        name = f"s{i}"
        m.create("surface", name, s, colour=_colour(data))
        surfaces.append(name)
    blocks = []
    for i in range(data.draw(st.integers(1, 3))):
        name = f"b{i}"
        m.create("block", name, colour=_colour(data), movable=data.draw(st.booleans()))
        for _ in range(data.draw(st.integers(0, 4))):
            custom = data.draw(st.sampled_from([None, None, "side", "ts3"]))
            target = data.draw(st.sampled_from(surfaces))
            if custom in [r.name for r in m.relations(("block", name))]:
                custom = None
            m.attach(("block", name), ("surface", target), _affine(data), name=custom)
        rels = m.relations(("block", name))
        if rels and data.draw(st.booleans()):
            m.detach(("block", name), data.draw(st.sampled_from(rels)).name)
        blocks.append(name)
    if data.draw(st.booleans()):
        ops = data.draw(st.lists(st.sampled_from(blocks), min_size=2, max_size=3))
        op = data.draw(st.sampled_from(["union", "difference", "intersection"]))
        m.create_boolean("bool", op, ops, [_affine(data) for _ in ops])
        blocks.append("bool")
    objects = []
    for i in range(data.draw(st.integers(0, 2))):
        name = f"o{i}"
        m.create("object", name, colour=_colour(data), movable=data.draw(st.booleans()))
        for _ in range(data.draw(st.integers(0, 3))):
            m.attach(("object", name), ("block", data.draw(st.sampled_from(blocks))), _affine(data))
        objects.append(name)
    for i in range(data.draw(st.integers(0, 2)) if objects else 0):
        name = f"sc{i}"
        m.create("scene", name)
        for _ in range(data.draw(st.integers(0, 3))):
            m.attach(("scene", name), ("object", data.draw(st.sampled_from(objects))), _rigid(data))
    if data.draw(st.booleans()):
        m.create("object", "s0")  # a name shared across levels
    return m


@given(st.data())
@settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
def test_random_models_round_trip(data):
    m = _random_model(data)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "model.json")
        m.save(path)
        back = Model.load(path)
        assert os.listdir(tmp) == ["model.json"]
    assert back.to_dict() == m.to_dict()
    assert _state(back) == _state(m)
    # generated names continue identically on every owner
    for lv in LEVELS[1:]:
        for n in m.list(lv):
            rels = m.relations((lv, n))
            if not rels:
                continue
            target = (rels[0].target_level, rels[0].target)
            T = np.eye(4)
            assert back.attach((lv, n), target, T) == m.attach((lv, n), target, T)
    assert back.to_dict() == m.to_dict()


# ============================================================== damaged files
def _valid_dict() -> dict:
    return _awkward_model().to_dict()


def _write(tmp_path: Path, data) -> Path:
    path = tmp_path / "damaged.json"
    path.write_text(json.dumps(data) if not isinstance(data, str) else data, encoding="utf-8")
    return path


def _block(d: dict, name: str) -> dict:
    return next(b for b in d["blocks"] if b["name"] == name)


def _damage(fn):
    def make():
        d = _valid_dict()
        fn(d)
        return d

    return make


DAMAGES = {
    "dangling-target": (
        _damage(lambda d: _block(d, "cube1")["relations"][0].update(target="ghost")),
        ["blocks[0] 'cube1'", "ghost"],
    ),
    "dangling-object": (
        _damage(lambda d: d["scenes"][0]["relations"][0].update(target="nobody")),
        ["scenes[0] 'cell'", "nobody"],
    ),
    "duplicate-name": (
        _damage(lambda d: d["blocks"].append(copy.deepcopy(d["blocks"][1]))),
        ["blocks[4] 'weird'", "already exists"],
    ),
    "duplicate-surface": (
        _damage(lambda d: d["surfaces"].append(copy.deepcopy(d["surfaces"][0]))),
        ["surfaces[4] 'square1'", "already exists"],
    ),
    "duplicate-relation-name": (
        _damage(lambda d: _block(d, "cube1")["relations"][1].update(name="ts1")),
        ["blocks[0] 'cube1'", "ts1"],
    ),
    "non-rigid-scene": (
        _damage(
            lambda d: d["scenes"][0]["relations"][0].update(
                transform=spatial.scaling(1, 2, 1).tolist()
            )
        ),
        ["scenes[0] 'cell'", "rigid"],
    ),
    "non-affine": (
        _damage(
            lambda d: _block(d, "weird")["relations"][1].update(
                transform=[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0.5, 1]]
            )
        ),
        ["blocks[1] 'weird'", "not affine"],
    ),
    "singular": (
        _damage(
            lambda d: _block(d, "weird")["relations"][0].update(
                transform=np.diag([1.0, 1, 0, 1]).tolist()
            )
        ),
        ["blocks[1] 'weird'", "singular"],
    ),
    "transform-3x3": (
        _damage(lambda d: _block(d, "weird")["relations"][0].update(transform=np.eye(3).tolist())),
        ["blocks[1] 'weird'"],
    ),
    "transform-ragged": (
        _damage(
            lambda d: _block(d, "weird")["relations"][0].update(
                transform=[[1, 0, 0, 0], [0, 1, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
            )
        ),
        ["blocks[1] 'weird'"],
    ),
    "transform-strings": (
        _damage(lambda d: _block(d, "weird")["relations"][0].update(transform=[["a"] * 4] * 4)),
        ["blocks[1] 'weird'"],
    ),
    "transform-huge-int": (
        _damage(
            lambda d: _block(d, "weird")["relations"][0].update(
                transform=[[10**400, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
            )
        ),
        ["blocks[1] 'weird'"],
    ),
    "surface-huge-int": (
        _damage(lambda d: d["surfaces"][0].update(main=[[0, 0], [10**400, 0], [1, 1]])),
        ["surfaces[0] 'square1'"],
    ),
    "unknown-version": (_damage(lambda d: d.update(version=2)), ["version 2"]),
    "version-string": (_damage(lambda d: d.update(version="1")), ["version (a str)"]),
    "version-bool": (_damage(lambda d: d.update(version=True)), ["version True"]),
    "version-missing": (_damage(lambda d: d.pop("version")), ["version"]),
    "wrong-format": (_damage(lambda d: d.update(format="other-model")), ["format"]),
    "format-missing": (_damage(lambda d: d.pop("format")), ["format"]),
    "top-level-list": (lambda: [1, 2, 3], ["format"]),
    "section-missing": (_damage(lambda d: d.pop("objects")), ["document", "objects"]),
    "section-not-list": (_damage(lambda d: d.update(blocks={})), ["document", "blocks"]),
    "bowtie-surface": (
        _damage(lambda d: d["surfaces"][0].update(main=[[0, 0], [1, 1], [1, 0], [0, 1]])),
        ["surfaces[0] 'square1'", "main contour"],
    ),
    "hole-outside": (
        _damage(lambda d: d["surfaces"][2].update(holes=[[[5, 5], [6, 5], [6, 6]]])),
        ["surfaces[2] 'plate'", "hole 0"],
    ),
    "surface-nan": (
        _damage(lambda d: d["surfaces"][0].update(main=[[0, 0], [float("nan"), 0], [1, 1]])),
        ["surfaces[0] 'square1'", "non-finite"],
    ),
    "name-int": (_damage(lambda d: d["blocks"][0].update(name=5)), ["blocks[0]", "name"]),
    "name-invalid": (_damage(lambda d: d["objects"][0].update(name="a b")), ["objects[0]"]),
    "movable-string": (
        _damage(lambda d: d["objects"][0].update(movable="no")),
        ["objects[0] 'o'", "movable"],
    ),
    "movable-missing": (
        _damage(lambda d: d["objects"][0].pop("movable")),
        ["objects[0] 'o'", "movable"],
    ),
    "relations-dict": (
        _damage(lambda d: d["blocks"][0].update(relations={})),
        ["blocks[0] 'cube1'", "relations"],
    ),
    "serial-string": (
        _damage(lambda d: d["blocks"][0].update(serial="6")),
        ["blocks[0] 'cube1'", "serial"],
    ),
    "serial-bool": (
        _damage(lambda d: d["blocks"][0].update(serial=True)),
        ["blocks[0] 'cube1'", "serial"],
    ),
    "serial-negative": (
        _damage(lambda d: d["blocks"][0].update(serial=-3)),
        ["blocks[0] 'cube1'", "serial"],
    ),
    "transform-string": (
        _damage(lambda d: d["blocks"][0]["relations"][0].update(transform="eye")),
        ["blocks[0] 'cube1' relation 0", "transform"],
    ),
    "relation-name-int": (
        _damage(lambda d: d["blocks"][0]["relations"][0].update(name=1)),
        ["blocks[0] 'cube1' relation 0", "name"],
    ),
    "relation-not-object": (
        _damage(lambda d: d["blocks"][0]["relations"].append("ts9")),
        ["blocks[0] 'cube1' relation 6"],
    ),
    "entity-not-object": (_damage(lambda d: d["objects"].append(7)), ["objects[2]"]),
    "main-string": (
        _damage(lambda d: d["surfaces"][0].update(main="square")),
        ["surfaces[0] 'square1'", "main"],
    ),
    "holes-null": (
        _damage(lambda d: d["surfaces"][0].update(holes=None)),
        ["surfaces[0] 'square1'", "holes"],
    ),
    "colour-string": (
        _damage(lambda d: d["blocks"][0].update(colour="red")),
        ["blocks[0] 'cube1'", "colour"],
    ),
    "colour-huge-int": (
        _damage(lambda d: d["blocks"][0].update(colour=[10**400, 0, 0])),
        ["blocks[0] 'cube1'", "colour"],
    ),
    "colour-out-of-range": (
        _damage(lambda d: d["surfaces"][1].update(colour=[0, 0, 2])),
        ["surfaces[1] 'odd'", "colour"],
    ),
    "boolean-one-operand": (
        _damage(lambda d: _block(d, "u").update(relations=_block(d, "u")["relations"][:1])),
        ["blocks[3] 'u'", "at least 2"],
    ),
    "boolean-no-operand": (
        _damage(lambda d: _block(d, "u").update(relations=[])),
        ["blocks[3] 'u'", "at least 2"],
    ),
    "boolean-unknown-op": (
        _damage(lambda d: _block(d, "u").update(boolean="xor")),
        ["blocks[3] 'u'", "xor"],
    ),
    "boolean-on-object": (
        _damage(lambda d: d["objects"][0].update(boolean="union")),
        ["objects[0] 'o'", "boolean"],
    ),
    "boolean-cycle": (
        _damage(
            lambda d: _block(d, "c2").update(
                boolean="union",
                relations=[
                    {"name": "op1", "target": "u", "transform": np.eye(4).tolist()},
                    {"name": "op2", "target": "cube1", "transform": np.eye(4).tolist()},
                ],
            )
        ),
        ["cycle"],
    ),
    "target-wrong-level": (
        _damage(lambda d: d["objects"][0]["relations"][0].update(target="square1")),
        ["objects[0] 'o'", "square1"],
    ),
}


@pytest.mark.parametrize("case", sorted(DAMAGES))
def test_damaged_file_raises_model_error_naming_the_place(tmp_path, case):
    make, needles = DAMAGES[case]
    path = _write(tmp_path, make())
    with pytest.raises(ModelError) as info:
        Model.load(path)
    msg = str(info.value)
    assert str(path) in msg
    for needle in needles:
        assert needle in msg, f"{needle!r} not in {msg!r}"


@pytest.mark.parametrize("case", sorted(DAMAGES))
def test_damaged_dict_raises_model_error(case):
    make, needles = DAMAGES[case]
    data = json.loads(json.dumps(make()))
    with pytest.raises(ModelError) as info:
        Model.from_dict(data)
    assert needles[-1] in str(info.value)


def test_every_damage_is_a_single_fault():
    """Each case starts from a valid document: undo-able damage, not a broken fixture."""
    d = _valid_dict()
    assert Model.from_dict(d).to_dict() == d


def test_truncated_json(tmp_path):
    path = tmp_path / "m.json"
    _awkward_model().save(path)
    text = path.read_text(encoding="utf-8")
    for cut in (len(text) // 2, len(text) - 1, 1):
        path.write_text(text[:cut], encoding="utf-8")
        with pytest.raises(ModelError, match="not valid JSON") as info:
            Model.load(path)
        assert str(path) in str(info.value)
        assert "line 1" in str(info.value)


def test_not_utf8(tmp_path):
    path = tmp_path / "m.json"
    path.write_bytes(b'{"format": "workcell-model", "version": 1, "x": "\xff\xfe"}')
    with pytest.raises(ModelError, match="not UTF-8") as info:
        Model.load(path)
    assert str(path) in str(info.value)


def test_missing_file_and_directory(tmp_path):
    missing = tmp_path / "nope.json"
    with pytest.raises(ModelError, match="cannot read") as info:
        Model.load(missing)
    assert str(missing) in str(info.value)
    with pytest.raises(ModelError, match="cannot read"):
        Model.load(tmp_path)


def test_empty_file(tmp_path):
    path = tmp_path / "m.json"
    path.write_text("", encoding="utf-8")
    with pytest.raises(ModelError, match="not valid JSON"):
        Model.load(path)


def test_save_into_missing_directory_is_a_model_error(tmp_path):
    target = tmp_path / "no" / "such" / "dir" / "m.json"
    with pytest.raises(ModelError, match=r"cannot write .*m\.json"):
        _awkward_model().save(target)
    assert not (tmp_path / "no").exists()


# ============================================================== atomic writes
class TestAtomicWrite:
    @staticmethod
    def _setup(tmp_path):
        path = tmp_path / "m.json"
        old = _awkward_model()
        old.save(path)
        return path, path.read_bytes(), old

    def _assert_intact(self, tmp_path, path, before, old):
        assert path.read_bytes() == before
        assert os.listdir(tmp_path) == ["m.json"]  # no temp file left behind
        assert Model.load(path).to_dict() == old.to_dict()

    def test_failing_json_dumps_keeps_old_file(self, tmp_path, monkeypatch):
        path, before, old = self._setup(tmp_path)

        def boom(*args, **kwargs):
            raise RuntimeError("serialisation failed")

        monkeypatch.setattr(storage.json, "dumps", boom)
        with pytest.raises(RuntimeError, match="serialisation failed"):
            Model().save(path)
        monkeypatch.undo()
        self._assert_intact(tmp_path, path, before, old)

    def test_failing_dict_conversion_keeps_old_file(self, tmp_path, monkeypatch):
        path, before, old = self._setup(tmp_path)

        def boom(model):
            raise ValueError("cannot convert")

        monkeypatch.setattr(storage, "model_to_dict", boom)
        with pytest.raises(ValueError, match="cannot convert"):
            Model().save(path)
        monkeypatch.undo()
        self._assert_intact(tmp_path, path, before, old)

    @pytest.mark.parametrize("where", ["fsync", "replace"])
    def test_failing_write_keeps_old_file_and_removes_temp(self, tmp_path, monkeypatch, where):
        path, before, old = self._setup(tmp_path)
        seen = {}

        def boom(*args, **kwargs):
            seen["temps"] = [n for n in os.listdir(tmp_path) if n != "m.json"]
            raise OSError(28, "No space left on device")

        monkeypatch.setattr(storage.os, where, boom)
        with pytest.raises((OSError, ModelError)):
            Model().save(path)
        monkeypatch.undo()
        assert len(seen["temps"]) == 1  # the temp file existed while writing ...
        assert seen["temps"][0].endswith(".tmp")
        self._assert_intact(tmp_path, path, before, old)  # ... and is gone now

    def test_interrupt_during_write_removes_temp(self, tmp_path, monkeypatch):
        path, before, old = self._setup(tmp_path)

        def interrupt(*args, **kwargs):
            raise KeyboardInterrupt

        monkeypatch.setattr(storage.os, "fsync", interrupt)
        with pytest.raises(KeyboardInterrupt):
            Model().save(path)
        monkeypatch.undo()
        self._assert_intact(tmp_path, path, before, old)


def test_saved_file_has_the_usual_mode(tmp_path):
    import os

    from workcell import Model

    umask = os.umask(0)
    os.umask(umask)
    path = tmp_path / "m.json"
    Model().save(path)
    assert (path.stat().st_mode & 0o777) == (0o666 & ~umask)
