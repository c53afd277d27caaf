"""Fixtures of the cell tests (the cell: cell_helpers.py)."""

from __future__ import annotations

import pytest
from cell_helpers import two_puma_cell

from workcell.cell import Workcell


@pytest.fixture(scope="module")
def cell() -> Workcell:
    return two_puma_cell()
