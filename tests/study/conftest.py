"""The study tests: stop the process pools' fork server when they are done (its socket
folder would otherwise stay in the temporary folder until the test process exits)."""

from __future__ import annotations

import pytest

from workcell.study.pool import stop_fork_server


@pytest.fixture(autouse=True, scope="package")
def _fork_server():
    yield
    stop_fork_server()
