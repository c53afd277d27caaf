"""The whole suite runs in its own temporary folder and must leave nothing behind.

Before the session starts, ``TMPDIR`` (and :mod:`tempfile`'s cached choice) point to a
fresh folder, so everything the tests and the code under test put in "the system's
temporary folder" (spill files, kernel connection files, subprocesses' files) lands
there; pytest's own ``tmp_path`` folders live there too. When the session ends, anything
else still in that folder is a leak: the session fails and lists it. The folder is then
removed, so a run leaves nothing in /tmp. (xdist workers inherit the folder.)

Property tests (hypothesis) run under the profile ``WORKCELL_HYPOTHESIS`` names:
``ci`` (the default, so ``make test`` and CI): derandomized (each test's examples come
from its own name: the same on every run and machine), no example database (nothing
found on one run is replayed on the next), no deadline and no too-slow health check (a
loaded machine must not fail a test); ``explore``: random examples on every run, as
many as each test asks for, failures kept in ``.hypothesis/`` and replayed first
(``WORKCELL_HYPOTHESIS=explore make test``, or add ``--hypothesis-seed=N`` to replay one
exploration).

Ctrl-C works in the processes tests start even when the suite runs as a background job
(which inherits SIGINT ignored; see below).
"""

from __future__ import annotations

import os
import shutil
import signal
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

from workcell.decompose import CACHE_ENV

_KEY = "WORKCELL_TEST_TMPDIR"
HYPOTHESIS_PROFILE = "WORKCELL_HYPOTHESIS"

_CALM = {"deadline": None, "suppress_health_check": [HealthCheck.too_slow]}
settings.register_profile("ci", derandomize=True, database=None, print_blob=True, **_CALM)
settings.register_profile("explore", derandomize=False, **_CALM)
_profile = os.environ.get(HYPOTHESIS_PROFILE, "ci")
if _profile not in ("ci", "explore"):
    raise pytest.UsageError(f"{HYPOTHESIS_PROFILE}={_profile!r}: valid: ci, explore")
settings.load_profile(_profile)

# A suite started as a background job of a script (``make test &``, ``nohup ... &``)
# inherits SIGINT ignored, and so would every process a test starts: Python keeps an
# inherited SIG_IGN, and the tests that press Ctrl-C on a server or a command would wait
# for an exit that never comes. A handler (not SIG_IGN) makes children start as from a
# terminal (exec resets handlers to the default).
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_configure(config: pytest.Config) -> None:
    if hasattr(config, "workerinput"):  # an xdist worker: the controller set TMPDIR
        tempfile.tempdir = os.environ.get("TMPDIR") or None
        return
    folder = tempfile.mkdtemp(prefix="workcell-tests-")
    os.environ["TMPDIR"] = folder
    os.environ[_KEY] = folder
    tempfile.tempdir = folder


def leftovers(folder: Path) -> list[str]:
    """What is in ``folder`` besides pytest's own ``pytest-of-*`` folders."""
    return sorted(p.name for p in folder.iterdir() if not p.name.startswith("pytest-of-"))


@pytest.hookimpl(trylast=True)
def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    if hasattr(session.config, "workerinput") or not os.environ.get(_KEY):
        return
    folder = Path(os.environ.pop(_KEY))
    left = leftovers(folder) if folder.is_dir() else []
    shutil.rmtree(folder, ignore_errors=True)
    if left:
        reporter = session.config.pluginmanager.get_plugin("terminalreporter")
        message = (
            f"the test session left {len(left)} file(s) in the temporary folder: "
            f"{', '.join(left[:20])}"
        )
        if reporter is not None:
            reporter.ensure_newline()
            reporter.write_line(f"ERROR: {message}", red=True)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


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


@pytest.fixture(autouse=True, scope="session")
def _runtime_dir(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Servers' token files go to a temporary runtime folder (clients find them there),
    never the user's (one per worker)."""
    old = os.environ.get("WORKCELL_RUNTIME_DIR")
    os.environ["WORKCELL_RUNTIME_DIR"] = str(tmp_path_factory.mktemp("runtime"))
    yield
    if old is None:
        del os.environ["WORKCELL_RUNTIME_DIR"]
    else:
        os.environ["WORKCELL_RUNTIME_DIR"] = old
