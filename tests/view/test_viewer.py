"""The live view without a browser: pacing against the wall clock, no slowdown without a
page, pause, end states only, scrubbing, teach lines, the CLI."""

from __future__ import annotations

import functools
import subprocess
import sys
import threading
import time

import mujoco
import numpy as np
import pytest

from workcell.examples import thesis_pick_place
from workcell.program.interpreter import Interpreter
from workcell.program.session import Session
from workcell.sim import Simulator
from workcell.view import Viewer
from workcell.view.program import teach_line


@functools.cache
def _cell():
    return thesis_pick_place.build()


def new_sim() -> Simulator:
    return Simulator(_cell(), dt=0.01)


def move_by(sim: Simulator, rad: float) -> None:
    """A joint-6 move of ``rad`` at the cell's 0.3 rad/s: rad / 0.3 s of simulated time."""
    sim.move_joints_absolute("puma", sim.joints("puma") + np.array([0, 0, 0, 0, 0, rad]))


def timed(f) -> float:
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


def test_no_page_never_slows_the_program():
    sim = new_sim()
    with Viewer(sim, speed=1.0) as v:
        wall = timed(lambda: move_by(sim, 0.6))  # 2 s of simulated time
        assert sim.sim_time == pytest.approx(2.0, abs=1e-12)
        assert wall < 0.5, wall
        assert v.pushes <= 2  # the pictures at attach, nothing per frame


def test_pacing_follows_speed_with_a_page():
    """With a page open (counted as one), a 1.5 s move takes 1.5 / speed s of wall time;
    with speed None it takes no longer than without a viewer."""
    for speed, expect in ((1.0, 1.5), (3.0, 0.5)):
        sim = new_sim()
        with Viewer(sim, speed=speed) as v:
            v._clients = 1
            wall = timed(lambda sim=sim: move_by(sim, 0.45))
            assert expect * 0.97 < wall < expect + 0.4, (speed, wall)
            assert v.pushes > 10
    sim = new_sim()
    with Viewer(sim, speed=None) as v:
        v._clients = 1
        n = v.pushes
        wall = timed(lambda: move_by(sim, 0.45))
        assert wall < 0.4
        assert v.pushes - n <= 2  # the command's end state (its event)


def test_pause_holds_the_program_until_resumed():
    sim = new_sim()
    with Viewer(sim, speed=None) as v:
        v._clients = 1
        v.set_paused(True)
        worker = threading.Thread(target=move_by, args=(sim, 0.3))
        worker.start()
        time.sleep(0.6)
        assert worker.is_alive()
        assert sim.frames == 1  # the initial frame: nothing of the move yet
        v.set_paused(False)
        worker.join(5)
        assert not worker.is_alive()
        assert sim.sim_time == pytest.approx(1.0, abs=1e-12)


def test_a_closed_page_releases_a_pause():
    sim = new_sim()
    with Viewer(sim, speed=None) as v:
        v._clients = 1
        v.set_paused(True)
        worker = threading.Thread(target=move_by, args=(sim, 0.3))
        worker.start()
        time.sleep(0.3)
        v._disconnected(None)
        worker.join(5)
        assert not worker.is_alive()


def test_show_frame_poses_the_scene_and_leaves_the_simulator():
    sim = new_sim()
    with Viewer(sim, speed=None) as v:
        move_by(sim, 0.6)
        qpos = sim.data.qpos.copy()
        k = 57
        v.show_frame(k)
        d = mujoco.MjData(sim.model)
        d.qpos[:] = sim.timeline.frame(k)[2]
        mujoco.mj_kinematics(sim.model, d)
        for b, frame in v.scene.frames.items():
            np.testing.assert_allclose(frame.position, d.xpos[b], atol=1e-12)
        assert int(v.timeline_panel.slider.value) == k
        np.testing.assert_array_equal(sim.data.qpos, qpos)
        with pytest.raises(Exception, match="frame must be"):
            v.show_frame(sim.frames)


def test_teach_lines_move_back_to_the_taught_pose():
    """The joint line and the linear line of a taught pose, run through the command
    language from elsewhere, end at that pose (joints to 1e-9 rad, tool to 1e-6 m)."""
    sim = new_sim()
    q = np.radians([25.0, 15.0, -100.0, 10.0, 60.0, -20.0])
    sim.jog("puma", q)
    T = sim.tool_pose("puma")
    joints, linear = teach_line(sim, "puma", "p1"), teach_line(sim, "puma", "p2", "linear")
    assert joints.startswith("# p1: puma tool at")
    interp = Interpreter(Session(sim=sim), lambda s: None)
    sim.jog("puma", np.radians([0.0, 10.0, -80.0, 0.0, 70.0, 0.0]))
    interp.run_line(joints.splitlines()[1])
    np.testing.assert_allclose(sim.joints("puma"), q, atol=1e-9)
    sim.jog("puma", q + np.radians([3.0, 2.0, -2.0, 1.0, 2.0, -3.0]))
    interp.run_line(linear.splitlines()[1])
    np.testing.assert_allclose(sim.tool_pose("puma"), T, atol=1e-6)


def test_workcell_view_runs_a_program_and_prints_the_url(tmp_path):
    prog = tmp_path / "p.wcl"
    prog.write_text("move joints relative puma 10 0 0 0 0 0\ntime\n")
    cmd = [sys.executable, "-m", "workcell.cli", "view", "pick-place", "--program", str(prog),
           "--no-wait", "--speed", "0"]  # fmt: skip
    child = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, cwd=tmp_path)
    try:
        url = child.stdout.readline()
        assert url.startswith("live view: http://127.0.0.1:")
        lines = [child.stdout.readline() for _ in range(2)]
        assert any(line.startswith("program done: t = 0.5818") for line in lines), lines
    finally:
        child.terminate()
        child.wait(10)


def test_workcell_view_serves_a_recording_in_rerun_web_viewer(tmp_path):
    from workcell.record import record

    sim = new_sim()
    move_by(sim, 0.3)
    record(sim, tmp_path / "run.rrd")
    cmd = [sys.executable, "-m", "workcell.cli", "view", "run.rrd"]
    child = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, cwd=tmp_path)
    try:
        line = child.stdout.readline()
        assert line.startswith("recording in the web viewer: http://127.0.0.1:")
        url = line.split()[5]
        assert url.endswith("&renderer=webgl")
        import urllib.request

        for _ in range(100):  # rerun's web server starts
            try:
                with urllib.request.urlopen(url, timeout=5) as r:
                    assert r.status == 200
                    break
            except OSError:
                time.sleep(0.1)
        else:
            raise AssertionError("rerun's web viewer did not answer")
    finally:
        child.terminate()
        assert child.wait(10) == 0


def test_a_followed_session_is_shown_and_a_read_only_page_changes_nothing():
    """The viewer follows a command-language session (the shell's, a server's): the
    simulator that 'simulate' starts is the one shown; with control=False (the server's
    default) the page's jog inputs are refused."""
    session = Session()
    with Viewer(None, speed=None, control=False) as v:
        v.follow(session)
        interp = Interpreter(session, lambda s: None)
        interp.run_line("cell example pick-place")
        assert v.sim is None
        interp.run_line("simulate path dt 0.01")
        assert v.sim is session.sim
        interp.run_line("move joints relative puma 10 0 0 0 0 0")
        assert v.sim.frames > 1
        q = v.sim.joints("puma")

        class Event:
            client = object()

        v.notify = lambda *a, **k: None
        v.jog.inputs["puma"][0].value = 50.0  # as if typed on the page
        v.jog._typed("puma", Event())
        np.testing.assert_array_equal(v.sim.joints("puma"), q)
