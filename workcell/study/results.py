"""Results on disk: ``DIR/results.parquet``, written as the study runs, and a study re-run
into the same folder skips what is done.

- ``DIR/study.json``: what the study is (its description and fingerprint, see
  :mod:`workcell.study.prepare`); a re-run of another study into DIR is refused.
- ``DIR/parts/part-*.parquet``: rows as they arrive, one small file at least every second
  of progress (each written to a hidden temp file and renamed: a file is whole or absent;
  temp files a killed run left are deleted on the next).
- ``DIR/results.parquet``: every row so far, one per candidate, sorted by candidate;
  rewritten (atomically, through :func:`workcell.files.atomic_path`) from itself and the
  parts every ``merge_seconds`` and at the end, after which the merged parts are deleted.

A killed study loses at most the rows of its last second; on the next run the rows of
``results.parquet`` and of every part are read back (a row in both counts once) and only
the other candidates run. Every file is pyarrow Parquet with one schema: ``candidate``
(int64), one column per parameter (float64, or string for robot names), then the
result columns of :mod:`workcell.study.evaluation`.
"""

from __future__ import annotations

import json
import os
import stat
import time
import uuid
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from workcell.errors import StudyError
from workcell.files import atomic_path, atomic_write_text, read_text
from workcell.study.evaluation import RESULT_COLUMNS
from workcell.study.spec import Parameter

__all__ = ["RESULTS", "ResultStore", "best_rows", "schema", "summary"]

RESULTS = "results.parquet"
STUDY_FILE = "study.json"
PARTS = "parts"
_TYPES = {
    "feasible": pa.bool_(),
    "clearance_pair": pa.string(),
    "error_type": pa.string(),
    "error": pa.string(),
}


def schema(parameters: Sequence[Parameter]) -> pa.Schema:
    """The results' schema for a study's ``parameters``."""
    fields = [pa.field("candidate", pa.int64())]
    fields += [pa.field(p.name, pa.string() if p.text else pa.float64()) for p in parameters]
    fields += [pa.field(c, _TYPES.get(c, pa.float64())) for c in RESULT_COLUMNS]
    return pa.schema(fields)


def _unique_sorted(table: pa.Table) -> pa.Table:
    """One row per candidate (the first seen), sorted by candidate."""
    ids = table.column("candidate").to_numpy()
    _, first = np.unique(ids, return_index=True)
    return table.take(pa.array(first))


class ResultStore:
    """The rows of one study, in memory and (with ``out``) in ``out`` (module doc)."""

    def __init__(
        self,
        out: str | Path | None,
        schema: pa.Schema,
        info: dict[str, Any],
        key: str,
        *,
        flush_seconds: float = 1.0,
        merge_seconds: float = 10.0,
    ) -> None:
        self.schema = schema
        self.out = None if out is None else Path(out)
        self.flush_seconds, self.merge_seconds = flush_seconds, merge_seconds
        self._pending: list[dict[str, Any]] = []
        self._tables: list[pa.Table] = []
        self._parts: list[Path] = []
        self._last_flush = self._last_merge = time.monotonic()
        if self.out is not None:
            self._open(self.out, info, key)
        self.finished: set[int] = set()
        for t in self._tables:
            self.finished.update(t.column("candidate").to_pylist())

    def _open(self, out: Path, info: dict[str, Any], key: str) -> None:
        _own_folder(out / PARTS)
        try:
            (out / PARTS).mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise StudyError(f"cannot create output folder '{out}': {exc}") from exc
        study = out / STUDY_FILE
        if study.exists():
            try:
                old = json.loads(read_text(study, what="study file", error=StudyError))
            except (StudyError, ValueError) as exc:
                raise StudyError(f"'{study}' is damaged ({exc}); use another folder") from exc
            if old.get("key") != key:
                differ = sorted(k for k in info if old.get("study", {}).get(k) != info[k])
                raise StudyError(
                    f"'{out}' holds the results of another study (it differs in: "
                    f"{', '.join(differ) or 'its version'}); use another --out folder, "
                    "or delete that one to start again"
                )
        else:
            atomic_write_text(study, json.dumps({"key": key, "study": info}, indent=2))
        for tmp in [*out.glob(f".{RESULTS}.*"), *(out / PARTS).glob(".part-*")]:
            tmp.unlink(missing_ok=True)  # half-written by a killed run
        files = [out / RESULTS] if (out / RESULTS).exists() else []
        self._parts = sorted((out / PARTS).glob("part-*.parquet"))
        for f in files + self._parts:
            if not stat.S_ISREG(os.lstat(f).st_mode):  # a FIFO would block the reader
                raise StudyError(f"'{f}' is not a regular file; remove it or use another folder")
            try:
                t = pq.read_table(f)
            except (OSError, pa.ArrowException) as exc:
                raise StudyError(f"cannot read results file '{f}': {exc}") from exc
            if t.schema != self.schema:
                raise StudyError(f"'{f}' has other columns than this study's results")
            self._tables.append(t)

    @property
    def count(self) -> int:
        """Rows so far (finished candidates)."""
        return len(self.finished)

    def add(self, rows: Iterable[dict[str, Any]]) -> None:
        """Keep ``rows``; write a part file when a second has passed since the last one."""
        for row in rows:
            if row["candidate"] in self.finished:
                continue
            self.finished.add(row["candidate"])
            self._pending.append(row)
        now = time.monotonic()
        if now - self._last_flush >= self.flush_seconds:
            self.flush()
        if self.out is not None and now - self._last_merge >= self.merge_seconds:
            self.merge()

    def flush(self) -> None:
        """Write the rows not yet on disk as a part file (in memory without ``out``)."""
        self._last_flush = time.monotonic()
        if not self._pending:
            return
        table = pa.Table.from_pylist(self._pending, schema=self.schema)
        self._pending = []
        self._tables.append(table)
        if self.out is None:
            return
        path = self.out / PARTS / f"part-{time.time_ns()}-{uuid.uuid4().hex[:8]}.parquet"
        with atomic_path(path, suffix=".parquet") as tmp:
            pq.write_table(table, tmp)
        self._parts.append(path)

    def table(self) -> pa.Table:
        """Every row so far, one per candidate, sorted by candidate."""
        self.flush()
        if not self._tables:
            return self.schema.empty_table()
        table = _unique_sorted(pa.concat_tables(self._tables))
        self._tables = [table]
        return table

    def merge(self) -> pa.Table:
        """Rewrite ``results.parquet`` with every row so far, then delete the merged parts."""
        table = self.table()
        self._last_merge = time.monotonic()
        if self.out is None:
            return table
        with atomic_path(self.out / RESULTS, suffix=".parquet") as tmp:
            pq.write_table(table, tmp)
        _own_folder(self.out / PARTS)  # still the study's own folder, not a link elsewhere
        for p in self._parts:
            p.unlink(missing_ok=True)
        self._parts = []
        return table


