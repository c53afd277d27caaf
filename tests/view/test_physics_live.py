"""The live view shows a physics replay (``run_physics``) as it runs: its frames in
order, paced at ``speed``, the run's collisions red, and its settled end state marked
as the physics run's. References: the physics result's own recorded frames (MuJoCo's
forward kinematics of them) and the run's collision events."""

from __future__ import annotations

import time

import mujoco
import numpy as np
import pytest

from workcell.examples import thesis_pick_place as pp
from workcell.sim.physics import run_physics
from workcell.view import Viewer
from workcell.view import viewer as viewer_module

DT = 0.02  # s: the kinematic sampling


def spy(v: Viewer) -> list[tuple[dict[str, np.ndarray], set[str]]]:
    """Record what each picture shows: every moving body's position (m, world) and the
    things drawn red."""
    shown: list[tuple[dict[str, np.ndarray], set[str]]] = []
    scene = v.scene
    assert scene is not None
    inner = scene.show

    def show(data, contacts=None):
        inner(data, contacts)
        names = {scene.model.body(b).name: data.xpos[b].copy() for b in scene.moving}
        shown.append((names, scene.red))

    scene.show = show  # type: ignore[method-assign]
    return shown


def test_a_physics_replay_is_shown_frame_by_frame_and_ends_on_its_settled_state(monkeypatch):
    monkeypatch.setattr(viewer_module, "_END_STATE_INTERVAL", 0.0)  # every frame a picture
    sim = pp.run("path", DT)
    with Viewer(sim, speed=None) as v:
        v._clients = 1  # a page open (counted)
        times: list[float] = []
        sim.physics_listeners.append(lambda t, d, pairs, last: times.append(t))
        shown = spy(v)
        n0 = v.pushes
        result = run_physics(sim, settle=0.2)
        assert v.pushes - n0 == len(times) == len(result.timeline)  # one per recorded frame
        assert np.all(np.diff(times) > 0)
        # each picture is the physics result's frame of that time (MuJoCo's kinematics)
        m, d = sim.model, mujoco.MjData(sim.model)
        for k in (0, len(times) // 2, len(times) - 1):
            d.qpos[:] = result.timeline.frame(k)[2]
            mujoco.mj_kinematics(m, d)
            for name, pos in shown[k][0].items():
                np.testing.assert_allclose(pos, d.xpos[m.body(name).id], atol=1e-9)
        assert "physics replay" in v.status.content
        assert "its end state" in v.status.content
        assert f"t = {times[-1]:.3f} s" in v.status.content
        # the next command's picture is the simulator's again
        v.refresh()
        assert "physics" not in v.status.content


def test_the_runs_collisions_are_red_at_their_frames(monkeypatch):
    monkeypatch.setattr(viewer_module, "_END_STATE_INTERVAL", 0.0)
    # joint by joint, the return home dips a finger into the table (tests/sim/test_physics)
    sim = pp.run("joint-by-joint", DT, joint_by_joint_clock="sequential")
    with Viewer(sim, speed=None) as v:
        v._clients = 1
        pairs_at: list[set[str]] = []
        sim.physics_listeners.insert(
            0, lambda t, d, pairs, last: pairs_at.append({x for p in pairs for x in p})
        )
        shown = spy(v)
        result = run_physics(sim, settle=0.1)
        hits = [e for e in result.events if e.kind == "collision" and "with table" in e.detail]
        assert len(hits) == 1
        red = [k for k, (_, r) in enumerate(shown) if r]
        assert red, "no picture showed the collision"
        for k, (_, r) in enumerate(shown):
            assert r == pairs_at[k], k  # red: what the run counted at that frame (any depth)
        assert any({"puma.gripper.right", "table"} <= shown[k][1] for k in red)
        assert not shown[-1][1]  # the settled end state: nothing red


def test_a_replay_is_paced_at_speed_with_a_page_and_free_without():
    sim = pp.run("path", DT)
    result = run_physics(sim, settle=0.2)
    span = result.timeline.sim_times()[-1]
    with Viewer(sim, speed=None) as v:  # no page: no pictures, no waiting
        n0 = v.pushes
        t0 = time.perf_counter()
        run_physics(sim, settle=0.2)
        free = time.perf_counter() - t0
        assert v.pushes == n0
    with Viewer(sim, speed=span / 1.0) as v:  # the whole replay in about 1 s of wall time
        v._clients = 1
        t0 = time.perf_counter()
        run_physics(sim, settle=0.2)
        wall = time.perf_counter() - t0
    assert wall >= 0.97, wall
    assert wall < max(free, 1.0) + 0.6, (wall, free)
    assert span == pytest.approx(sim.sim_time + 0.2, abs=0.01)
