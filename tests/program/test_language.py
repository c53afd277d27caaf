"""The command language: tokens, units, the key tree matcher, errors, completion, help."""

from __future__ import annotations

import math

import numpy as np
import pytest

from workcell import ProgramError
from workcell.program import Session
from workcell.program import cellcommands as cellc
from workcell.program import commands as cmd
from workcell.program import simcommands as simc
from workcell.program import solidcommands as sol
from workcell.program.args import LEVELS
from workcell.program.keytree import CommandSyntaxError, leaves
from workcell.program.language import TREE, Meta, complete, help_text, parse_line
from workcell.program.lexer import split_commands, tokenize

D = math.pi / 180


def one(line: str, ctx=None):
    (c,) = parse_line(line, ctx)
    return c


def test_tokens_carry_columns_units_and_strings():
    toks = tokenize('save "my file.json"  # a comment')
    assert [(t.kind, t.col) for t in toks] == [("word", 1), ("string", 6)]
    assert toks[1].content == "my file.json"
    toks = tokenize("q (0, -90deg, 1.5e-1rad) 100mm")
    assert [(t.text, t.col, t.value, t.unit) for t in toks if t.kind == "number"] == [
        ("0", 4, 0.0, ""),
        ("-90deg", 7, -90.0, "deg"),
        ("1.5e-1rad", 15, 0.15, "rad"),
        ("100mm", 26, 100.0, "mm"),
    ]
    assert len(split_commands("list; list ;; show")) == 3
    with pytest.raises(ProgramError, match="column 6: string not closed"):
        tokenize('save "x')


@pytest.mark.parametrize(
    ("line", "field", "value"),
    [
        ("wait 20 ms", "seconds", 0.02),
        ("wait 1.5", "seconds", 1.5),
        ("speed puma 0.3 rad/s", "speed", 0.3),
        ("speed puma 90", "speed", 90 * D),
        ("speed puma 90deg/s", "speed", 90 * D),
        ("create cube c size 40 mm", "size", 0.04),
        ("create cube c size 4cm", "size", 0.04),
        ("close gripper puma distance 10 mm angle 5", "max_distance", 0.01),
        ("close gripper puma distance 10 mm angle 5", "max_angle", 5 * D),
    ],
)
def test_numbers_are_read_in_si_with_peoples_defaults(line, field, value):
    assert getattr(one(line), field) == pytest.approx(value, rel=1e-12)


def test_joint_vectors_take_degrees_a_trailing_unit_or_glued_units():
    c = one("move joints absolute puma -60 0 -70 0 90 30")
    assert c == simc.MoveJointsAbsolute("puma", tuple(v * D for v in (-60, 0, -70, 0, 90, 30)))
    c = one("move joints relative puma 0.1 0 0 0 0 0 rad")
    assert c.dq == (0.1, 0, 0, 0, 0, 0)
    c = one("move joints relative puma (0.1rad, 90, 0, 0, 0, 0)")
    assert c.dq == pytest.approx((0.1, 90 * D, 0, 0, 0, 0))


def test_transforms_are_srt_in_degrees_and_metres():
    c = one("attach square1 to cube1 as face2 rotate 90 0 0 translate 0 1 0")
    assert c.relation == "face2"
    # R_x(90) then T_y(1): the square's y axis goes to +z, its origin to (0, 1, 0)
    assert np.allclose(c.transform, [[1, 0, 0, 0], [0, 0, -1, 1], [0, 1, 0, 0], [0, 0, 0, 1]])
    c = one("copy cube1 to para scale 2 3 1.5")
    assert c.transform == ((2, 0, 0, 0), (0, 3, 0, 0), (0, 0, 1.5, 0), (0, 0, 0, 1))
    c = one("copy cube1 to big scale 2")
    assert c.transform[0][0] == c.transform[1][1] == c.transform[2][2] == 2
    c = one("copy cube1 to m matrix 1 0 0 5  0 1 0 0  0 0 1 0  0 0 0 1")
    assert c.transform[0][3] == 5
    with pytest.raises(ProgramError, match="not both"):
        one("copy cube1 to m matrix 1 0 0 5 0 1 0 0 0 0 1 0 0 0 0 1 scale 2")
    with pytest.raises(ProgramError, match="1 or 3"):
        one("copy cube1 to m scale 1 2")


