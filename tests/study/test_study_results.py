"""Results on disk: written as the study runs, a re-run skips what is done (also after a
real process is killed mid-study), another study's folder is refused."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import study_programs as sp

from workcell.errors import StudyError
from workcell.study import Study, execute, run
from workcell.study.results import PARTS, RESULTS, ResultStore, schema
from workcell.study.spec import parameter

STUDY = Study(cell="joints", vary={"puma.base.x": "0:0.3:4", "puma.base.yaw": "0,90"})


def _files(out: Path) -> list[Path]:
    """The results files in ``out``: results.parquet and the part files (no temp files)."""
    results = [out / RESULTS] if (out / RESULTS).exists() else []
    return results + sorted((out / PARTS).glob("part-*.parquet"))


def _on_disk(out: Path) -> pa.Table:
    """Every row in ``out`` (results and parts), duplicates kept."""
    files = _files(out)
    if not files:
        return schema(STUDY.parameters).empty_table()
    return pa.concat_tables([pq.read_table(f) for f in files])


def test_results_are_written_and_a_rerun_runs_only_what_is_missing(tmp_path):
    full = run(STUDY, tmp_path, backend="serial", progress=False, plots=False)
    assert pq.read_table(tmp_path / RESULTS).equals(full)
    assert list((tmp_path / PARTS).glob("*")) == []  # merged into results.parquet
    kept = full.filter(pa.array([i % 3 == 0 for i in range(full.num_rows)]))
    pq.write_table(kept, tmp_path / RESULTS)  # as if the study had stopped there
    again = execute(STUDY, tmp_path, backend_name="serial", progress=False, plots=False)
    assert (again.resumed, again.evaluated) == (kept.num_rows, full.num_rows - kept.num_rows)
    assert again.table.equals(full)
    done = execute(STUDY, tmp_path, backend_name="serial", progress=False, plots=False)
    assert (done.resumed, done.evaluated) == (full.num_rows, 0)


def test_rows_in_parts_and_results_count_once(tmp_path):
    full = run(STUDY, tmp_path, backend="serial", progress=False, plots=False)
    (tmp_path / PARTS).mkdir(exist_ok=True)
    pq.write_table(full.slice(2, 3), tmp_path / PARTS / "part-1.parquet")  # left by a crash
    info = json.loads((tmp_path / "study.json").read_text())
    store = ResultStore(tmp_path, schema(STUDY.parameters), info["study"], info["key"])
    assert store.count == full.num_rows
    assert store.merge().equals(full)
    assert list((tmp_path / PARTS).glob("*")) == []


def test_another_study_in_the_same_folder_is_refused(tmp_path):
    run(STUDY, tmp_path, backend="serial", progress=False, plots=False)
    other = Study(cell="joints", vary={"puma.base.x": "0:0.3:5", "puma.base.yaw": "0,90"})
    with pytest.raises(StudyError, match=r"another study \(it differs in: parameters\)"):
        run(other, tmp_path, backend="serial", progress=False)
    with pytest.raises(StudyError, match="differs in: dt"):
        run(Study(cell="joints", vary=STUDY.vary, dt=0.02), tmp_path, backend="serial")


def test_without_a_folder_nothing_is_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    table = run(STUDY, backend="serial", progress=False)
    assert table.num_rows == 8
    assert list(tmp_path.iterdir()) == []


def test_store_keeps_one_row_per_candidate(tmp_path):
    p = parameter("puma.base.x", "0,1")
    store = ResultStore(None, schema([p]), {}, "k")
    row = {
        "candidate": 0,
        "puma.base.x": 0.0,
        "feasible": False,
        "error_type": "X",
        "error": "X: y",
    }
    store.add([row, row, {**row, "candidate": 1}])
    assert store.count == 2
    assert store.table().column("candidate").to_pylist() == [0, 1]


KILLED = """
import sys
from workcell.study import Study, run
import study_programs
study = Study(cell="joints", program=study_programs.slow_joints, vary={"puma.base.x": "0:0.29:30"})
run(study, sys.argv[1], backend="serial", progress=False, plots=False)
"""


@pytest.mark.slow
def test_a_killed_study_resumes_and_loses_and_repeats_nothing(tmp_path):
    """Kill a real process mid-study (SIGKILL: no cleanup at all), then run the study
    again: every candidate has exactly one row, the rows written before the kill are kept
    as they were, and only the others are evaluated."""
    study = Study(cell="joints", program=sp.slow_joints, vary={"puma.base.x": "0:0.29:30"})
    env = {**os.environ, "PYTHONPATH": str(Path(sp.__file__).parent)}
    args = [sys.executable, "-c", KILLED, str(tmp_path)]
    proc = subprocess.Popen(args, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while not _files(tmp_path) and proc.poll() is None:
            assert time.monotonic() < deadline, "no rows written"
            time.sleep(0.02)
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        err = proc.communicate()[1].decode()
    before = _on_disk(tmp_path)
    assert 0 < before.num_rows < 30, f"the study was not killed mid-way: {err[-2000:]}"
    again = execute(study, tmp_path, backend_name="serial", progress=False, plots=False)
    assert again.resumed == before.num_rows
    assert again.evaluated == 30 - before.num_rows
    ids = again.table.column("candidate").to_pylist()
    assert ids == list(range(30))
    kept = {r["candidate"]: r for r in before.to_pylist()}
    for r in again.table.to_pylist():
        if r["candidate"] in kept:
            assert r == kept[r["candidate"]]
    assert pq.read_table(tmp_path / RESULTS).equals(again.table)
