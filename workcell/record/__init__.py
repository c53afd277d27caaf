"""Recording and pictures (issue 5): the rerun timeline writer, offscreen renders and video.

Names are imported on first use (``workcell --help`` stays light): ``record``,
``log_timeline``, ``default_blueprint`` and ``RecordStats`` from
:mod:`workcell.record.rerun_log`; ``render_frame``, ``render_cell``, ``save_png``,
``contact_sheet``, ``save_mp4``, ``key_frames``, ``overview_camera`` and ``CellRenderer``
from :mod:`workcell.record.render`.
"""

from __future__ import annotations

import importlib
from typing import Any

from workcell.errors import RecordError, RenderError

_LAZY = {
    "RecordStats": "workcell.record.rerun_log",
    "check_recording_path": "workcell.cli_common",
    "default_blueprint": "workcell.record.rerun_log",
    "log_timeline": "workcell.record.rerun_log",
    "record": "workcell.record.rerun_log",
    "CellRenderer": "workcell.record.render",
    "KeyFrame": "workcell.record.render",
    "contact_sheet": "workcell.record.render",
    "gl_backend": "workcell.record.render",
    "key_frames": "workcell.record.render",
    "overview_camera": "workcell.record.render",
    "render_cell": "workcell.record.render",
    "render_frame": "workcell.record.render",
    "save_mp4": "workcell.record.render",
    "save_png": "workcell.record.render",
}

__all__ = ["RecordError", "RenderError", *sorted(_LAZY)]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'workcell.record' has no attribute {name!r}")
