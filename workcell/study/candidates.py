"""The candidates of a study: the full grid, or a seeded random sample.

Candidate ``i`` is the i-th cell variant; its number is stable: the same study gives the
same candidates with the same numbers on every machine (numpy's PCG64 generator seeded
with ``Study.seed``), which is what lets a re-run skip the candidates already done.

- Full grid: every combination of the parameters' values, the last parameter varying
  fastest (row-major, like ``itertools.product``).
- ``sample=N`` with only lists and grid axes: N distinct grid points drawn without
  replacement (N at most the grid's size), numbered in the order drawn.
- ``sample=N`` with a range ``LO:HI``: each candidate draws each range uniformly in
  [LO, HI) and each list or grid axis uniformly among its values, parameter by parameter
  (N draws for the first parameter, then N for the second, ...).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from workcell.errors import StudyError
from workcell.study.spec import Parameter, Study

__all__ = ["Candidate", "candidates"]


@dataclass(frozen=True)
class Candidate:
    """One cell variant: its number and one value per parameter (in the study's order)."""

    id: int
    values: tuple[float | str, ...]

    def as_dict(self, parameters: tuple[Parameter, ...]) -> dict[str, float | str]:
        """Parameter name -> value."""
        return {p.name: v for p, v in zip(parameters, self.values, strict=True)}


def candidates(study: Study) -> list[Candidate]:
    """Every candidate of ``study``, numbered from 0 (module doc)."""
    params = study.parameters
    if study.sample is None:
        grid = itertools.product(*(p.values for p in params))
        return [Candidate(i, tuple(v)) for i, v in enumerate(grid)]
    n = study.sample
    rng = np.random.Generator(np.random.PCG64(study.seed))
    if all(p.discrete for p in params):
        shape = tuple(len(p.values) for p in params)
        size = math.prod(shape)
        if n > size:
            raise StudyError(
                f"sample={n} is more than the {size} distinct candidates of the grid; "
                "sample at most that many, give ranges LO:HI, or run the full grid"
            )
        picks = rng.choice(size, size=n, replace=False)
        index = np.unravel_index(picks, shape)
        return [
            Candidate(i, tuple(p.values[int(index[k][i])] for k, p in enumerate(params)))
            for i in range(n)
        ]
    columns: list[list[float | str]] = []
    for p in params:
        if p.discrete:
            columns.append([p.values[int(j)] for j in rng.integers(0, len(p.values), size=n)])
        else:
            columns.append([float(v) for v in rng.uniform(p.low, p.high, size=n)])
    return [Candidate(i, tuple(col[i] for col in columns)) for i in range(n)]