def test_tool_poses_from_positions_parts_and_orientations():
    c = one("move end_effector puma at 400 0 300 mm down config ru")
    assert c.T.position == pytest.approx((0.4, 0, 0.3))
    assert c.config == "ru"
    assert np.allclose(c.T.rotation, [[1, 0, 0], [0, -1, 0], [0, 0, -1]])
    c = one("move straight puma on stage_1 offset 0 0 20mm rpy 90 0 -90 step 1 mm")
    assert (c.T.part, c.T.anchor, c.step) == ("stage_1", "top", 0.001)
    assert c.T.offset == pytest.approx((0, 0, 0.02))
    # rpy 90 0 -90: R = Rz(-90) Rx(90): tool z along -x
    assert np.allclose(c.T.rotation, [[0, 0, -1], [-1, 0, 0], [0, 1, 0]])
    c = one("move end_effector puma at cube")
    assert (c.T.part, c.T.anchor, c.T.rotation) == ("cube", "centroid", None)
    for bad in ("move end_effector p at cube on cube", "move end_effector p rpy 0 0 0 down"):
        with pytest.raises(ProgramError, match="not both"):
            one(bad)


def test_keywords_by_unambiguous_prefix_any_case_and_the_simulators_method_names():
    assert one("cr cu c1 si 2") == sol.CreateCube("c1", 2.0)
    assert one("MOVE Joints ABS p 0 0 0 0 0 0") == one("move joints absolute p 0 0 0 0 0 0")
    assert one("move_joints_absolute p 0 0 0 0 0 0") == one("move joints absolute p 0 0 0 0 0 0")
    assert one("set_speed p 0.3 rad/s") == simc.SetSpeed("p", 0.3)
    assert one("sim_time") == simc.SimTime()
    assert one("simulate playback dt 1 ms realtime") == simc.Simulate("playback", 0.001, True)
    assert one("simulate dt 0.02") == simc.Simulate("path", 0.02)
    assert one("simulate") == simc.Simulate()
    assert one("show") == cmd.Show()
    assert one("show detail") == cmd.Show(None, True)
    assert one("show block cube1 detail") == cmd.Show(("block", "cube1"), True)
    assert one("list") == cmd.ListEntities()
    assert one("list object") == cmd.ListEntities("object")
    assert one("modify cube1 colour none") == cmd.SetColour("cube1", None)
    assert one("modify cube1 movable no") == cmd.SetMovable("cube1", False)
    assert one("cell example pick") == cellc.ExampleCell("pick-place")
    assert one("help move joints") == Meta("help", ("move", "joints"))
    assert list(parse_line("")) == list(parse_line("   # nothing")) == []


def test_every_commands_help_example_parses_to_a_command():
    count = 0
    for path, leaf in leaves(TREE):
        if not leaf.syntax:
            continue
        assert leaf.summary, path
        assert leaf.example, path
        assert path[0] == leaf.example.split()[0] or path[0] in ("help", "quit", "exit"), path
        (_c,) = parse_line(leaf.example)
        count += 1
    assert count >= 60


@pytest.mark.parametrize(
    ("line", "column", "expected", "reason"),
    [
        ("creat blok x", 7, ["surface", "block", "cube"], "unexpected 'blok'"),
        ("mo", 1, ["modify", "mode", "move"], "ambiguous"),
        ("speed puma", 12, ["<speed (deg/s)>"], "incomplete"),
        ("create box b size 1 2", 23, ["<x y z (m)>"], "got 2"),
        ("wait 3 deg", 8, ["ms", "s"], "unit 'deg'"),
        ("move joints absolute p 0 0 0 0 0 90 mm", 37, ["deg", "rad"], "unit 'mm'"),
        ("create cube c size 1 2", 22, ["colour", "end of command"], "unexpected '2'"),
        ("create cylinder c radius 1 height 1 facets 2.5", 44, [], "not a whole number"),
        ("create cube c size 1 size 2", 22, ["colour"], "'size' given twice"),
        ("simulate fast", 10, ["stop", "path", "dt"], "unexpected 'fast'"),
    ],
)
def test_syntax_errors_point_at_the_token_and_list_what_is_valid(line, column, expected, reason):
    with pytest.raises(CommandSyntaxError) as e:
        parse_line(line)
    err = e.value
    assert err.column == column
    assert reason in err.reason
    for w in expected:
        assert w in err.expected
    caret = str(err).splitlines()[-1]
    assert caret.index("^") - 2 == column - 1  # the caret under the column
    assert isinstance(err, ProgramError)


