"""Errors in robot programs: every reader error names the file, the line and the column
of what is wrong and says what; unsupported constructs say that they are not supported;
a fuzz test mutates valid programs: each gives a clean error at a place or a valid run,
never another exception."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from workcell import Workcell
from workcell.errors import ProgramError, WorkcellError
from workcell.robotprog import load
from workcell.sim import Simulator
from workcell.spatial import translation

PROGRAMS = Path(__file__).parent / "programs"
ROBOT = {
    ".src": "kuka_kr6_r700",
    ".mod": "abb_irb140",
    ".script": "ur5e",
    ".ls": "fanuc_lrmate200id",
}
LS_HEAD = "/PROG  T\n/ATTR\n/MN\n"


def _where(exc: BaseException) -> tuple[str, int, int]:
    m = re.match(r"^(.*):(\d+):(\d+): ", str(exc))
    assert m, f"no file:line:column in {exc}"
    return m.group(1), int(m.group(2)), int(m.group(3))


def _load_error(tmp_path: Path, name: str, text: str) -> ProgramError:
    path = tmp_path / name
    path.write_text(text)
    cell = Workcell("e")
    cell.add_robot("r", ROBOT[path.suffix], gripper=True)
    sim = Simulator(cell, profile="jerk", check_collisions=False)
    with pytest.raises(ProgramError) as info:
        load(path).run(sim, "r")
    f, _, _ = _where(info.value)
    assert f == str(path)
    return info.value


CASES = [
    # (file, text, line, column, words in the message)
    ("a.src", "DEF a( )\n  PTP {A1 0\nEND\n", 2, 12, "expected"),
    ("a.src", "DEF a( )\n  SPLINE\nEND\n", 2, 3, "not supported"),
    ("a.src", "DEF a( )\n  $TIMER[1] = 0\nEND\n", 2, 3, "$TIMER is not supported"),
    ("a.src", "DEF a( )\n  X = 1 @ 2\nEND\n", 2, 9, "unexpected character"),
    ("a.src", "DEF a( )\n  DECL INT I\n  I = I + 1\nEND\n", 3, 7, "before it has a value"),
    ("a.src", "DEF a( )\n  LIN XNOWHERE\nEND\n", 2, 7, "not declared"),
    ("a.src", "DEF a( )\n  FOR I = 1 TO 3\n  ENDWHILE\nEND\n", 3, 3, "unexpected ENDWHILE"),
    ("a.src", "DEF a( )\n  LOOP\n  ENDLOOP\nEND\n", 2, 3, "max_program_steps"),
    ("a.src", "DEF a( )\n  $VEL_AXIS[2] = 50\n  PTP {A1 10}\nEND\n", 3, 3, "differs between axes"),
    (
        "a.mod",
        "MODULE m\n  PROC main()\n    MoveL p1, v100, fine, tool0;\n  ENDPROC\nENDMODULE\n",
        3,
        11,
        "not declared",
    ),
    ("a.mod", "MODULE m\n  PROC main()\n    Stop;\n  ENDPROC\nENDMODULE\n", 3, 5, "not supported"),
    ("a.mod", "MODULE m\n  FUNC num f()\n  ENDFUNC\nENDMODULE\n", 2, 3, "not supported"),
    (
        "a.mod",
        "MODULE m\n  VAR robtarget p1;\n  PROC main()\n    MoveL Offs(p1, 1), v100, fine, tool0;\n  ENDPROC\nENDMODULE\n",
        4,
        11,
        "not supported",
    ),
    ("a.mod", "MODULE m\n  PROC main()\n    WaitTime 1\n  ENDPROC\nENDMODULE\n", 4, 3, "expected"),
    ("a.script", "def a():\n  movel(p[0, 0, 0.1, 0, 0], a=1)\nend\n", 2, 9, "a pose has 6 numbers"),
    ("a.script", "def a():\n  thread t():\n  end\nend\n", 2, 3, "not supported"),
    ("a.script", "def a():\n  movej([0, 0, 0, 0, 0, 0], t=2)\nend\n", 2, 3, "by time"),
    ("a.script", "def a():\n  x = y + 1\nend\n", 2, 7, "has no value"),
    (
        "a.script",
        "def a():\n  movec(p[0,0,0,0,0,0], p[0,0,0,0,0,0], mode=1)\nend\n",
        2,
        3,
        "mode=1",
    ),
    ("a.ls", LS_HEAD + "   1:  CALL SUB ;\n/POS\n/END\n", 4, 8, "not supported"),
    ("a.ls", LS_HEAD + "   1:  J P[7] 50% FINE ;\n/POS\n/END\n", 4, 10, "P[7] is not in /POS"),
    ("a.ls", LS_HEAD + "   1:  JMP LBL[3] ;\n/POS\n/END\n", 4, 8, "not defined"),
    (
        "a.ls",
        LS_HEAD
        + "   1:  UTOOL_NUM=1 ;\n   2:  L P[1] 100sec FINE ;\n/POS\nP[1]{\n GP1:\n UF : 0, UT : 1,\n"
        " X = 1 mm, Y = 2 mm, Z = 3 mm, W = 0 deg, P = 0 deg, R = 0 deg\n};\n/END\n",
        5,
        18,
        "not supported",
    ),
    (
        "a.ls",
        LS_HEAD + "   1:  UTOOL_NUM=1 ;\n   2:  L P[1] 100mm/sec FINE ;\n/POS\nP[1]{\n GP1:\n"
        " UF : 0, UT : 2,\n X = 1 mm, Y = 2 mm, Z = 3 mm, W = 0 deg, P = 0 deg, R = 0 deg\n};\n/END\n",
        5,
        8,
        "was taught in UF 0, UT 2",
    ),
    ("a.ls", LS_HEAD + "   1:  DO[1]=PULSE ;\n/POS\n/END\n", 4, 14, "not supported"),
    (
        "a.ls",
        LS_HEAD + "   1:  WAIT DI[1]=ON ;\n/POS\n/END\n",
        4,
        8,
        "the cell has no signal of that name",
    ),
    ("a.ls", LS_HEAD + "   1:  R[1]=1 \n/POS\n/END\n", 4, 14, "';'"),
    (
        "a.ls",
        LS_HEAD + "   1:  J P[1] 50% FINE ;\n/POS\nP[1]{\n GP1:\n UF : 0, UT : 0,\n"
        " X = 1 mm, Y = 2 mm, Z = 3 mm, W = 0 deg, P = 0 deg, R = 0 deg\n};\nP[1]{\n GP1:\n"
        " UF : 0, UT : 0,\n X = 1 mm, Y = 2 mm, Z = 3 mm, W = 0 deg, P = 0 deg, R = 0 deg\n};\n/END\n",
        11,
        1,
        "P[1] is defined twice",
    ),
    (
        "a.src",
        "DEF a( )\n  DECL INT X\n  X = 2\n  FOR I = 1 TO 3 STEP -X\n  ENDFOR\nEND\n",
        4,
        23,
        "STEP must be a constant number",
    ),
    ("a.src", "DEF a( )\n  $OV_PRO = 150\nEND\n", 2, 3, "it must be in (0, 100] %"),
]


def test_a_krl_loop_with_a_negative_step_counts_down(tmp_path: Path) -> None:
    """FOR I = 3 TO 1 STEP -1 runs I = 3, 2, 1: the axis 1 targets 30, 20, 10 deg."""
    path = tmp_path / "down.src"
    path.write_text(
        "DEF down( )\n  DECL INT I\n  FOR I = 3 TO 1 STEP -1\n"
        "    PTP {A1 10*I, A2 -90, A3 90, A4 0, A5 0, A6 0}\n  ENDFOR\nEND\n"
    )
    cell = Workcell("e")
    cell.add_robot("r", ROBOT[".src"], gripper=True)
    sim = Simulator(cell, profile="jerk", check_collisions=False)
    load(path).run(sim, "r")
    ends = [e.data["program"]["q"][0] for e in sim.events() if (e.data or {}).get("program")]
    assert np.degrees(ends) == pytest.approx([30, 20, 10], abs=1e-9)


@pytest.mark.parametrize(("name", "text", "line", "col", "words"), CASES)
def test_errors_name_file_line_and_column(
    tmp_path: Path, name: str, text: str, line: int, col: int, words: str
) -> None:
    exc = _load_error(tmp_path, name, text)
    _, got_line, got_col = _where(exc)
    assert (got_line, got_col) == (line, col), str(exc)
    assert words in str(exc)


def test_missing_file_and_unknown_language(tmp_path: Path) -> None:
    with pytest.raises(ProgramError, match="no robot program file"):
        load(tmp_path / "none.src")
    (tmp_path / "x.txt").write_text("x")
    with pytest.raises(ProgramError, match=r"\.script \(urscript\)"):
        load(tmp_path / "x.txt")
    with pytest.raises(ProgramError, match="unknown robot language 'cobol'"):
        load(tmp_path / "x.txt", language="cobol")


def _mutate(text: str, op: int, at: float, junk: str) -> str:
    i = int(at * len(text))
    if op == 0:  # delete a stretch
        return text[:i] + text[i + 1 + len(junk) :]
    if op == 1:  # insert junk
        return text[:i] + junk + text[i:]
    if op == 2:  # replace a character
        return text[:i] + (junk[:1] or "0") + text[i + 1 :]
    lines = text.split("\n")  # duplicate or drop a line
    k = int(at * len(lines)) % len(lines)
    return "\n".join(lines[: k + 1] + ([lines[k]] if op == 3 else []) + lines[k + 1 :])


SOURCES = sorted(p.name for p in PROGRAMS.iterdir() if p.suffix in ROBOT)


@settings(
    max_examples=120, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    st.sampled_from(SOURCES),
    st.integers(0, 4),
    st.floats(0.0, 0.999),
    st.sampled_from(
        [
            "",
            "9",
            "-",
            "(",
            "]",
            "{",
            ";",
            ":",
            "\n",
            "END",
            "99999",
            "1e308",
            "X",
            "FOR",
            "ENDIF",
            ",",
            "p[",
            "'",
            '"',
        ]
    ),
)
def test_fuzzed_programs_fail_cleanly_or_run(
    tmp_path: Path, name: str, op: int, at: float, junk: str
) -> None:
    folder = tmp_path / f"f{abs(hash((name, op, at, junk))) % 10**9}"
    folder.mkdir()
    src = PROGRAMS / name
    path = folder / name
    path.write_text(_mutate(src.read_text(), op, at, junk))
    if src.suffix == ".src":
        shutil.copy(PROGRAMS / "pick.dat", folder / "pick.dat")
    cell = Workcell("fuzz")
    cell.add_robot("r", ROBOT[src.suffix], base=translation(0.2, 0.1, 0.0))
    sim = Simulator(cell, profile="trapezoid" if src.suffix == ".script" else "jerk", dt=0.05,
                    check_collisions=False)  # fmt: skip
    try:
        load(path).run(sim, "r")
    except WorkcellError as exc:
        f, line, col = _where(exc)
        assert Path(f).name in (name, "pick.dat")
        assert line >= 1
        assert col >= 1
