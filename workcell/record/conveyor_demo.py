"""``workcell demo conveyor``: the conveyor cell's two programs run together, its
throughput and utilisation, a picture and a recording.

:func:`demo` runs :mod:`workcell.examples.conveyor` (a belt, a light beam, a UR5e stacking
boxes, a cell controller), prints the boxes per hour and each robot's moving / waiting /
idle time (or one JSON object), and writes :func:`picture` (two views of the run above the
Gantt chart), a recording and the cell as MJCF when asked. (Here, not in the example: the
examples sit below the recording layer.)
"""

from __future__ import annotations

import json
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell.examples.conveyor import build, run
from workcell.record.demo_files import write_asked
from workcell.sim.simulator import Simulator

__all__ = ["demo", "picture"]


def picture(sim: Simulator, *, width: int = 1280) -> NDArray[np.uint8]:
    """Two views of the run side by side (the cell as the 6th box is gripped at the beam,
    the beam red; the end, all boxes stacked) above the Gantt chart of both programs."""
    from workcell.record.gantt import gantt_chart
    from workcell.record.render import render_frame

    grasps = [e.frame for e in sim.events if e.kind == "grasp"]
    busy = grasps[min(5, len(grasps) - 1)] if grasps else 0
    w = width // 2
    h = w * 3 // 4
    top = np.hstack(
        [render_frame(sim, f, camera="overview", width=w, height=h) for f in (busy, -1)]
    )
    chart = gantt_chart(sim, width=2 * w)
    return np.vstack([top, chart])


def demo(
    mode: str,
    dt: float,
    *,
    render: str | None = None,
    as_json: bool = False,
    save: str | None = None,
    mjcf: str | None = None,
    physics: bool = False,
    record_fps: float | None = 60.0,
) -> int:
    """``workcell demo conveyor``: run it, print throughput and utilisation (or one JSON
    object), write the picture (``render``), the recording (``save``) and the MJCF."""
    t0 = time.perf_counter()
    sim = run(mode, dt)
    out = sim.summary()
    result: Any = sim
    if physics:
        from workcell.sim.physics import run_physics

        result = run_physics(sim, progress=not as_json)
        out["physics"] = result.summary().get("physics")
    tp = out["throughput"]
    placed = tp["signals"]["placed"]
    write_asked(
        out, render=render, picture=lambda: picture(sim), save=save, recorded=result,
        mjcf=mjcf, build=build, quiet=as_json, fps=record_fps,
    )  # fmt: skip
    if as_json:
        print(json.dumps(out))
        return 0
    print("A belt brings boxes, a light beam stops it, a UR5e stacks them on a pallet\n")
    for e in sim.events:
        if e.kind in ("source", "signal", "grasp", "release") and not (
            e.kind == "signal" and "(sensor)" not in e.detail and e.robot is None
        ):
            print(f"  t = {e.t:8.3f} s  {e.robot or '-':10s} {e.kind:7s} {e.detail}")
    print(
        f"\n{placed['rising']} boxes stacked in {tp['time_s']:.2f} s of simulated time: "
        f"throughput {placed['per_hour']:.0f} boxes per hour"
    )
    for robot, f in tp["robots"].items():
        print(
            f"{robot}: moving {f['moving'] * 100:.1f} %, waiting {f['waiting'] * 100:.1f} %, "
            f"idle {f['idle'] * 100:.1f} % of the time"
        )
    if physics:
        worst = max(t.tool_max for t in result.tracking.values())
        moved = max((p.distance for p in result.parts.values()), default=0.0)
        resting = sum(p.resting for p in result.parts.values())
        print(
            f"physics (mj_step, belts through surfacevel): tool within {worst * 1e3:.3g} mm of "
            f"the plan, {resting} of {len(result.parts)} boxes resting, within "
            f"{moved * 1e3:.3g} mm of the kinematic result"
        )
    print(f"{sim.frames} frames at dt = {dt:g} s; {out['collisions']} collision(s); "
          f"total {time.perf_counter() - t0:.2f} s")  # fmt: skip
    for key, what in (("png", "picture"), ("rrd", "recording"), ("mjcf", "cell")):
        if out.get(key):
            print(f"{what} written to {out[key]}")
    return 0