def test_with_a_session_names_are_checked_where_they_are_typed():
    s = Session()
    s.execute(sol.CreateCube("cube1", 1.0))
    s.execute(cellc.ExampleCell("joints"))  # the cell's model replaces the empty one
    with pytest.raises(CommandSyntaxError) as e:
        list(parse_line("move joints absolute pume 0 0 0 0 0 0", s))
    assert (e.value.column, e.value.expected) == (22, ["puma"])
    assert "unknown robot 'pume'" in str(e.value)
    s2 = Session()
    s2.execute(sol.CreateCube("cube1", 1.0))
    with pytest.raises(CommandSyntaxError, match="unknown entity 'cub'") as e:
        list(parse_line("properties cub", s2))
    assert "cube1" in e.value.expected
    with pytest.raises(CommandSyntaxError, match="unknown relation 'ts9'"):
        list(parse_line("detach cube1 ts9", s2))
    assert list(parse_line("detach cube1 ts6", s2)) == [cmd.Detach("cube1", "ts6")]


def test_on_a_line_each_command_is_checked_when_it_runs():
    """Names made by the commands before it on a ';' line are known (docs/program.md's
    Python example); a syntax error anywhere on the line still stops it before anything runs."""
    s = Session()
    results = [s.execute(c) for c in parse_line("create cube c1 size 40 mm; properties c1", s)]
    assert results[0] == "c1"
    assert results[1]["volume"] == pytest.approx(0.04**3, rel=1e-12)
    s2 = Session()
    with pytest.raises(CommandSyntaxError, match="column 28"):
        parse_line("create cube c1 size 40 mm; propertys c1", s2)
    assert s2.model.list("block") == []  # nothing ran
    commands = parse_line("create cube c1 size 40 mm; properties c2", s2)
    s2.execute(next(commands))
    with pytest.raises(CommandSyntaxError, match="unknown entity 'c2'"):
        next(commands)
    assert s2.model.list("block") == ["c1"]  # the first command ran, the second was refused


def test_completion_offers_keywords_names_and_relations():
    s = Session()
    s.execute(sol.CreateCube("cube1", 1.0))
    s.execute(cmd.CreateEntity("object", "thing"))
    assert complete("cr")[0] == ["create"]
    assert complete("create cu") == (["cube"], 2)
    assert complete("help mo")[0] == ["modify", "mode", "move"]
    words, n = complete("attach cu", s)
    assert set(words) == {"cube1", "cube1.square"}
    assert n == 2
    assert set(complete("attach cube1 to ", s)[0]) == {*LEVELS, "cube1", "thing"}
    assert complete("detach cube1 ts", s)[0] == [f"ts{i}" for i in range(1, 7)]
    assert complete("remove block ", s)[0] == ["cube1"]
    assert complete("create surface x rectangle 1 1 ")[0] == ["centered", "colour"]
    assert "config" in complete("move end_effector p ")[0]
    assert complete("list; sh")[0] == ["show"]
    assert complete('save "unfinished')[0] == []
    assert complete("frobnicate ")[0] == []
    s.execute(cellc.ExampleCell("joints"))
    assert complete("move joints absolute ", s)[0] == ["puma"]


def test_help_lists_every_command_and_says_the_units():
    text = help_text()
    assert "degrees" in text
    assert "metres" in text
    for word in ("create", "attach", "move end_effector", "close gripper", "simulate"):
        assert word in text
    one_ = help_text(("mo", "j"))
    assert "move joints absolute ROBOT" in one_
    assert "example: move joints" in one_
    assert "create" not in one_.split("Units:")[0]
    assert "no command starts with" in help_text(("frob",))


def test_a_robot_without_named_poses_says_so_in_words():
    # the user's step: `move joints absolute r home` for a robot that has no named poses
    # (read "valid here: none: no pose:robot yet" before)
    from dataclasses import replace

    from workcell import Workcell
    from workcell.robots import get

    s = Session()
    s.cell = Workcell("c")
    s.cell.add_robot("r", replace(get("puma260"), poses={}))
    with pytest.raises(CommandSyntaxError) as info:
        list(parse_line("move joints absolute r home", s))
    first = str(info.value).splitlines()[0]
    assert first.endswith(
        "unknown pose name 'home'; valid here: none (robot 'r' has no named poses)"
    )
    s.cell = Workcell("empty")
    with pytest.raises(CommandSyntaxError) as info:
        list(parse_line("move joints absolute r home", s))
    assert (
        str(info.value)
        .splitlines()[0]
        .endswith("unknown robot 'r'; valid here: none (no robot yet)")
    )
