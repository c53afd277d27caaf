"""Backends: serial, process pool and Ray give the same rows, bit for bit; a candidate
that kills its worker is retried, then becomes an error row; the others carry on."""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile

import numpy as np
import pyarrow as pa
import pytest
import study_programs as sp

from workcell.errors import StudyError
from workcell.study import Study, run
from workcell.study.pool import CRASH_MESSAGE

# robot choice and placement: two compiled templates per worker, reach and clearance work
MIXED = Study(
    cell="pick-place",
    vary={
        "puma.robot": "puma260,ur5e",
        "puma.base.x": "0:0.05:2",
        "puma.base.y": "-0.1,0",
    },
)
CRASHY = {"puma.base.x": "0:0.3:4"}  # x = 0.2 and 0.3 kill their worker


def _bits(table: pa.Table) -> list[tuple[str, bytes]]:
    """Every column as raw bytes (floats compared bit for bit, nulls included)."""
    out = []
    for name in table.column_names:
        col = table.column(name).combine_chunks()
        if pa.types.is_floating(col.type):
            out.append((name, np.asarray(col.fill_null(np.nan)).view(np.uint64).tobytes()))
            out.append((name + ".valid", np.asarray(col.is_valid()).tobytes()))
        else:
            out.append((name, str(col.to_pylist()).encode()))
    return out


@pytest.fixture(scope="module")
def serial_table():
    return run(MIXED, backend="serial", progress=False)


def test_serial_results(serial_table):
    assert serial_table.num_rows == 8
    assert serial_table.column("candidate").to_pylist() == list(range(8))
    rows = serial_table.to_pylist()
    assert any(r["feasible"] for r in rows)
    assert rows[0]["puma.robot"] == "puma260"


@pytest.mark.parametrize("start", ["fork", "forkserver"])
def test_process_pool_gives_the_same_rows_bit_for_bit(serial_table, start, monkeypatch):
    """Workers forked from this process or from the fork server (whichever the parent's
    threads allow, see workcell.study.pool): the same rows as one process."""
    import multiprocessing

    from workcell.study import pool

    context = multiprocessing.get_context(start)
    if start == "forkserver":
        context.set_forkserver_preload(["workcell.study.evaluation"])
    monkeypatch.setattr(pool, "_context", lambda: context)
    table = run(MIXED, backend="process", workers=2, batch_size=1, progress=False)
    assert _bits(table) == _bits(serial_table)


def test_a_crashing_candidate_becomes_an_error_row_after_its_retries(tmp_path, monkeypatch):
    monkeypatch.setenv(sp.CRASH_DIR, str(tmp_path))
    study = Study(cell="joints", program=sp.crash_at_far_x, vary=CRASHY)
    table = run(study, backend="process", workers=2, retries=1, progress=False)
    rows = table.to_pylist()
    assert [r["feasible"] for r in rows] == [True, True, False, False]
    for r in rows[2:]:
        assert r["error_type"] == "WorkerCrashed"
        assert r["error"] == "WorkerCrashed: " + CRASH_MESSAGE.format(1)
    for x in (0.2, 0.3):  # tried once, retried once
        assert len((tmp_path / f"attempt-{x:.3f}").read_text().split()) == 2
    fine = run(Study(cell="joints", vary=CRASHY), backend="serial", progress=False)
    assert rows[:2] == fine.to_pylist()[:2]


def test_a_candidate_that_crashes_once_succeeds_on_retry(tmp_path, monkeypatch):
    monkeypatch.setenv(sp.CRASH_DIR, str(tmp_path))
    study = Study(cell="joints", program=sp.crash_once_at_far_x, vary=CRASHY)
    table = run(study, backend="process", workers=2, progress=False)
    fine = run(Study(cell="joints", vary=CRASHY), backend="serial", progress=False)
    assert table.to_pylist() == fine.to_pylist()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["attempt-0.200", "attempt-0.300"]


def test_a_program_workers_cannot_import_is_refused_clearly():
    study = Study(cell="joints", program=lambda sim: None, vary={"puma.base.x": "0,1"})
    with pytest.raises(StudyError, match="module level"):
        run(study, backend="process", workers=1, progress=False)
    assert run(study, backend="serial", progress=False).num_rows == 2


