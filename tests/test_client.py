"""workcell.client.Client is a drop-in Simulator: every public Simulator method and
property exists on it with the same parameters, and one program gives the same results
in-process and through ``workcell serve``."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

from workcell import ProgramError
from workcell.client import Client
from workcell.examples import thesis_pick_place as pp
from workcell.program.server import Server
from workcell.sim import Simulator
from workcell.sim.grasp import tool_down
from workcell.spatial import translation


def public(cls: type) -> dict[str, object]:
    return {n: inspect.getattr_static(cls, n) for n in dir(cls) if not n.startswith("_")}


def test_the_client_has_every_public_simulator_method_with_its_parameters():
    sim, client = public(Simulator), public(Client)
    missing = sorted(set(sim) - set(client))
    assert not missing, f"Simulator methods missing on Client: {missing}"
    for name, member in sim.items():
        other = client[name]
        assert isinstance(other, property) == isinstance(member, property), name
        if isinstance(member, property):
            continue
        mine = [p for p in inspect.signature(member).parameters if p != "self"]
        theirs = [p for p in inspect.signature(other).parameters if p != "self"]
        assert theirs[: len(mine)] == mine or mine[: len(theirs)] == theirs, (name, mine, theirs)


@pytest.fixture(scope="module")
def server():
    srv = Server(port=0)
    srv.serve_in_thread()
    yield srv
    srv.stop()


def program(sim) -> str:
    """The README's simulator example, then the methods the client lacked before."""
    above = translation(0, 0, 0.1) @ tool_down(pp.grasp_position())
    sim.set_speed(pp.ROBOT, 0.5)
    sim.move_end_effector(pp.ROBOT, above, config="ru")
    sim.move_straight_line(pp.ROBOT, tool_down(pp.grasp_position()))
    held = sim.close_gripper(pp.ROBOT)
    sim.move_straight_line(pp.ROBOT, above)
    with sim.concurrently():
        sim.move_joints_relative(pp.ROBOT, np.radians([10, 0, 0, 0, 0, 0]))
    sim.move_joints_absolute(pp.ROBOT, "home")  # a named pose
    return held


def test_one_program_gives_the_same_results_in_process_and_remote(server):
    local = Simulator(pp.build(), dt=0.01)
    with Client(port=server.port, timeout=60) as remote:
        remote.example_cell("pick-place")
        remote.simulate("path", dt=0.01)
        assert program(local) == program(remote) == pp.CUBE
        assert remote.sim_time == pytest.approx(local.sim_time, abs=1e-9)
        assert remote.frames == local.frames
        assert remote.speed(pp.ROBOT) == pytest.approx(0.5)
        assert np.allclose(remote.part_pose(pp.CUBE), local.part_pose(pp.CUBE), atol=1e-9)
        assert np.allclose(remote.gripper_pose(pp.ROBOT), local.gripper_pose(pp.ROBOT), atol=1e-9)
        assert np.allclose(remote.joints(pp.ROBOT), np.radians([0, 0, -90, 0, 90, 0]))
        t, q = remote.trajectory(pp.ROBOT)
        t0, q0 = local.trajectory(pp.ROBOT)
        assert t.shape == t0.shape
        assert q.shape == q0.shape == (local.frames, 6)
        assert np.allclose(t, t0, atol=1e-9)
        assert np.allclose(q, q0, atol=1e-9)
        assert remote.wall_time > 0
        assert [e.kind for e in remote.events] == [e.kind for e in local.events]
        assert [e.kind for e in remote.events()] == [e.kind for e in local.events()]  # calls too


def test_a_failing_concurrent_block_is_dropped_on_both(server):
    with Client(port=server.port, timeout=60) as remote:
        remote.example_cell("pick-place")
        remote.simulate("path", dt=0.01)
        local = Simulator(pp.build(), dt=0.01)
        for sim in (local, remote):
            before = sim.frames
            with pytest.raises(ProgramError, match="cannot run inside concurrently"):
                block(sim)
            assert sim.frames == before
            assert sim.sim_time == 0.0
            with sim.concurrently():  # and a new block can start
                sim.move_joints_relative(pp.ROBOT, np.radians([10, 0, 0, 0, 0, 0]))
            assert sim.frames > before


def block(sim) -> None:
    """A concurrent block with a command that is refused inside it."""
    with sim.concurrently():
        sim.move_joints_relative(pp.ROBOT, np.radians([10, 0, 0, 0, 0, 0]))
        sim.wait(1.0)  # refused inside a block: the whole block is undone


@pytest.mark.parametrize("q", ["nowhere", [1, "a"], [[1, 2], [3]], {"x": 1}])
def test_a_bad_joint_target_is_a_program_error_on_both(server, q):
    local = Simulator(pp.build(), dt=0.01)
    with pytest.raises(ProgramError):
        local.move_joints_absolute(pp.ROBOT, q)
    with Client(port=server.port, timeout=60) as remote:
        remote.example_cell("pick-place")
        remote.simulate("path", dt=0.01)
        with pytest.raises(ProgramError):
            remote.move_joints_absolute(pp.ROBOT, q)
        assert remote.frames == 1  # nothing moved


def test_named_poses_are_listed_when_unknown():
    local = Simulator(pp.build(), dt=0.01)
    with pytest.raises(ProgramError, match="named poses: home, zero"):
        local.move_joints_absolute(pp.ROBOT, "nowhere")
