"""Names that moved to another module keep working at their old place for one release.

A module whose names moved up the layers (docs/architecture.md, "Layers": imports run
one way) cannot import them back; it sets ``__getattr__ = moved(__name__, {name: new
module})`` instead. The old spelling then finds the name where it lives now, on first
use, with a :class:`DeprecationWarning` naming the new place; the old spellings go in
the release after. (The import-graph test reads these tables: they are the only
references that may point up, and only to modules that exist.)
"""

from __future__ import annotations

import importlib
import warnings
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["moved"]


def moved(module: str, names: Mapping[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``module`` resolving each of ``names`` (name -> the
    module it lives in now) there, with a DeprecationWarning; other names: AttributeError."""
    table = dict(names)

    def lookup(name: str) -> Any:
        if name not in table:
            raise AttributeError(f"module {module!r} has no attribute {name!r}")
        warnings.warn(
            f"{module}.{name} moved to {table[name]}.{name}; the old name goes in the next release",
            DeprecationWarning,
            stacklevel=2,
        )
        return getattr(importlib.import_module(table[name]), name)

    lookup.moved = table  # type: ignore[attr-defined]  (for the import-graph test)
    return lookup
