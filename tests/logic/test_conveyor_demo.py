"""The conveyor demo: its throughput agrees with a hand computation from the programs'
cycle times, and ``workcell demo conveyor`` prints and writes what the README says.

The hand computation is a small event model of the cell written here, independent of the
simulator's scheduler and devices: box k appears at k x EVERY with its front face at the
source; it reaches the beam when the belt has run (beam - front) / speed seconds since
then; the belt stands still from each arrival until the robot sets ``placed``; the robot
is ready above the belt after its approach move, picks when the box is there and the
robot ready, and sets ``placed`` its cycle time later. Only the robot's motion durations
come from the run (each command's own duration, the programs' cycle times).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from workcell.cli import main
from workcell.examples import conveyor as cv

DT = 0.01


@pytest.fixture(scope="module")
def sim():
    return cv.run("path", DT)


def _cycles(sim):
    """Per box: the approach move's duration, the time from the beam to ``placed``; and
    the final move home (s), from the robot's command records."""
    recs = [r for r in sim.cycle_time()["commands"] if r["robot"] == cv.ROBOT]
    back, pick, i = [], [], 0
    for _ in range(cv.BOXES):
        assert recs[i]["command"] == "move_end_effector"
        assert recs[i + 1]["command"] == "wait_signal"
        back.append(recs[i]["duration_s"])
        j = i + 2
        while recs[j]["command"] != "set_signal":
            j += 1
        pick.append(sum(r["duration_s"] for r in recs[i + 2 : j]))
        i = j + 1
    assert recs[i]["command"] == "move_joints_absolute"
    return back, pick, recs[i]["duration_s"]


def _hand_model(back, pick):
    """The placed times (s) of the event model (module doc)."""
    beam = cv.BELT_END - cv.BEAM_BEFORE_END
    front0 = cv.SOURCE_X + cv.BOX[0]
    need = (beam - front0) / cv.BELT_SPEED  # s of running belt from the source to the beam
    stops: list[tuple[float, float]] = []
    placed, ready = [], back[0]
    for k in range(cv.BOXES):
        t, run = k * cv.EVERY, 0.0
        for a, b in stops:  # run from t, skipping the stops, until `need` s have run
            if b <= t:
                continue
            if a > t:
                if run + (a - t) >= need:
                    break
                run += a - t
            t = max(t, b)
        arrive = t + (need - run)
        start = max(arrive, ready)
        placed.append(start + pick[k])
        stops.append((arrive, placed[-1]))
        if k + 1 < cv.BOXES:
            ready = placed[-1] + back[k + 1]
    return np.array(placed)


def test_the_demos_throughput_agrees_with_a_hand_computation(sim):
    back, pick, home = _cycles(sim)
    expected = _hand_model(back, pick)
    got = np.array(
        [e.t for e in sim.events if e.kind == "signal" and e.detail.startswith("placed = true")]
    )
    assert len(got) == cv.BOXES
    # each arrival is seen at the first frame at or after it: at most one frame late each
    assert np.all(got >= expected - 1e-9)
    assert np.all(got - expected <= (np.arange(cv.BOXES) + 1) * DT + 1e-9)
    T = expected[-1] + home
    tp = sim.throughput()
    assert tp["time_s"] == pytest.approx(T, abs=cv.BOXES * DT)
    assert tp["signals"]["placed"]["rising"] == cv.BOXES
    assert tp["signals"]["placed"]["per_hour"] == pytest.approx(cv.BOXES * 3600 / T, rel=2e-3)
    f = tp["robots"][cv.ROBOT]
    assert f["moving"] + f["waiting"] + f["idle"] == pytest.approx(1.0)
    assert f["moving_s"] == pytest.approx(sum(back) + sum(pick) + home, abs=1e-9)


def test_every_box_ends_on_the_pallet_in_its_place(sim):
    end = sim.part_positions()
    for k, place in enumerate(cv.stack_positions()):
        # where the box stopped at the beam (within one frame's travel) is where it was held
        assert np.linalg.norm(np.array(end[f"box_{k + 1}"]) - place) <= cv.BELT_SPEED * DT + 1e-6
    assert sim.summary()["collisions"] == 0
    assert {e.data["part"] for e in sim.events if e.kind == "source"} == {
        f"box_{k}" for k in range(1, cv.BOXES + 1)
    }


def test_the_demo_prints_throughput_and_writes_picture_and_recording(tmp_path, capsys):
    png, rrd = tmp_path / "demo.png", tmp_path / "demo.rrd"
    assert main(["demo", "conveyor", "--json", "--render", str(png), "--save", str(rrd)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["throughput"]["signals"]["placed"]["rising"] == cv.BOXES
    assert set(out["throughput"]["robots"]) == {cv.ROBOT}
    assert out["png"] == str(png)
    assert png.stat().st_size > 10_000
    assert out["rrd"] == str(rrd)
    assert rrd.stat().st_size > 10_000
    assert main(["demo", "conveyor"]) == 0
    text = capsys.readouterr().out
    assert "boxes per hour" in text
    assert "moving" in text
    assert "waiting" in text
