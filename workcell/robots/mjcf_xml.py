"""MJCF text at full double precision: MuJoCo's XML writer switched to 17 digits.

Used by :mod:`workcell.robots.mjcf` (``export_robot``) and :mod:`workcell.cell.compile`;
:func:`spec_to_xml` is re-exported by :mod:`workcell.robots.mjcf`.
"""

from __future__ import annotations

import ctypes
import functools
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import mujoco

__all__ = ["spec_to_xml"]


@functools.cache
def _xml_format_hooks() -> tuple[ctypes._CFuncPtr, ctypes._CFuncPtr] | None:
    """MuJoCo's (get, set) hooks of its XML significant digits; None when unusable.

    mujoco 3.17 exports ``int _mjPRIVATE__get_xml_precision()`` and
    ``void _mjPRIVATE__set_xml_precision(int)`` (a thread-local digit count, default 6);
    other releases differ (some take a printf format), so the hooks are used only on
    3.17 and only when the current value looks like a digit count.
    """
    if not mujoco.__version__.startswith("3.17."):
        return None
    here = Path(mujoco.__file__).parent
    for pattern in ("libmujoco.so*", "libmujoco*.dylib", "mujoco.dll"):
        for path in sorted(here.glob(pattern)):
            try:
                lib = ctypes.CDLL(str(path))
                get, put = lib._mjPRIVATE__get_xml_precision, lib._mjPRIVATE__set_xml_precision
            except (OSError, AttributeError):
                continue
            get.restype, get.argtypes = ctypes.c_int, []
            put.restype, put.argtypes = None, [ctypes.c_int]
            return (get, put) if 0 < get() <= 30 else None
    return None


@contextmanager
def _full_precision() -> Iterator[None]:
    """Make MuJoCo's XML writer print 17 significant digits (its default prints 6).

    The setting is thread-local in MuJoCo: set, used and restored in the calling thread.
    """
    hooks = _xml_format_hooks()
    if hooks is None:
        warnings.warn(
            "MuJoCo's XML number precision cannot be set in this release: the saved XML "
            "has 6 significant digits (tool poses off by ~1e-7 m)",
            stacklevel=3,
        )
        yield
        return
    get, put = hooks
    old = get()
    put(17)
    try:
        yield
    finally:
        put(old)


def spec_to_xml(spec: mujoco.MjSpec) -> str:
    """MJCF text of ``spec`` with every number at full double precision.

    MuJoCo's writer prints 6 significant digits by default, which moves a saved robot's
    tool by ~1e-7 m; this switches it to 17 for the call (through the library's exported
    XML-precision hook, a private symbol of mujoco 3.17; elsewhere it warns and keeps 6). Raises ValueError as
    ``spec.to_xml`` does when the spec does not compile.
    """
    with _full_precision():
        return spec.to_xml()
