"""Programs written by hand from the vendors' published syntax (tests/robotprog/programs):
comments and folds, data files and declarations, variables and arithmetic on poses, loops
with constant bounds, an if on an input (False: the cell has no signal for it), calls,
tool and base (work object) changes. The simulated tool reaches the poses computed here
from the numbers in the text with the tests' own formulas."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from progframes import Rx, Ry, Rz, kuka_frame, quat_matrix, rodrigues

from workcell import Workcell
from workcell.robotprog import load
from workcell.sim import Simulator
from workcell.spatial import translation

PROGRAMS = Path(__file__).parent / "programs"
BASE = translation(0.2, 0.1, 0.0)  # the robot stands here in the cell


def _run(
    robot: str, name: str, profile: str = "jerk"
) -> tuple[Simulator, object, list[np.ndarray]]:
    cell = Workcell("hand")
    cell.add_robot("r", robot, base=BASE)  # no gripper: the robot's tool is its flange
    sim = Simulator(cell, profile=profile, dt=0.01, check_collisions=False)
    vm = load(PROGRAMS / name).run(sim, "r")
    ends = [
        np.array(e.data["program"]["q"])
        for e in sim.events
        if e.data and "q" in (e.data.get("program") or {})
    ]
    return sim, vm, ends


def _flanges(sim: Simulator, ends: list[np.ndarray]) -> list[np.ndarray]:
    robot = sim.cell.robots["r"].robot
    return [robot.fk(q) for q in ends]  # tool0 in the robot's base frame


def _close(A: np.ndarray, B: np.ndarray) -> None:
    assert np.abs(A[:3, 3] - B[:3, 3]).max() < 1e-6
    assert np.abs(A[:3, :3] - B[:3, :3]).max() < 1e-6


def test_krl_program_with_its_data_file() -> None:
    sim, vm, ends = _run("kuka_kr6_r700", "pick.src")
    assert np.allclose(np.degrees(ends[0]), [0, -90, 90, 0, 90, 0], atol=1e-9)  # PTP XHOME
    # the TCP: 100 mm along KUKA's flange x (the flange's axis), i.e. tool0's z
    tcp = translation(0, 0, 0.1)
    # KUKA's flange frame from tool0: x = tool0's z, y = tool0's y, z = -tool0's x
    to_kuka = np.eye(4)
    to_kuka[:3, :3] = np.column_stack([[0, 0, 1], [0, 1, 0], [-1, 0, 0]])
    poses = [F @ tcp @ to_kuka for F in _flanges(sim, ends)]
    expect = [kuka_frame(400 + 20 * k, -50, 500, 0, 90, 0) for k in (1, 2, 3)]
    expect.append(kuka_frame(460, -50, 500, 0, 90, 0) @ kuka_frame(0, 30, 0, 0, 0, 0))  # ELSE
    expect.append(kuka_frame(460, -50, 550, 30, 90, 0))  # LIFT
    assert len(poses) == 1 + len(expect)
    for got, want in zip(poses[1:], expect, strict=True):
        _close(got, want)
    assert vm.motion.outputs == {2: True}
    # the world: the robot's base placement x the program's pose
    _close(sim.tool_pose("r") @ tcp @ to_kuka, BASE @ expect[-1])


def test_rapid_module() -> None:
    sim, vm, ends = _run("abb_irb140", "pick.mod")
    assert np.allclose(np.degrees(ends[0]), [0, 20, 10, 0, 60, 0], atol=1e-9)  # MoveAbsJ
    tframe = translation(0, 0, 0.1)  # tGrip: 100 mm along the flange's z, no turn
    wobj = translation(0.1, 0, 0)  # wTable's user frame
    down = np.eye(4)
    down[:3, :3] = quat_matrix(0, 0, 1, 0)  # [0, 0, 1, 0]: half a turn about y
    poses = [F @ tframe for F in _flanges(sim, ends)]
    expect = [wobj @ translation(0.4 + 0.02 * k, -0.05, 0.3) @ down for k in (1, 2, 3)]
    expect.append(wobj @ translation(0.46, -0.02, 0.3) @ down)  # Offs(p, 0, 30, 0)
    expect.append(wobj @ translation(0.46, -0.05, 0.3) @ down @ translation(0, 0, -0.05))  # RelTool
    assert len(poses) == 1 + len(expect)
    for got, want in zip(poses[1:], expect, strict=True):
        _close(got, want)
    assert vm.motion.outputs == {0: True}  # doClamp: no number in the file (RAPID names it)


def test_urscript_program() -> None:
    sim, vm, ends = _run("ur5e", "pick.script", profile="trapezoid")
    assert np.allclose(np.degrees(ends[0]), [0, -100, 90, -80, -90, 0], atol=1e-9)
    tcp = translation(0, 0, 0.1)
    rot = np.eye(4)
    rot[:3, :3] = rodrigues(np.array([2.221441469079183, 2.221441469079183, 0.0]))
    start = translation(-0.40, -0.13, 0.40) @ rot
    poses = [F @ tcp for F in _flanges(sim, ends)]
    expect = [translation(0.02 * k, 0, 0) @ start for k in (1, 2, 3)]  # pose_add: base x
    last = expect[-1]
    expect.append(last @ translation(0, 0.03, 0))  # pose_trans: in the tool's frame
    expect.append(last @ translation(0, 0, -0.05))  # lift()
    assert len(poses) == 1 + len(expect)
    for got, want in zip(poses[1:], expect, strict=True):
        _close(got, want)
    assert vm.motion.outputs == {3: True}


def test_fanuc_ls_program() -> None:
    sim, vm, ends = _run("fanuc_lrmate200id", "pick.ls")
    # P[1] holds the controller's J3 = -10 deg with J2 = 10: the URDF's J3 = J3 + J2 = 0
    assert np.allclose(np.degrees(ends[0]), [0, 10, 0, 0, -80, 0], atol=1e-9)
    tcp = translation(0, 0, 0.1)  # UTOOL[1] = PR[1]: Z 100 mm

    def wpr(x: float, y: float, z: float, w: float, p: float, r: float) -> np.ndarray:
        T = np.eye(4)  # W, P, R about the fixed X, Y, Z
        T[:3, :3] = Rz(math.radians(r)) @ Ry(math.radians(p)) @ Rx(math.radians(w))
        T[:3, 3] = np.array([x, y, z]) / 1000.0
        return T

    poses = [F @ tcp for F in _flanges(sim, ends)]
    expect = [wpr(400 + 20 * k, -50, 350, 180, 0, 0) for k in (1, 2, 3)]
    expect.append(wpr(0, 30, 0, 0, 0, 0) @ wpr(460, -50, 350, 180, 0, 0))  # Offset,PR[3]
    expect.append(wpr(460, 20, 350, 180, 0, 0))  # C P[3] P[4]
    assert len(poses) == 1 + len(expect)
    for got, want in zip(poses[1:], expect, strict=True):
        _close(got, want)
    # the arc went through P[3]: some frame of the move passes within 1 mm of it
    _, Q = sim.trajectory("r")
    robot = sim.cell.robots["r"].robot
    pts = (robot.fk_batch(Q) @ tcp)[:, :3, 3]
    assert np.min(np.linalg.norm(pts - [0.48, 0.0, 0.35], axis=1)) < 1e-3
    assert vm.motion.outputs == {2: True}


@pytest.mark.parametrize("name", ["pick.src", "pick.mod", "pick.script", "pick.ls"])
def test_dwell_is_in_the_cycle_time(name: str) -> None:
    """Each program waits 0.2 s: the clock shows it between the two moves around it."""
    robot = {
        "src": "kuka_kr6_r700",
        "mod": "abb_irb140",
        "script": "ur5e",
        "ls": "fanuc_lrmate200id",
    }
    sim, _, _ = _run(
        robot[name.split(".")[1]], name, "trapezoid" if name.endswith("script") else "jerk"
    )
    waits = [e for e in sim.events if e.kind == "wait"]
    assert len(waits) == 1
    assert waits[0].data["duration_s"] == pytest.approx(0.2)
