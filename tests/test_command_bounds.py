"""Issue 19, item 4: single commands whose work or memory scaled with a number the user
gives, each performed as the issue found it.

``move_straight_line`` at a 5e-8 m step (76 s, 2.5 GB), ``trajectory`` of a long timeline
over the protocol (the reply built whole before the bound was checked), ``study
--sample 50000000`` (a MemoryError), ``--workers`` in the thousands, ``--record-fps 1e6``
(a 74.5 GiB allocation), ``run --render`` of a 3,000-move script (no tile cap), a 10 MB
``.wcl`` line (88 s). Each is now refused before the work by the one budget
(:mod:`workcell.limits`), or (the recording) done in time and memory proportional to the
run; replies are bounded while they are encoded. The 250 MB STL: tests/test_special_files.py."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_limits import refused

from workcell import limits
from workcell.errors import ProtocolError
from workcell.examples import thesis_joints
from workcell.program.protocol import ReplyTooLargeError, encode, encode_bounded
from workcell.sim import Simulator


@pytest.fixture
def sim():
    return Simulator(thesis_joints.build(), dt=0.01, check_collisions=False)


def state(s: Simulator) -> tuple:
    return s.sim_time, s.frames, len(s.events), tuple(s.joints("puma"))


# ------------------------------------------------------------------ IK samples
def test_a_line_at_a_5e_8_m_step_is_refused_before_any_ik(sim, monkeypatch):
    from workcell.sim import cartesian

    T = sim.tool_pose("puma")
    T[:3, 3] += [0.0, 0.0, -0.09]  # 0.09 m at 5e-8 m: 1,800,000 samples (frames allow it)
    before = state(sim)
    monkeypatch.setattr(cartesian, "path_joints", lambda *a, **k: pytest.fail("IK ran"))
    e = refused(lambda: sim.move_straight_line("puma", T, step=5e-8), "max_path_samples")
    assert "1,800,000 samples" in str(e)
    assert state(sim) == before
    sim.set_profile("jerk")  # the line timed by toppra: the same samples first
    before = state(sim)
    refused(lambda: sim.move_straight_line("puma", T, step=5e-8), "max_path_samples")
    assert state(sim) == before


# ------------------------------------------------------------------ replies
def test_trajectory_over_the_protocol_is_refused_before_it_is_built(tmp_path, monkeypatch):
    from workcell.client import Client
    from workcell.program.server import Server
    from workcell.sim.readback import ReadBack

    srv = Server(root=tmp_path)
    srv.serve_in_thread()
    try:
        with Client(port=srv.port, timeout=60) as c:
            c.call("example_cell", name="joints")
            c.call("simulate", mode="path", dt=1e-5)
            c.call("move_joints_relative", robot="puma", dq=[0.5, 0, 0, 0, 0, 0])
            frames = c.call("frames")
            assert frames * 7 * 2 > 1 << 20  # 7 numbers a frame: over the bound for sure
            monkeypatch.setattr(ReadBack, "trajectory", lambda *a: pytest.fail("built"))
            with pytest.raises(ProtocolError, match="nothing was built"):
                c.call("trajectory", robot="puma")
            assert c.call("frames") == frames  # the connection goes on
    finally:
        srv.stop()


def test_a_reply_is_encoded_only_up_to_the_bound():
    big = {"id": 1, "result": {"q": np.zeros((20_000_000 // 64, 7))}}  # 17 MB as JSON
    with pytest.raises(ReplyTooLargeError) as info:
        encode_bounded(big, 1 << 20)
    assert info.value.size <= (1 << 20) + 4096 * 24  # stopped within a chunk of the bound


json_values = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(10**20), 10**20)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=8),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=4), inner, max_size=4)
    ),
    max_leaves=20,
)


@settings(max_examples=100, deadline=None)
@given(json_values, st.integers(0, 3), st.integers(1, 9000))
def test_the_bounded_encoder_writes_exactly_what_encode_writes(value, ndim, n):
    arrays = {0: np.float64(1.5), 1: np.linspace(0, 1, n), 2: np.ones((n, 3)) / 3}
    msg = {"id": "x", "result": {"v": value, "a": arrays.get(ndim, np.arange(n) - 7)}}
    assert encode_bounded(msg, 1 << 30) == encode(msg)
    json.loads(encode(msg))


# ------------------------------------------------------------------ studies
def test_a_study_sample_of_50_million_is_refused_before_any_candidate_is_drawn():
    from workcell.study import Study

    e = refused(
        lambda: Study(cell="pick-place", vary={"puma.base.x": "0:0.1"}, sample=50_000_000),
        "max_candidates",
    )
    assert "50,000,000 candidates" in str(e)
    refused(
        lambda: Study(
            cell="pick-place", vary={"puma.base.x": "0:1:1001", "puma.base.y": "0:1:1001"}
        ),
        "max_candidates",
    )


def test_thousands_of_worker_processes_are_refused_before_any_starts():
    from workcell.study.backends import backend

    refused(lambda: backend("process", workers=10_000), "max_workers")
    refused(lambda: backend("ray", workers=10_000), "max_workers")  # a local Ray instance
    backend("ray", workers=10_000, address="auto")  # a cluster's own CPUs: not started here


# ------------------------------------------------------------------ recordings
def test_a_recording_at_a_million_frames_a_second_costs_no_more_than_the_frames():
    from workcell.record.rerun_log import kept_frames

    times = np.array([0.0, 5.0, 10_000.0])  # a 10^4 s run: 10^10 samples at 1e6 fps
    assert kept_frames(times, 1e6).tolist() == [True, True, True]  # was a 74.5 GiB array


def _kept_by_samples(times: np.ndarray, fps: float) -> np.ndarray:
    """The sampling rule itself, sample by sample (the reference): the first frame at or
    after each multiple of 1/fps, and the first and last frames."""
    keep = np.zeros(len(times), dtype=bool)
    for j in range(math.floor((times[-1] - times[0]) * fps + 1e-9) + 1):
        s = times[0] + j / fps
        keep[min(int(np.searchsorted(times, s - 1e-9, side="left")), len(times) - 1)] = True
    keep[[0, -1]] = True
    return keep


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(0.001, 1.0), min_size=1, max_size=40),
    st.floats(0.5, 200.0),
)
def test_dense_recordings_keep_the_frames_the_samples_hit(gaps, fps):
    from workcell.record.rerun_log import kept_frames

    times = np.concatenate([[0.0], np.cumsum(gaps)])
    expected = _kept_by_samples(times, fps)
    assert kept_frames(times, fps).tolist() == expected.tolist()


# ------------------------------------------------------------------ pictures
def test_a_contact_sheet_of_3000_moves_is_refused_before_rendering(sim, tmp_path, monkeypatch):
    from workcell.record import render, sheets

    for k in range(1500):  # 3,000 commands, each a key frame at its start and end
        sim.move_joints_relative("puma", [0.001 * (-1) ** k, 0, 0, 0, 0, 0])
    monkeypatch.setattr(render.CellRenderer, "__init__", lambda *a, **k: pytest.fail("rendered"))
    monkeypatch.setattr(sheets, "CellRenderer", render.CellRenderer)
    e = refused(lambda: sheets.contact_sheet(sim, tmp_path / "s.png"), "max_pixels")
    assert "tiles of 320 x 240" in str(e)
    assert not (tmp_path / "s.png").exists()


def test_a_video_of_a_long_run_at_a_high_rate_is_refused_before_rendering(sim, tmp_path):
    from workcell.record.sheets import video_frames

    sim.wait(1000.0)
    refused(lambda: video_frames(sim, 1000.0), "max_images")  # 10^6 pictures
    assert len(video_frames(sim, 1.0)) == 1001


# ------------------------------------------------------------------ command lines
def test_a_10_mb_line_is_refused_before_it_is_parsed(tmp_path, capsys):
    from workcell.cli import main

    script = tmp_path / "long.wcl"
    script.write_text("create box b size " + " ".join(["1"] * (5 << 20)) + "\n")  # 10 MB
    assert main(["run", str(script)]) != 0
    err = capsys.readouterr().err
    assert "over the limit max_line_chars = 65,536 characters" in err
    assert len(err) < 2000  # the line is not echoed


def test_a_syntax_error_in_a_long_line_shows_a_window_around_it():
    from workcell.errors import ProgramError
    from workcell.program.language import parse_line

    line = "create box b size 1 1 1 " + "1 " * 20_000
    with pytest.raises(ProgramError) as info:
        list(parse_line(line))
    text = str(info.value)
    assert len(text) < 600
    shown, caret = text.splitlines()[-2:]
    assert shown.strip().startswith("create box b size 1 1 1 1")
    assert caret.index("^") == shown.index("1 1 1 1") + 6  # under the 4th number


def test_the_new_limits_are_documented_and_can_be_raised():
    with limits.using(max_line_chars=10_000_000, max_path_samples=10**7):
        assert limits.current().max_line_chars == 10_000_000
    assert limits.current().max_line_chars == 65_536
    assert math.isclose(limits.DEFAULTS.max_pixels * 3 / 1e6, 150.0)
