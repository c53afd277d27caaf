"""``make test`` gives the same result on every run: property tests are derandomized.

The profile comes from tests/conftest.py (``WORKCELL_HYPOTHESIS``, default ``ci``).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.skipif(
    os.environ.get("WORKCELL_HYPOTHESIS", "ci") != "ci", reason="an exploring run, by request"
)
def test_the_default_profile_is_derandomized_with_no_example_database():
    now = settings.default
    assert now.derandomize is True
    assert now.database is None  # nothing found on one run is replayed on the next
    assert now.deadline is None  # a loaded machine does not fail a test


def test_a_property_test_draws_the_same_examples_on_every_run():
    # the user's step: run the same property test twice; with the ci profile (the default)
    # both runs see the same examples, even where the first one failed
    def run() -> list[float]:
        seen: list[float] = []

        @settings(max_examples=30, derandomize=True, database=None)
        @given(st.floats(-3.0, 3.0))
        def prop(x: float) -> None:
            seen.append(x)

        prop()
        return seen

    first = run()
    assert len(set(first)) > 10
    assert run() == first


def test_exploring_is_one_environment_variable_away(tmp_path):
    # WORKCELL_HYPOTHESIS=explore: random examples on each run (two runs differ)
    test = tmp_path / "test_x.py"
    test.write_text(
        "from hypothesis import given, strategies as st\n"
        "import pathlib\n"
        "@given(st.floats(-3.0, 3.0))\n"
        "def test_p(x):\n"
        f"    with open({str(tmp_path / 'seen.txt')!r}, 'a') as f:\n"
        "        f.write(repr(x) + '\\n')\n"
    )
    (tmp_path / "conftest.py").write_text((ROOT / "tests" / "conftest.py").read_text())
    runs = []
    for _ in range(2):
        env = {**os.environ, "WORKCELL_HYPOTHESIS": "explore"}
        done = subprocess.run(
            [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
             str(test), "-o", "addopts="],
            cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300,
        )  # fmt: skip
        assert done.returncode == 0, done.stdout[-2000:]
        runs.append((tmp_path / "seen.txt").read_text())
        (tmp_path / "seen.txt").unlink()
    assert runs[0] != runs[1]
    bad = subprocess.run(
        [sys.executable, "-c", "import conftest"],
        cwd=tmp_path, env={**os.environ, "WORKCELL_HYPOTHESIS": "wild"},
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert bad.returncode != 0
    assert "WORKCELL_HYPOTHESIS='wild': valid: ci, explore" in bad.stderr
