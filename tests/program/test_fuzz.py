"""Fuzzing the language: any input gives commands or a WorkcellError, never another
exception, and a command that fails changes nothing."""

from __future__ import annotations

import functools

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from program_helpers import snapshot

from workcell import WorkcellError
from workcell.program import Command, Session
from workcell.program import cellcommands as cellc
from workcell.program import commands as cmd
from workcell.program import simcommands as simc
from workcell.program import solidcommands as sol
from workcell.program.keytree import Keys, Node, Options, Seq, continuations
from workcell.program.language import TREE, Meta, complete, parse_line
from workcell.program.lexer import tokenize
from workcell.program.params import Choice

# properties of a flat surface (zero volume) have no centroid: trimesh warns while dividing
pytestmark = pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")


def _keywords(node: Node, seen: set[int], out: set[str]) -> None:
    if id(node) in seen:
        return
    seen.add(id(node))
    if isinstance(node, (Keys, Options)):
        out.update(node.branches)
        for n in node.branches.values():
            _keywords(n, seen, out)
        for n in (getattr(node, "other", None), getattr(node, "empty", None)):
            if n is not None:
                _keywords(n, seen, out)
    elif isinstance(node, Seq):
        for n in node.nodes:
            _keywords(n, seen, out)
    elif isinstance(node, Choice):
        out.update(node.options)


@functools.cache
def vocabulary() -> list[str]:
    words: set[str] = set()
    _keywords(TREE, set(), words)
    words -= {"realtime"}  # real-time replays would make the fuzz test sleep
    names = ["cube", "cube1", "square1", "puma", "stage_1", "table", "ts1", "tb1", "face1",
             "cube_block", "cube_block.square", "new1", "x", "o1"]  # fmt: skip
    numbers = ["-90", "-1", "0", "0.5", "1", "2", "3", "45", "90", "1e9", "1e308", "100mm",
               "90deg", "1.5rad", "0.3rad/s", "2e", "-", ".", "1..2"]  # fmt: skip
    units = ["deg", "rad", "m", "mm", "s", "ms", "deg/s", "rad/s", "°"]
    junk = [";", "#", '"', '"a b"', "(", ")", ",", "[", "é", "\t", "\\", "🙂", "-x", ""]
    return sorted(words) + names + numbers + units + junk


GUIDED_NUMBERS = [
    "-90",
    "-30",
    "-1",
    "0",
    "0.01",
    "0.05",
    "0.1",
    "0.3",
    "1",
    "2",
    "10",
    "45",
    "1e9",
]
GUIDED_NAMES = ["n1", "n2", "x.y", "bad name", "a/b"]


def grow_line(session: Session, picks: list[int]) -> str:
    """A line grown word by word from what the key tree says may come next (with the
    session's names), each word chosen by the next of ``picks``, with a random word now
    and then: mostly valid commands, with values that may well be refused. (Hypothesis
    draws only ``picks``: the choices offered depend on the session's state.)"""
    words: list[str] = []
    vocab = vocabulary()
    for pick in picks:
        p = (pick * 2654435761 + 12345) % 2**32  # spread hypothesis's favourite small ints
        try:
            tokens = tokenize(" ".join(words))
        except WorkcellError:  # an open string: the line is complete (and wrong)
            break
        expected = continuations(TREE, tokens, session)
        if words and (not expected or (p % 3 == 0 and _complete(words))):
            break  # a whole command
        if not expected or p % 25 == 0:
            words.append(vocab[p % len(vocab)])
            continue
        choice = expected[p % len(expected)]
        if choice.startswith("<"):
            pool = GUIDED_NAMES if "name" in choice or "file" in choice else GUIDED_NUMBERS
            choice = pool[p % len(pool)]
        words.append(choice)
    return " ".join(words)


def _complete(words: list[str]) -> bool:
    try:
        parse_line(" ".join(words))
    except WorkcellError:
        return False
    return True


