"""A robot's signal sets and waits leave the simulator as the vendor's I/O and come back
as the cell's signals: a robot program that waits for a controller's ``go`` (set at a
time the controller chose) and then sets ``done``, exported, read back and run against
the same controller, sets ``done`` at the same simulated time, in every language."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from workcell import ProgramError, Workcell
from workcell.robotprog import export, load
from workcell.robotprog.instructions import SetOutput, WaitInput, from_sim
from workcell.sim import Simulator
from workcell.spatial import translation

LANGS = {"urscript": ".script", "krl": ".src", "rapid": ".mod", "fanuc_ls": ".ls"}
GO_AT = 1.5  # s: when the controller sets 'go'
Q1 = np.radians([20, -90, 80, -80, -90, 0])


def _sim(profile: str) -> Simulator:
    cell = Workcell("io")
    cell.add_robot("ur", "ur5e", gripper=True, base=translation(0, 0, 0.1))
    cell.add_signal("go", False)
    cell.add_signal("done", False)
    return Simulator(cell, profile=profile, dt=0.01, check_collisions=False)


def controller(sim: Simulator) -> None:
    sim.wait(GO_AT)
    sim.set_signal("go", True)


def robot_program(sim: Simulator) -> None:
    sim.wait_signal("go")
    sim.move_joints_absolute("ur", Q1)
    sim.set_signal("done", True)


def _done_at(sim: Simulator) -> float:
    [t] = [e.t for e in sim.events() if e.kind == "signal" and e.detail.startswith("done")]
    return t


def test_the_instruction_list_has_the_robots_waits_and_sets_not_the_controllers():
    sim = _sim("jerk")
    sim.run_programs({"ur": robot_program, "cell": controller})
    prog = from_sim(sim, "ur", signals={"go": 1, "done": 2})
    io = [i for i in prog.instructions if isinstance(i, SetOutput | WaitInput)]
    assert [(type(i).__name__, i.name, i.number) for i in io] == [
        ("WaitInput", "go", 1),
        ("SetOutput", "done", 2),
    ]
    assert prog.inputs == {1: "go"}
    assert prog.outputs == {2: "done"}


@pytest.mark.parametrize("language", sorted(LANGS))
def test_signal_io_round_trips_through_every_language(language, tmp_path: Path):
    profile = "trapezoid" if language == "urscript" else "jerk"
    sim = _sim(profile)
    sim.run_programs({"ur": robot_program, "cell": controller})
    t_done = _done_at(sim)
    # done: once the robot had 'go' (at GO_AT) and made its move (a closed-form time)
    assert t_done > GO_AT
    paths = export(sim, "ur", tmp_path / f"io{LANGS[language]}", language=language)
    prog = load(paths[0])
    again = _sim(profile)
    again.run_programs({"ur": lambda s: prog.run(s, "ur"), "cell": controller})
    assert _done_at(again) == pytest.approx(t_done, rel=0.01)
    assert np.abs(again.joints("ur") - Q1).max() < 1e-6
    assert again.signal("done") is True


def test_waiting_for_an_input_the_cell_lacks_says_so(tmp_path: Path):
    sim = _sim("jerk")
    sim.run_programs({"ur": robot_program, "cell": controller})
    path = export(sim, "ur", tmp_path / "io.script")[0]
    cell = Workcell("bare")
    cell.add_robot("ur", "ur5e", gripper=True, base=translation(0, 0, 0.1))
    bare = Simulator(cell, dt=0.01, check_collisions=False)
    q0 = bare.joints("ur")
    with pytest.raises(ProgramError, match=r"io\.script:\d+:\d+: .*no signal of that name.*none"):
        load(path).run(bare, "ur")
    assert np.abs(bare.joints("ur") - q0).max() < 1e-6  # stopped at the wait, before the move
