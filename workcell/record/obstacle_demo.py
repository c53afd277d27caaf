"""``workcell demo obstacle``: the obstacle cell's two programs side by side, and a picture.

:func:`demo` runs the direct program and the task-level program of
:mod:`workcell.examples.obstacle` on the same cell, lists the direct program's collisions
and what the task-level run did, and writes what is asked for: :func:`picture` (both tool
paths over the end of the task-level run), a recording of the task-level run, the cell
as MJCF. (Moved here from the example, which sits below the recording layer.)
"""

from __future__ import annotations

import json
import time
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from workcell.examples.obstacle import (
    DIRECT_COLOUR,
    PLANNED_COLOUR,
    build,
    compare,
    tool_path,
)
from workcell.record.demo_files import write_asked

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["demo", "picture"]


def picture(
    direct: Simulator, planned: Simulator, *, width: int = 800, height: int = 600
) -> NDArray[np.uint8]:
    """The cell at the end of the task-level run with both tool paths: the direct
    program's in red, the task-level program's in green."""
    import mujoco

    from workcell.record.render import CellRenderer

    data = mujoco.MjData(planned.model)
    data.qpos[:] = planned.timeline.frame(-1)[2]
    mujoco.mj_forward(planned.model, data)
    paths = [(tool_path(direct), DIRECT_COLOUR), (tool_path(planned), PLANNED_COLOUR)]
    with CellRenderer(planned.model, width, height) as r:
        return r.render(data, "overview", paths=paths)


def demo(
    mode: str,
    dt: float,
    *,
    render: str | None = None,
    as_json: bool = False,
    save: str | None = None,
    mjcf: str | None = None,
) -> int:
    """``workcell demo obstacle``: both programs, the direct one's collisions, the picture
    (``render``); ``save``: record the task-level run (.rrd); ``mjcf``: export the cell."""
    t0 = time.perf_counter()
    direct, planned = compare(mode, dt)
    hits = [e for e in direct.events if e.kind == "collision"]
    out: dict[str, Any] = {
        "direct": direct.summary(),
        "planned": planned.summary(),
        "collisions": {"direct": len(hits), "planned": planned.summary()["collisions"]},
    }
    write_asked(
        out, render=render, picture=lambda: picture(direct, planned), save=save,
        recorded=planned, mjcf=mjcf, build=build, quiet=as_json,
    )  # fmt: skip
    if as_json:
        print(json.dumps(out))
        return 0
    print("A wall between two stages: the cube goes from stage_1 to stage_2\n")
    print(f"direct program (poses by hand, joint-space moves): {len(hits)} collision(s)")
    for e in hits:
        print(f"  t = {e.t:8.3f} s  {e.detail}")
    n = out["collisions"]["planned"]
    print(f"\npick/place program (task level, planned paths): {n} collision(s)")
    for e in planned.events:
        if e.kind in ("move", "grasp", "release", "settle", "warning", "collision"):
            print(f"  t = {e.t:8.3f} s  {e.kind:9s} {e.detail}")
    for name, pos in planned.part_positions().items():
        print(f"{name} ends at ({', '.join(f'{v:.4f}' for v in pos)}) m")
    print(
        f"simulated time: direct {direct.sim_time:.2f} s, task level {planned.sim_time:.2f} s; "
        f"total {time.perf_counter() - t0:.2f} s"
    )
    if render:
        print(f"picture written to {out['png']} (red: direct program, green: pick/place)")
    for key, what in (("rrd", "recording of the pick/place run"), ("mjcf", "cell")):
        if key in out:
            print(f"{what} written to {out[key]}")
    return 0