def test_backend_options_are_checked():
    study = Study(cell="joints", vary={"puma.base.x": "0,1"})
    with pytest.raises(StudyError, match="unknown backend"):
        run(study, backend="threads")
    with pytest.raises(StudyError, match="workers must be"):
        run(study, workers=0)
    with pytest.raises(StudyError, match="for the ray backend"):
        run(study, backend="process", address="auto")


# ---------------------------------------------------------------------------- Ray
@pytest.fixture(scope="module")
def local_ray(tmp_path_factory):
    """A local Ray of 2 CPUs, usage stats off, its files in the test session's temporary
    folder (a short path of its own: Ray's socket paths must stay under 108 bytes)."""
    ray = pytest.importorskip("ray")
    from ray import cloudpickle

    crash_dir = tmp_path_factory.mktemp("crash")
    ray_dir = tempfile.mkdtemp(prefix="ray-")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("RAY_USAGE_STATS_ENABLED", "0")
        mp.setenv("RAY_AUTH_MODE", "disabled")
        mp.setenv(sp.CRASH_DIR, str(crash_dir))  # Ray's workers inherit it
        cloudpickle.register_pickle_by_value(sp)  # Ray's workers cannot import the tests
        ray.init(
            num_cpus=2,
            include_dashboard=False,
            log_to_driver=False,
            _temp_dir=ray_dir,
        )
        try:
            yield crash_dir
        finally:
            ray.shutdown()
            cloudpickle.unregister_pickle_by_value(sp)
            shutil.rmtree(ray_dir, ignore_errors=True)


@pytest.mark.slow
def test_ray_gives_the_same_rows_bit_for_bit(local_ray, serial_table):
    table = run(MIXED, backend="ray", batch_size=3, progress=False)
    assert _bits(table) == _bits(serial_table)


@pytest.mark.slow
def test_ray_retries_a_killed_worker_then_writes_an_error_row(local_ray):
    study = Study(cell="joints", program=sp.crash_at_far_x, vary={"puma.base.x": "0,0.1,0.3"})
    # batches [0, 0.1] and [0.3]: the second dies, Ray retries it once (retries=1), then
    # its candidate gets the error row; with batches of 2 at retries=0, a dead batch is
    # split and only its killer gets the error row
    for size, retries in ((2, 1), (3, 0)):
        table = run(study, backend="ray", batch_size=size, retries=retries, progress=False)
        rows = table.to_pylist()
        assert [r["feasible"] for r in rows] == [True, True, False]
        assert rows[2]["error"] == "WorkerCrashed: " + CRASH_MESSAGE.format(retries)
    # 2 attempts, then 1 for the whole batch and 1 for the candidate alone
    assert len((local_ray / "attempt-0.300").read_text().split()) == 4


@pytest.mark.slow
def test_a_script_without_a_main_guard(tmp_path):
    """Alone, a script's workers are forks of it: no main guard needed. With a thread
    running, workers come from the fork server, which imports the main script: without
    the guard the study stops with a StudyError that says what to do."""
    body = (
        "from workcell.study import Study, run\n"
        "table = run(Study(cell='joints', vary={'puma.base.x': '0,0.1'}), workers=1)\n"
        "print(table.num_rows, 'rows')\n"
    )
    thread = "import threading, time\nthreading.Thread(target=time.sleep, args=(60,), daemon=True).start()\n"
    for name, text in (("alone.py", body), ("threaded.py", thread + body)):
        (tmp_path / name).write_text(text)
    alone = subprocess.run(
        [sys.executable, "alone.py"], capture_output=True, text=True, timeout=300, cwd=tmp_path
    )
    assert alone.returncode == 0, alone.stderr[-2000:]
    assert "2 rows" in alone.stdout
    threaded = subprocess.run(
        [sys.executable, "threaded.py"], capture_output=True, text=True, timeout=300, cwd=tmp_path
    )
    assert threaded.returncode != 0
    assert "if __name__ == '__main__':" in threaded.stderr
    assert "StudyError" in threaded.stderr


def test_without_ray_the_ray_backend_says_how_to_get_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray fails as if not installed
    study = Study(cell="joints", vary={"puma.base.x": "0,1"})
    with pytest.raises(StudyError, match=r"pip install 'workcell\[cluster\]'"):
        run(study, backend="ray", progress=False)
