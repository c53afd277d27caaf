"""Issue 14, item 6: loaders turn every parse failure into ModelError, and names and
script lines cannot hide anything.

Attacks: JSON nested far deeper than the parser's recursion, integers of more than 4300
digits, ``"version": true``, names ending in a newline or a million characters long, and
random JSON put anywhere in a valid model or cell (hypothesis): nothing but ModelError
may come out, and nothing is loaded partially. Script lines split by Unicode line
separators (a command hidden behind a comment) are refused."""

from __future__ import annotations

import contextlib
import json
import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from workcell import Model, Workcell, solids
from workcell.errors import ModelError, ProgramError
from workcell.examples import thesis_joints
from workcell.modeller.model import MAX_NAME_LENGTH
from workcell.program import Session
from workcell.program.interpreter import check_script, run_script


def small_model() -> dict:
    m = Model()
    solids.cube(m, "c", size=0.1)
    m.create("object", "o")
    m.attach("o", "c")
    return m.to_dict()


def load_both(tmp_path, text: str) -> list[Exception]:
    """Load ``text`` as a model file and as a cell file; the exceptions raised."""
    p = tmp_path / "f.json"
    p.write_text(text)
    errors = []
    for load in (Model.load, Workcell.load):
        with pytest.raises(ModelError) as info:
            load(p)
        errors.append(info.value)
    return errors


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),  # RecursionError before
        ('{"a": ' * 50_000 + "1" + "}" * 50_000, "nested too deeply"),
        ('{"format": "workcell-model", "version": ' + "9" * 5000 + "}", "more than 4300 digits"),
        ("[" + "1" * 4301 + "]", "more than 4300 digits"),  # ValueError before
        ('{"format": "workcell-model", "version": 1, "surfaces": [', "not valid JSON"),
        ("\ufeff{}", "not valid JSON"),
        ("", "not valid JSON"),
    ],
)
def test_unparsable_files_give_model_errors(tmp_path, text, words):
    for error in load_both(tmp_path, text):
        assert words in str(error)
        assert len(str(error)) < 400  # no echo of the file


def test_deep_nesting_inside_a_valid_document_is_a_model_error(tmp_path):
    deep = "[" * 900 + "0" + "]" * 900  # parses; deeper than anything a loader expects
    data = small_model()
    data["surfaces"][0]["main"] = "DEEP"
    path = tmp_path / "m.json"
    path.write_text(json.dumps(data).replace('"DEEP"', deep))
    with pytest.raises(ModelError, match=r"surfaces\[0\]"):
        Model.load(path)
    cell = thesis_joints.build().to_dict()
    cell["robots"][0]["q"] = "DEEP"
    path.write_text(json.dumps(cell).replace('"DEEP"', deep))
    with pytest.raises(ModelError, match=r"robots\[0\]"):
        Workcell.load(path)


@pytest.mark.parametrize(
    "version",
    [True, 1.0, "1", None, [1], 10**5000],
    ids=["true", "1.0", "str", "null", "list", "huge"],
)
def test_a_version_that_is_not_the_integer_1_is_refused(version):
    model = {**small_model(), "version": version}
    with pytest.raises(ModelError, match="version"):
        Model.from_dict(model)
    cell = {**thesis_joints.build().to_dict(), "version": version}
    with pytest.raises(ModelError, match="version"):  # "version": true was accepted as 1
        Workcell.from_dict(cell)


@pytest.mark.parametrize(
    "name",
    [
        "abc\n",  # passed the old check (re.match with $)
        "a" * 1_000_000,
        "a" * (MAX_NAME_LENGTH + 1),
        "a\tb",
        "caf\u00e9",
        "a\u2028b",
        "",
        "1a",
    ],
)
def test_bad_names_are_refused_quickly_everywhere(tmp_path, name):
    t0 = time.process_time()  # CPU time: the work done, whatever the machine's load
    m = Model()
    with pytest.raises(ModelError, match="invalid name") as info:
        m.create("block", name)
    assert len(str(info.value)) < 300  # a million characters are not echoed
    with pytest.raises(ModelError, match="invalid"):
        Workcell(name)
    data = small_model()
    data["blocks"][0]["name"] = name
    with pytest.raises(ModelError, match="invalid name"):
        Model.from_dict(data)
    cell = thesis_joints.build().to_dict()
    cell["robots"][0]["name"] = name
    with pytest.raises(ModelError) as info:
        Workcell.from_dict(cell)
    assert len(str(info.value)) < 500
    assert time.process_time() - t0 < 2.0
    assert m.list("block") == []


def test_names_up_to_the_documented_length_are_fine():
    m = Model()
    name = "a" * MAX_NAME_LENGTH
    assert m.create("block", name) == name
    assert Workcell(name).name == name


# random JSON anywhere: only ModelError, never a partial load
json_values = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(10**30), 10**30)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=20),
    lambda inner: (
        st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=8), inner, max_size=5)
    ),
    max_leaves=30,
)


def _paths(d: object, here: tuple = ()) -> list[tuple]:
    out = [here]
    if isinstance(d, dict):
        for k, v in d.items():
            out += _paths(v, (*here, k))
    elif isinstance(d, list):
        for i, v in enumerate(d[:3]):
            out += _paths(v, (*here, i))
    return out


def _put(d: object, path: tuple, value: object) -> object:
    if not path:
        return value
    d[path[0]] = _put(d[path[0]], path[1:], value)  # type: ignore[index]
    return d


CELL = thesis_joints.build().to_dict()
CELL_PATHS = _paths(CELL)
MODEL = small_model()
MODEL_PATHS = _paths(MODEL)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    which=st.sampled_from(["model", "cell"]),
    index=st.integers(0, 10**6),
    value=json_values,
)
def test_random_json_anywhere_gives_model_error_or_a_valid_load(which, index, value):
    base, paths, load = (
        (MODEL, MODEL_PATHS, Model.from_dict)
        if which == "model"
        else (CELL, CELL_PATHS, Workcell.from_dict)
    )
    data = _put(json.loads(json.dumps(base)), paths[index % len(paths)], value)
    with contextlib.suppress(ModelError):  # the only failure allowed
        load(data)


# ------------------------------------------------------------------ script lines
@pytest.mark.parametrize(
    "separator",
    ["\u2028", "\u2029", "\x85", "\x0b", "\x0c", "\x1c", "\r", "\u202e", "\x1b"],
)
def test_a_line_separator_cannot_hide_a_command_behind_a_comment(tmp_path, separator):
    script = tmp_path / "s.wcl"
    script.write_text(f"# only a comment{separator}create cube hidden size 1\n", encoding="utf-8")
    session = Session(base_dir=tmp_path)
    with pytest.raises(ProgramError, match=f"character U\\+{ord(separator):04X}") as info:
        run_script(script, session, out=lambda text: None)
    assert "s.wcl:1:" in str(info.value)  # before any line ran
    assert "column 17" in str(info.value)
    assert session.model.list("block") == []


def test_crlf_and_plain_scripts_still_run(tmp_path):
    script = tmp_path / "s.wcl"
    script.write_bytes(b"create cube a size 1\r\ncreate cube b size 2 # fine\r\n\r\n")
    session = run_script(script, Session(base_dir=tmp_path), out=lambda text: None)
    assert session.model.list("block") == ["a", "b"]
    assert check_script("create cube a size 1\n# \u00e9t\u00e9 is fine in a comment\n") == 1
