"""Fixtures of the program tests (the helpers: program_helpers.py)."""

from __future__ import annotations

import pytest
from program_helpers import (  # noqa: F401  (re-exported for tests that import them here)
    EXAMPLE1_SIM_TIME,
    needs_cartesian,
    needs_handoff,
    needs_pick_place,
    snapshot,
)

from workcell.program import Session


@pytest.fixture
def session(tmp_path) -> Session:
    """An empty session whose relative files go to a temporary folder."""
    return Session(base_dir=tmp_path)
