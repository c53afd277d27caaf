"""Fixtures for the whole suite."""

from __future__ import annotations

import os

import pytest

from workcell.decompose import CACHE_ENV


@pytest.fixture(autouse=True, scope="session")
def _coacd_cache(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Convex decompositions go to a temporary cache, never the user's (one per worker)."""
    old = os.environ.get(CACHE_ENV)
    os.environ[CACHE_ENV] = str(tmp_path_factory.mktemp("coacd"))
    yield
    if old is None:
        del os.environ[CACHE_ENV]
    else:
        os.environ[CACHE_ENV] = old
