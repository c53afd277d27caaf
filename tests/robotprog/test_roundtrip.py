"""Export, load and run: for every library robot family and every language, the program
run from the file reaches every target the simulation reached (1e-6 m, 1e-6 rad: the
joints, hence the poses) and takes the same cycle time (1 %). The programs are built
here in Python (joint moves, Cartesian joint moves, lines, arcs, zones, a wait, the
gripper, a planned path's waypoints); the outside numbers are the simulation's own
records of what it ran."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from workcell import Workcell
from workcell.robotprog import export, load
from workcell.robotprog.instructions import from_sim
from workcell.sim import Simulator
from workcell.spatial import translation

# a start pose inside each arm's workspace (deg) and the family's scale (m)
FAMILIES = {
    "ur5e": ([0, -100, 90, -80, -90, 0], 0.08),
    "kuka_kr6_r700": ([0, -90, 90, 0, 60, 0], 0.08),
    "abb_irb140": ([0, 10, 10, 0, 60, 0], 0.08),
    "fanuc_lrmate200id": ([0, 10, 0, 0, -70, 0], 0.08),
    "puma560": ([0, 45, -180, 0, 45, 0], 0.06),
}
LANGS = {"urscript": ".script", "krl": ".src", "rapid": ".mod", "fanuc_ls": ".ls"}


def _sim(robot: str, profile: str) -> Simulator:
    cell = Workcell("c")
    cell.add_robot("r", robot, gripper=True, base=translation(0.5, -0.2, 0.1))
    return Simulator(cell, profile=profile, dt=0.01, check_collisions=False)


def _program(sim: Simulator, robot: str, override: float) -> None:
    start, s = FAMILIES[robot]
    q0 = np.radians(start)
    sim.set_override("r", override)
    sim.move_joints_absolute("r", q0, zone=0.01)
    T = sim.tool_pose("r")
    up = translation(0, 0, s / 2) @ T
    sim.move_end_effector("r", up, zone=0.01)
    sim.move_linear("r", translation(s, 0, 0) @ up, speed=0.25, zone=0.01)
    sim.move_circular(
        "r", translation(1.5 * s, s / 2, 0) @ up, translation(2 * s, 0, 0) @ up, speed=0.2
    )
    sim.wait(0.25)
    sim.open_gripper("r")
    sim.move_linear("r", translation(s, 0, 0) @ T, speed=0.15, acceleration=0.8)
    sim.move_joints_absolute("r", q0 + np.radians([10, -5, 5, 10, 5, -10]))


def _targets(sim: Simulator) -> list[np.ndarray]:
    """The joints each motion command ended at (its record's q), in order."""
    out = []
    for e in sim.events:
        p = (e.data or {}).get("program") or {}
        if "q" in p:
            out.append(np.array(p["q"]))
    return out


@pytest.mark.parametrize("robot", sorted(FAMILIES))
@pytest.mark.parametrize("language", sorted(LANGS))
def test_export_load_run_reproduces_targets_and_cycle_time(
    robot: str, language: str, tmp_path: Path
) -> None:
    # URScript's movej is UR's trapezoid (leading axis v, a); the others time joint moves
    # by each joint's limits x the override: the simulator's profile "jerk"
    profile = "trapezoid" if language == "urscript" else "jerk"
    override = 1.0 if language == "urscript" else 0.5
    sim = _sim(robot, profile)
    _program(sim, robot, override)
    paths = export(sim, "r", tmp_path / f"prog{LANGS[language]}", language=language)
    assert all(Path(p).is_file() for p in paths)
    again = _sim(robot, profile)
    load(paths[0]).run(again, "r")
    want, got = _targets(sim), _targets(again)
    # the file starts with a joint move to the joints the robot had (no time there)
    assert np.allclose(got[0], again.timeline.frame(0)[2][again._qadr["r"]], atol=1e-12)
    got = got[1:]
    assert len(got) == len(want)
    for a, b in zip(want, got, strict=True):
        assert np.abs(a - b).max() < 1e-6
        Ta, Tb = sim.cell.robots["r"].robot.fk(a), again.cell.robots["r"].robot.fk(b)
        assert np.abs(Ta[:3, 3] - Tb[:3, 3]).max() < 1e-6
    assert again.sim_time == pytest.approx(sim.sim_time, rel=0.01)
    assert again.held("r") is None


def test_the_instruction_list_of_a_planned_and_task_level_program(tmp_path: Path) -> None:
    """move_straight_line (a task's approach) exports as a linear move to the same pose,
    a planned path as its waypoints; the run ends where the simulation did."""
    sim = _sim("kuka_kr6_r700", "jerk")
    q0 = np.radians(FAMILIES["kuka_kr6_r700"][0])
    sim.move_joints_absolute("r", q0)
    T = sim.tool_pose("r")
    sim.move_straight_line("r", translation(0, 0, -0.05) @ T)
    sim.move_joints_absolute("r", q0 + 0.2, plan=True)
    prog = from_sim(sim, "r")
    kinds = [type(i).__name__ for i in prog.instructions]
    assert kinds[:3] == ["MoveJoint", "MoveJoint", "MoveLinear"]
    assert kinds.count("MoveJoint") >= 3
    path = export(sim, "r", tmp_path / "task.src")[0]
    again = _sim("kuka_kr6_r700", "jerk")
    load(path).run(again, "r")
    assert np.allclose(again.joints("r"), sim.joints("r"), atol=1e-6)
    # a straight line without a tool speed is written at the trapezoid taking its time
    assert again.sim_time == pytest.approx(sim.sim_time, rel=0.05)


def test_a_jog_exports_as_a_joint_move_to_the_jogged_joints(tmp_path: Path) -> None:
    """A jog (the live view's joint inputs and gizmo) changes joints with no time passing;
    a real robot cannot jump, so the exported program moves there (a joint move to the
    jogged joints) before what followed, and the file run back reaches every target."""
    sim = _sim("ur5e", "jerk")
    q0 = np.radians(FAMILIES["ur5e"][0])
    sim.move_joints_absolute("r", q0)
    jogged = q0 + np.radians([15, -10, 5, 0, 20, 0])
    sim.jog("r", jogged)
    sim.move_linear("r", translation(0.05, 0, 0) @ sim.tool_pose("r"), speed=0.2)
    kinds = [type(i).__name__ for i in from_sim(sim, "r").instructions]
    assert kinds == ["MoveJoint", "MoveJoint", "MoveJoint", "MoveLinear"]
    assert np.abs(from_sim(sim, "r").instructions[2].q - jogged).max() < 1e-12
    path = export(sim, "r", tmp_path / "jog.src")[0]
    again = _sim("ur5e", "jerk")
    load(path).run(again, "r")
    assert np.abs(again.joints("r") - sim.joints("r")).max() < 1e-6
    # the jog's move takes time on the robot (the simulation's jog took none)
    assert again.sim_time > sim.sim_time


def test_a_path_without_a_suffix_gets_the_languages(tmp_path: Path) -> None:
    sim = _sim("kuka_kr6_r700", "jerk")
    sim.move_joints_absolute("r", np.radians(FAMILIES["kuka_kr6_r700"][0]))
    paths = export(sim, "r", tmp_path / "sub" / "prog", language="krl")
    assert paths == [str(tmp_path / "sub" / "prog.src"), str(tmp_path / "sub" / "prog.dat")]
    assert all(Path(p).is_file() for p in paths)
    assert sorted(p.name for p in (tmp_path / "sub").iterdir()) == ["prog.dat", "prog.src"]
