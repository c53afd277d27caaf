"""What a demo writes when asked (``workcell demo conveyor``, ``workcell demo obstacle``):
a picture, a recording of a run, the cell as MJCF.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["write_asked"]


def write_asked(
    out: dict[str, Any],
    *,
    render: str | None,
    picture: Callable[[], NDArray[np.uint8]],
    save: str | None,
    recorded: Any,
    mjcf: str | None,
    build: Callable[[], Any],
    quiet: bool,
    **record_options: Any,
) -> None:
    """Write what was asked and put the paths into ``out`` ("png", "rrd", "mjcf"):
    ``render``: the PNG of ``picture()``; ``save``: the recording (.rrd) of ``recorded``
    (a simulator or a physics run; a progress bar unless ``quiet``; ``record_options`` go
    to :func:`~workcell.record.record`); ``mjcf``: the cell ``build()`` makes, exported
    into that folder."""
    if render:
        from workcell.record.render import save_png

        out["png"] = str(save_png(picture(), render))
    if save:
        from workcell.record import record

        stats = record(recorded, save, progress=None if quiet else True, **record_options)
        out["rrd"] = str(stats.path)
    if mjcf:
        from workcell.cell import export_cell

        out["mjcf"] = str(export_cell(build(), mjcf))
