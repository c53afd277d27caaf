"""Study parameters and candidates: value specs, grids in product order, seeded samples."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from workcell.errors import LimitError, StudyError
from workcell.study import Study, parameter
from workcell.study.spec import parse_vary

finite = st.floats(-10, 10, allow_nan=False, allow_infinity=False)


@given(lo=finite, span=st.floats(0, 10), n=st.integers(1, 50))
def test_grid_axis_is_n_evenly_spaced_values_from_lo_to_hi(lo, span, n):
    hi = lo + span
    p = parse_vary(f"puma.base.x={lo!r}:{hi!r}:{n}")
    assert len(p.values) == n
    assert p.values[0] == pytest.approx(lo, abs=1e-9)
    assert p.values[-1] == hi if n > 1 else p.values[-1] == lo
    if n > 1:
        assert np.diff(p.values) == pytest.approx(np.full(n - 1, span / (n - 1)), abs=1e-9)


def test_value_specs():
    assert parameter("puma.base.x", "-0.1:0.1:5").values == (-0.1, -0.05, 0.0, 0.05, 0.1)
    assert parameter("puma.base.x", (0, 1, 3)).values == (0.0, 0.5, 1.0)
    assert parameter("cube.y", "0.1,0.2,0.25").values == (0.1, 0.2, 0.25)
    assert parameter("cube.y", [0.3]).values == (0.3,)
    assert parameter("puma.speed", 0.4).values == (0.4,)
    r = parameter("puma.base.yaw", "0:90")
    assert (r.discrete, r.low, r.high, r.unit) == (False, 0.0, 90.0, "deg")
    choice = parameter("puma.robot", "puma260, puma560")
    assert choice.values == ("puma260", "puma560")
    assert choice.text


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("puma.base.q=1", "unknown field 'base.q'"),
        ("base.x", "NAME=VALUES"),
        ("x=1", "THING.FIELD"),
        ("puma.base.x=1:0:3", "LO must be <= HI"),
        ("puma.base.x=0:1:0", "integer >= 1"),
        ("puma.base.x=0:1:2.5", "integer >= 1"),
        ("puma.base.x=0:1:2:3", "cannot read"),
        ("puma.base.x=zero", "not a number"),
        ("puma.base.x=nan", "finite"),
        ("puma.speed=0:1:3", "speed must be > 0"),
        ("puma.override=0.5,1.5", "override must be in (0, 1]"),
        ("puma.base.x=1:1", "LO < HI"),
    ],
)
def test_bad_values_are_refused_with_what_is_valid(text, says):
    with pytest.raises(StudyError, match=None) as info:
        parse_vary(text)
    assert says in str(info.value)


def test_study_checks():
    with pytest.raises(StudyError, match="at least one parameter"):
        Study(cell="joints", vary={})
    with pytest.raises(StudyError, match="given twice"):
        Study(cell="joints", vary=["puma.base.x=0,1", "puma.base.x=2"])
    with pytest.raises(StudyError, match="sample=N"):
        Study(cell="joints", vary={"puma.base.x": "0:1"})
    with pytest.raises(LimitError, match="over the limit max_candidates"):  # the one budget
        Study(cell="joints", vary={"puma.base.x": (0, 1, 1001), "puma.base.y": (0, 1, 1001)})
    with pytest.raises(StudyError, match="sample must be"):
        Study(cell="joints", vary={"puma.base.x": "0,1"}, sample=0)
    with pytest.raises(StudyError, match="needs a cell"):
        Study(vary={"puma.base.x": "0,1"})


def test_full_grid_is_the_product_in_order():
    study = Study(
        cell="joints",
        vary={"puma.base.x": "0:0.2:3", "puma.robot": "puma260,puma560", "puma.base.yaw": "0,90"},
    )
    got = study.candidates()
    want = list(itertools.product((0.0, 0.1, 0.2), ("puma260", "puma560"), (0.0, 90.0)))
    assert [c.values for c in got] == want
    assert [c.id for c in got] == list(range(12))
    assert study.size == 12


def test_sample_of_a_grid_is_distinct_seeded_and_reproducible():
    vary = {"puma.base.x": "0:0.9:10", "puma.base.y": "0:0.9:10"}
    a = Study(cell="joints", vary=vary, sample=30, seed=7).candidates()
    b = Study(cell="joints", vary=vary, sample=30, seed=7).candidates()
    c = Study(cell="joints", vary=vary, sample=30, seed=8).candidates()
    assert a == b
    assert [x.values for x in a] != [x.values for x in c]
    assert len({x.values for x in a}) == 30  # without replacement
    grid = set(itertools.product(*(parameter(k, v).values for k, v in vary.items())))
    assert {x.values for x in a} <= grid
    with pytest.raises(StudyError, match="more than the 100 distinct"):
        Study(cell="joints", vary=vary, sample=101).candidates()


def test_sample_of_ranges_is_uniform_within_the_range():
    study = Study(
        cell="joints",
        vary={"puma.base.x": "-0.2:0.2", "puma.robot": "puma260,puma560"},
        sample=400,
        seed=3,
    )
    got = study.candidates()
    x = np.array([c.values[0] for c in got])
    assert x.min() >= -0.2
    assert x.max() < 0.2
    # uniform on [-0.2, 0.2): mean 0, standard deviation 0.4 / sqrt(12); 4 standard errors
    assert abs(x.mean()) < 4 * 0.4 / np.sqrt(12) / np.sqrt(400)
    assert x.std() == pytest.approx(0.4 / np.sqrt(12), rel=0.1)
    robots = [c.values[1] for c in got]
    assert 150 < robots.count("puma260") < 250
