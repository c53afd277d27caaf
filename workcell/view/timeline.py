"""The timeline panel of the live view: the frame slider, the events, the tool paths and
the cycle-time report.

The slider scrubs every frame of what has run (:meth:`TimelinePanel.show_frame` poses
the scene from a scratch copy of the state, collisions of that frame in red; the
simulator is not changed) and follows the live frame while a program runs; choosing an
event shows its frame. The event list shows the latest events (collisions and errors in
red); the tool paths are the robots' FK of the timeline's joints, a point per
millimetre, drawn as lines; the cycle-time report is
:func:`workcell.sim.cycle.format_table` of the run.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from workcell.errors import ProgramError
from workcell.sim.cycle import format_table
from workcell.sim.timeline import Event

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator
    from workcell.view.viewer import Viewer

__all__ = ["PALETTE", "TimelinePanel"]

PALETTE = [(230, 80, 40), (40, 120, 230), (40, 170, 80), (200, 60, 200), (220, 180, 30)]
_EVENTS_SHOWN = 14
_PATH_STEP = 1e-3  # m: tool path points closer than this along the path are dropped


class TimelinePanel:
    """Slider, events, tool paths and cycle-time report (module doc)."""

    def __init__(self, viewer: Viewer) -> None:
        self.viewer = viewer
        gui = viewer.server.gui
        with gui.add_folder("Timeline"):
            self.slider = gui.add_slider("frame", min=0, max=1, step=1, initial_value=0)
            self.slider.on_update(self._slider_moved)
            self.paths_box = gui.add_checkbox("tool paths", True)
            self.paths_box.on_update(lambda e: self.draw_paths())
            self.event_choice = gui.add_dropdown("go to event", ("-",), initial_value="-")
            self.event_choice.on_update(self._event_chosen)
            self.events_md = gui.add_markdown("no events yet")
        with gui.add_folder("Cycle time", expand_by_default=False):
            self.cycle_md = gui.add_markdown("")
        self._paths: dict[str, tuple[int, list[np.ndarray]]] = {}
        self._scratch: mujoco.MjData | None = None

    def reset(self, sim: Simulator) -> None:
        """Start over for another simulator."""
        self._paths = {}
        self._scratch = mujoco.MjData(sim.model)

    def draw(self) -> None:
        """Events, report and tool paths from the simulator."""
        self.events()
        self.draw_paths()

    def events(self) -> None:
        """The latest events, the event chooser and the cycle-time report."""
        sim = self.viewer.sim
        assert sim is not None
        evs = sim.events
        rows = []
        for e in evs[-_EVENTS_SHOWN:]:
            text = f"{e.t:.3f} s · {e.robot or 'cell'} · {e.kind}: {e.detail}"
            rows.append(f"- <span style='color:#d01010'>{text}</span>" if e.kind in
                        ("collision", "error") else f"- {text}")  # fmt: skip
        more = f"\n\n({len(evs) - _EVENTS_SHOWN} earlier)" if len(evs) > _EVENTS_SHOWN else ""
        self.events_md.content = "\n".join(rows) + more if rows else "no events yet"
        options = ["-", *(_event_label(i, e) for i, e in enumerate(evs))][-200:]
        self.event_choice.options = tuple(options)
        self.cycle_md.content = "```\n" + format_table(sim.cycle_time()) + "\n```"

    def draw_paths(self) -> None:
        """Tool paths: the tool points of every frame so far (the robots' FK of the
        timeline's joints), a point per millimetre of path."""
        sim, scene = self.viewer.sim, self.viewer.scene
        assert sim is not None
        assert scene is not None
        if not self.paths_box.value:
            for h in scene.paths.values():
                h.visible = False
            return
        n = len(sim.timeline)
        for i, robot in enumerate(sim.robots):
            done, pts = self._paths.get(robot, (0, []))
            if done > n:
                done, pts = 0, []
            if done < n:
                placement = sim.cell.robots[robot]
                Q = sim.timeline.qpos(done, n)[:, sim._qadr[robot]]
                P = (placement.base @ placement.robot.fk_batch(Q))[:, :3, 3]
                pts = [*pts, *_thin(P, pts[-1] if pts else None)]
            self._paths[robot] = (n, pts)
            scene.set_path(robot, np.array(pts).reshape(-1, 3), PALETTE[i % len(PALETTE)])

    def follow(self, frame: int, n: int) -> None:
        """The slider at ``frame`` of ``n`` frames."""
        self.slider.max = max(1, n - 1, frame)
        self.slider.value = frame

    def show_frame(self, frame: int) -> None:
        """Show frame ``frame`` of the timeline (the simulator's state is not changed)."""
        v = self.viewer
        sim = v.sim
        assert sim is not None
        assert self._scratch is not None
        n = len(sim.timeline)
        if not 0 <= frame < n:
            raise ProgramError(f"show_frame: frame must be 0 ... {n - 1}, got {frame!r}")
        t, _, q = sim.timeline.frame(frame)
        d = self._scratch
        d.qpos[:] = q
        mujoco.mj_kinematics(sim.model, d)
        mujoco.mj_collision(sim.model, d)
        v._push(frame, t, d)

    def _slider_moved(self, event: Any) -> None:
        v = self.viewer
        if event.client is None or v.sim is None or v.busy:
            return
        frame = int(self.slider.value)
        if frame >= len(v.sim.timeline) - 1:
            v.refresh()
        else:
            self.show_frame(frame)

    def _event_chosen(self, event: Any) -> None:
        v = self.viewer
        if event.client is None or v.sim is None or self.event_choice.value == "-":
            return
        k = int(self.event_choice.value.split(" ", 1)[0].lstrip("#"))
        evs = v.sim.events
        if 0 <= k < len(evs) and not v.busy:
            self.show_frame(max(0, min(evs[k].frame, len(v.sim.timeline) - 1)))


def _thin(P: np.ndarray, last: np.ndarray | None) -> list[np.ndarray]:
    """Points of P (k, 3) a path length of _PATH_STEP or more apart, after ``last``."""
    if len(P) == 0:
        return []
    start = P[0] if last is None else last
    seg = np.linalg.norm(np.diff(np.vstack([start, P]), axis=0), axis=1)
    steps = np.floor(np.cumsum(seg) / _PATH_STEP)
    keep = np.flatnonzero(np.diff(np.concatenate([[0.0], steps])) > 0)
    out = [P[k] for k in keep]
    if last is None:
        out.insert(0, P[0])
    return out


def _event_label(i: int, e: Event) -> str:
    text = f"#{i} {e.t:.3f} s {e.kind} {e.robot or ''}: {e.detail}"
    return text if len(text) <= 90 else text[:87] + "..."