def _own_folder(parts: Path) -> None:
    """StudyError unless ``parts`` is missing or a real folder: a symbolic link there
    would make the study read, and delete, files of another folder."""
    try:
        st = os.lstat(parts)
    except FileNotFoundError:
        return
    except OSError as exc:
        raise StudyError(f"cannot use '{parts}': {exc.strerror or exc}") from exc
    if stat.S_ISLNK(st.st_mode) or not stat.S_ISDIR(st.st_mode):
        what = "a symbolic link" if stat.S_ISLNK(st.st_mode) else "not a folder"
        raise StudyError(
            f"'{parts}' is {what}: a study keeps its part files in a folder of its own and "
            "deletes them once merged, so it reads and deletes nothing through it; remove "
            "it or use another --out folder"
        )


def best_rows(table: pa.Table, n: int) -> list[dict[str, Any]]:
    """The ``n`` feasible rows of shortest cycle time (ties: lower candidate first)."""
    rows = [r for r in table.to_pylist() if r["feasible"]]
    rows.sort(key=lambda r: (r["cycle_time_s"], r["candidate"]))
    return rows[:n]


def _cell(v: object, digits: int) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.{digits}f}"
    return str(v)


def summary(table: pa.Table, parameters: Sequence[Parameter], top: int = 5) -> str:
    """A text table of the ``top`` best candidates, and the counts of errors by type."""
    n = table.num_rows
    rows = table.to_pylist()
    feasible = sum(1 for r in rows if r["feasible"])
    lines = [f"{feasible} of {n} candidates feasible"]
    errors: dict[str, int] = {}
    for r in rows:
        if not r["feasible"]:
            errors[r["error_type"]] = errors.get(r["error_type"], 0) + 1
    if errors:
        lines[0] += "; infeasible: " + ", ".join(
            f"{k} {v}" for k, v in sorted(errors.items(), key=lambda kv: -kv[1])
        )
    best = best_rows(table, top)
    if not best:
        return "\n".join(lines)
    cols = [
        ("candidate", "candidate", 0),
        *((p.name, f"{p.name} ({p.unit})", 4) for p in parameters),
        ("cycle_time_s", "cycle (s)", 3),
        ("min_clearance_m", "clearance (mm)", 1),
        ("reach_margin_m", "reach margin (mm)", 1),
        ("joint_limit_margin_deg", "joint margin (deg)", 1),
    ]
    mm = {"min_clearance_m", "reach_margin_m"}
    body = [
        [_cell(r[k] * 1e3 if k in mm and r[k] is not None else r[k], d) for k, _, d in cols]
        for r in best
    ]
    heads = [h for _, h, _ in cols]
    widths = [max(len(h), *(len(row[i]) for row in body)) for i, h in enumerate(heads)]
    lines.append(f"best {len(best)} by cycle time:")
    lines.append("  ".join(h.rjust(w) for h, w in zip(heads, widths, strict=True)))
    lines += ["  ".join(c.rjust(w) for c, w in zip(row, widths, strict=True)) for row in body]
    return "\n".join(lines)
