"""Shared helpers of the program tests: state snapshots, optional examples, numbers.

A module of its own name (not conftest: several test folders have a conftest.py, and
``from conftest import ...`` finds whichever was imported last, so it depended on which
tests were collected first)."""

from __future__ import annotations

import importlib.util
import math

import numpy as np
import pytest

from workcell.program import Session
from workcell.sim import Simulator

HAS_PICK_PLACE = importlib.util.find_spec("workcell.examples.thesis_pick_place") is not None
HAS_HANDOFF = importlib.util.find_spec("workcell.examples.thesis_handoff") is not None
CARTESIAN = ("move_end_effector", "move_straight_line", "close_gripper", "open_gripper")
HAS_CARTESIAN = all(hasattr(Simulator, n) for n in CARTESIAN)
needs_cartesian = pytest.mark.skipif(
    not HAS_CARTESIAN, reason="the Simulator has no Cartesian/gripper commands yet"
)
needs_pick_place = pytest.mark.skipif(
    not (HAS_PICK_PLACE and HAS_CARTESIAN), reason="thesis example 2 cell not available yet"
)
needs_handoff = pytest.mark.skipif(
    not (HAS_HANDOFF and HAS_CARTESIAN), reason="thesis example 3 cell not available yet"
)

# thesis example 1 by hand (eq. 4.27): the joint that moves most moves 70, 40 and 60 deg
EXAMPLE1_SIM_TIME = math.radians(70 + 40 + 60) / 0.3


def snapshot(session: Session) -> tuple:
    """Everything a command may change: model, cell, simulator state (joints, clocks,
    timeline length, events, holds), and which objects the session holds."""
    sim = session.sim
    sim_state = None
    if sim is not None:
        holds = tuple(sim.held(r) for r in sim.robots) if hasattr(sim, "held") else ()
        sim_state = (
            sim.mode,
            sim.sim_time,
            sim.frames,
            tuple(sim.events),
            tuple(tuple(sim.joints(r)) for r in sim.robots),
            tuple(tuple(np.ravel(p)) for p in sim.part_positions().values()),
            holds,
        )
    cell = session.cell.to_dict() if session.cell is not None else None
    return (id(session.cell), id(session.sim), session.model.to_dict(), cell, sim_state)