def fuzz_session(base_dir) -> Session:
    s = Session(base_dir=base_dir)
    s.execute(cellc.ExampleCell("pick-place"))
    s.execute(cmd.CreateSurface("square1", ((0, 0), (1, 0), (1, 1), (0, 1))))
    s.execute(cmd.CreateEntity("block", "cube1"))
    s.execute(cmd.Attach("cube1", "square1", None, "face1"))
    s.execute(cmd.CreateEntity("object", "o1"))
    s.execute(sol.CreateBox("spare", (0.1, 0.1, 0.1)))
    s.execute(simc.Simulate("path", 0.05))
    s.execute(simc.SetPlanning(time_limit=0.5))  # a failing search gives up soon
    return s


def too_slow(c: object) -> bool:
    """Commands that are valid but would make later moves take minutes (a speed of a
    fraction of a degree per second, a fine sampling interval, a line sampled every few
    micrometres) or would replay the run in real time (after a 'wait 1e6', for days): the
    fuzz test skips them; they are no different in kind from others."""
    return (
        (isinstance(c, simc.SetSpeed) and c.speed < 0.1)
        or (isinstance(c, simc.Simulate) and (c.dt < 0.01 or c.realtime))
        or (isinstance(c, simc.Play) and c.realtime)
        or (isinstance(c, simc.MoveStraightLine) and c.step < 1e-3)
        or (isinstance(c, simc.SetPlanning) and (c.time_limit or 0) > 0.5)
    )


def run_checked(session: Session, line: str) -> None:
    """Parse and run ``line``; every failure is a WorkcellError and changes nothing."""
    try:
        commands = parse_line(line, session)
    except WorkcellError:
        return
    while True:
        try:  # each command's names are checked when it is taken, after the ones before ran
            c = next(commands, None)
        except WorkcellError:
            return
        if c is None:
            return
        if isinstance(c, Meta) or too_slow(c):  # help and quit belong to the shell
            continue
        before = snapshot(session)
        try:
            session.execute(c)
        except WorkcellError:
            assert snapshot(session) == before, f"failed command {c} changed the session"


SETTINGS = settings(
    max_examples=400,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


@pytest.fixture(scope="module")
def shared(tmp_path_factory):
    """One session the fuzz lines run on one after another (state accumulates)."""
    return fuzz_session(tmp_path_factory.mktemp("fuzz"))


@given(st.text(max_size=80))
@settings(max_examples=300, deadline=None)
def test_any_text_parses_or_raises_a_workcell_error(text):
    try:
        out = list(parse_line(text))
    except WorkcellError:
        return
    assert all(isinstance(c, (Command, Meta)) for c in out)
    complete(text)  # completion never raises either


@given(st.lists(st.sampled_from(vocabulary()), min_size=1, max_size=12))
@SETTINGS
def test_token_soup_runs_or_fails_cleanly_without_changing_anything(shared, words):
    line = " ".join(words)
    run_checked(shared, line)
    complete(line, shared)
    complete(line + " ", shared)


@given(st.lists(st.integers(0, 2**20), min_size=1, max_size=16))
@SETTINGS
def test_grammar_guided_lines_run_or_fail_cleanly_without_changing_anything(shared, picks):
    run_checked(shared, grow_line(shared, picks))


@given(
    st.lists(
        st.sampled_from(
            [
                "move joints relative puma 10 0 0 0 0 0",
                "move joints absolute puma 0 0 -90 0 90 0",
                "move joints absolute puma 0 0 0 0 0 400",
                "move end_effector puma at cube offset 0 0 0.1 down config ru",
                "move straight puma at cube down",
                "move end_effector puma at 5 5 5",
                "close gripper puma",
                "open gripper puma",
                "speed puma 30",
                "speed puma 1e9",
                "mode playback",
                "mode path",
                "wait 0.1",
                "wait -1",
                "remove cube_block",
                "cell remove cube",
                "simulate stop",
                "simulate dt 0.05",
                "add robot puma_2 translate 1 0 0",
                "create cube c9 size 0.1",
                "remove c9",
                "modify cube_block name other",
                "clearance puma table",
                "held puma",
            ]
        ),
        min_size=1,
        max_size=8,
    )
)
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_sequences_of_valid_commands_keep_the_failure_rule(tmp_path_factory, lines):
    s = fuzz_session(tmp_path_factory.mktemp("seq"))
    for line in lines:
        run_checked(s, line)
