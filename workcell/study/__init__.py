"""Studies over many cells (beyond the thesis): one program run on a grid or a random
sample of cell variants (robot placements, robot choices, speeds, part positions),
headless, on one core, a local process pool or a Ray cluster, with results written as
they come to ``results.parquet`` and picked up again after an interruption.

>>> from workcell.study import Study, run
>>> table = run(Study(cell="pick-place", vary={"puma.base.x": "-0.05:0.05:3"}),
...             backend="serial")  # doctest: +SKIP

Modules: :mod:`~workcell.study.spec` (what varies), :mod:`~workcell.study.candidates`,
:mod:`~workcell.study.program`, :mod:`~workcell.study.variants` (cells without
recompiling), :mod:`~workcell.study.evaluation` and :mod:`~workcell.study.metrics` (one
candidate's row), :mod:`~workcell.study.backends` and :mod:`~workcell.study.pool`,
:mod:`~workcell.study.results`, :mod:`~workcell.study.plots`,
:mod:`~workcell.study.runner`, :mod:`~workcell.study.cli`.
"""

from __future__ import annotations

import importlib
from typing import Any

_LAZY = {  # imported on first use (``workcell --help`` stays light)
    "Candidate": "workcell.study.candidates",
    "Outcome": "workcell.study.runner",
    "execute": "workcell.study.runner",
    "run": "workcell.study.runner",
    "Parameter": "workcell.study.spec",
    "Study": "workcell.study.spec",
    "parameter": "workcell.study.spec",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'workcell.study' has no attribute {name!r}")
