"""The live view: a web page that shows a simulator's cell as its commands run.

``Viewer(sim)`` starts a viser server (on loopback, behind a random token: see
:mod:`workcell.view.guard`) and hangs two listeners on the simulator
(``sim.frame_listeners``, ``sim.event_listeners``): whatever runs the simulator (Python,
the command language, the server) is shown as it happens; a third
(``sim.physics_listeners``) shows a physics replay (``run_physics``) as it runs.

Pacing: with ``speed`` (default 1.0) each frame is shown when the wall clock has run its
simulated time / speed since the command began (the simulator waits, in the listener, for
frames that come early; frames that come late are dropped from the page but never
slow anything; at most 60 pushes a second). With ``speed=None`` only each command's end
state is shown (at its event). A viewer with no page open, or closed, returns from its
listeners at once. The page's Pause button holds the program inside the next frame
until Resume (or until the page closes).

The page: the clock and the run state, camera presets, Pause; the events (collisions in
red; choosing one shows its frame); the timeline slider (scrubs every frame of what has
run, tool paths drawn as lines) and the cycle-time report; per robot the jog panel
(:mod:`workcell.view.jog`); the program panel (:mod:`workcell.view.program`). Things
in contact at the shown frame are red, with a marker and the depth at the contact point.

Page actions that change the simulator (jog, gripper, teach, run) take :attr:`Viewer.lock`
and are refused while a command runs; front ends that run commands from another thread
(the shell, the server) hold the same lock around each command. ``control=False`` (the
server's default) makes the page read-only.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from workcell.checks import is_finite_number
from workcell.errors import ProgramError
from workcell.sim.timeline import Event
from workcell.view.cameras import View, apply_view, presets, reach
from workcell.view.contacts import contacts
from workcell.view.guard import LOOPBACK, Guard, new_token, start_server, stop_quietly
from workcell.view.scene import Scene, stage
from workcell.view.timeline import TimelinePanel

if TYPE_CHECKING:
    import viser

    from workcell.sim.simulator import Simulator

__all__ = ["Viewer"]

_PUSH_INTERVAL = 1.0 / 60.0  # s between two pictures sent to the page while running
_END_STATE_INTERVAL = 0.05  # s between two end states (speed None) while running
_PANELS_INTERVAL = 0.25  # s between two redraws of events, report, paths, inputs
_BUSY_GAP = 0.25  # s after the last frame during which a command counts as running


class Viewer:
    """A live web view of ``sim`` (module doc); ``.url``, ``.close()``, a context manager.

    ``host`` (default loopback) and ``port`` (0: any free port) to listen on; ``speed``:
    frames shown at ``speed`` x real time, None: each command's end state only;
    ``root``: the folder the page's files (saved programs) are written in (default: the
    working folder); ``control``: the page may jog, teach and run (False: read-only).
    """

    def __init__(self, sim: Simulator | None, *, host: str = "127.0.0.1", port: int = 0,
                 speed: float | None = 1.0, root: str | Path = ".",
                 control: bool = True) -> None:  # fmt: skip
        if speed is not None and not (is_finite_number(speed) and speed > 0):
            raise ProgramError(f"Viewer: speed must be a number > 0 or None, got {speed!r}")
        if not (isinstance(port, int) and 0 <= port <= 65535):
            raise ProgramError(f"Viewer: port must be an integer 0 ... 65535, got {port!r}")
        self.speed = None if speed is None else float(speed)
        self.root = Path(root).resolve()
        self.control = bool(control)
        self.guard = Guard(new_token(), loopback=host in LOOPBACK)
        self.server: viser.ViserServer = start_server(host, port, self.guard)
        shown = "127.0.0.1" if host in ("0.0.0.0", "") else host
        shown = f"[{shown}]" if ":" in shown and not shown.startswith("[") else shown
        self.url = f"http://{shown}:{self.server.get_port()}/{self.guard.token}"
        self.lock = threading.RLock()
        self.sim: Simulator | None = None
        self.scene: Scene | None = None
        self.pushes = 0  # pictures sent to the page (for benchmarks)
        self._closed = False
        self._clients = 0
        self._paused = False
        self._resume = threading.Condition()
        self._anchor: tuple[float, float] | None = None  # (wall, sim time) of pacing
        self._last_push = 0.0
        self._shown_at: tuple[int, float] | None = None  # the (frame, t) the page shows
        self._physics_at: tuple[float, bool] | None = None  # (t, last) of a physics frame
        self._last_frame = 0.0
        self._own = False  # the page's own jog is running (its frames are not 'busy')
        self._commands = 0  # commands of a followed session running now
        self._scrubbed: int | None = None
        self._views: dict[str, View] = {}
        self._dirty = threading.Event()
        self._pending: tuple[int, float, np.ndarray] | None = None
        self._panels_at = 0.0
        self._paint_data: mujoco.MjData | None = None
        self._build_page()
        self._painter = threading.Thread(target=self._paint, daemon=True, name="workcell-view")
        self._painter.start()
        self.server.on_client_connect(self._connected)
        self.server.on_client_disconnect(self._disconnected)
        if sim is not None:
            self.attach(sim)

    # ------------------------------------------------------------------ life cycle
    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Detach from the simulator and stop the server (the page goes blank)."""
        if self._closed:
            return
        self._closed = True
        self._detach()
        with self._resume:
            self._resume.notify_all()
        if self._painter is not threading.current_thread():
            self._painter.join(2.0)  # its last picture sent before the server stops
        stop_quietly(self.server)

    def _repr_html_(self) -> str:
        """In a notebook: the page's link."""
        return f'<a href="{self.url}" target="_blank">workcell live view: {self.url}</a>'

    @property
    def clients(self) -> int:
        """Pages connected now."""
        return self._clients

    @property
    def busy(self) -> bool:
        """True while a command is running: a followed session's, or one whose frame was
        applied less than 0.25 s ago (not the page's own jogs)."""
        return self._commands > 0 or time.perf_counter() - self._last_frame < _BUSY_GAP

    def attach(self, sim: Simulator) -> None:
        """Show ``sim`` (another simulator than before: the scene is rebuilt)."""
        if sim is self.sim:
            return
        self._detach()
        for panel in getattr(self, "_panels", []):
            panel.remove()
        self._panels = []
        self.sim = sim
        self._shown_at = None
        stage(self.server)
        cc, m = sim.compiled, sim.model
        bases = {r: p.world_base for r, p in sim.cell.robots.items()}
        self.scene = Scene(self.server, m, sim.data, labels=sim.contacts.labels,
                           tool_sites=dict(sim._site), bases=bases)  # fmt: skip
        reaches = {r: reach(p.robot) for r, p in sim.cell.robots.items()}
        self._views = presets(m, sim.data, bases, reaches, dict(cc.cameras))
        self.camera_choice.options = tuple(self._views)
        self.camera_choice.value = "overview"
        apply_view(self.server, self._views["overview"], None)
        self._paint_data = mujoco.MjData(m)
        self.timeline_panel.reset(sim)
        from workcell.view.jog import JogPanel
        from workcell.view.program import ProgramPanel

        self.jog = JogPanel(self)
        self.program = ProgramPanel(self)
        self._panels = [self.jog, self.program]
        sim.frame_listeners.append(self._on_frame)
        sim.event_listeners.append(self._on_event)
        sim.physics_listeners.append(self._on_physics)
        self.refresh()

    def follow(self, session: Any) -> None:
        """Show what ``session`` (a command-language session) runs: its commands take
        :attr:`lock` (so the page waits for them), and a simulator the session starts
        (``simulate``) replaces the one shown."""
        inner = session.execute

        def execute(command: Any) -> Any:
            with self.lock:
                self._commands += 1
                try:
                    return inner(command)
                finally:
                    self._commands -= 1
                    if session.sim is not None and session.sim is not self.sim:
                        self.attach(session.sim)

        session.execute = execute
        if session.sim is not None:
            self.attach(session.sim)

    def _detach(self) -> None:
        sim = self.sim
        if sim is None:
            return
        if self._on_frame in sim.frame_listeners:
            sim.frame_listeners.remove(self._on_frame)
        if self._on_event in sim.event_listeners:
            sim.event_listeners.remove(self._on_event)
        if self._on_physics in sim.physics_listeners:
            sim.physics_listeners.remove(self._on_physics)

    # ------------------------------------------------------------------ the page
    def _build_page(self) -> None:
        gui = self.server.gui
        gui.configure_theme(control_width="large", show_share_button=False, show_logo=False)
        self.server.gui.set_panel_label("workcell")
        self.status = gui.add_markdown("**t = 0 s**")
        self.pause_button = gui.add_button("Pause", hint="hold the program at its next frame")
        self.pause_button.on_click(lambda e: self.set_paused(not self._paused))
        self.camera_choice = gui.add_dropdown("View", ("overview",), initial_value="overview")
        self.camera_choice.on_update(self._camera_chosen)
        self.timeline_panel = TimelinePanel(self)

    def notify(self, title: str, body: str, client: Any = None, *, error: bool = False) -> None:
        """A message on the page (one client's, or every page's)."""
        targets = [client] if client is not None else list(self.server.get_clients().values())
        for c in targets:
            c.add_notification(title, body, auto_close_seconds=8.0,
                               color="red" if error else None)  # fmt: skip

    def set_paused(self, paused: bool) -> None:
        """Pause (the program waits at its next frame) or resume."""
        with self._resume:
            self._paused = bool(paused)
            self._resume.notify_all()
        self.pause_button.label = "Resume" if self._paused else "Pause"
        self._anchor = None
        self._status()

    def _connected(self, client: Any) -> None:
        self._clients += 1
        self.refresh()

    def _disconnected(self, client: Any) -> None:
        self._clients = max(0, self._clients - 1)
        if self._clients == 0:
            with self._resume:
                self._resume.notify_all()

    def _camera_chosen(self, event: Any) -> None:
        v = self._views.get(self.camera_choice.value)
        if v is not None and event.client is not None:
            apply_view(self.server, v, event.client)

    # ------------------------------------------------------------------ listeners
    def _on_frame(self, frame: int, t: float) -> None:
        """Frame listener (module doc: pacing, pause)."""
        if self._clients == 0 or self._closed:
            return
        now = time.perf_counter()
        if not self._own:
            self._last_frame = now
        if self._paused:
            self._wait_resumed()
            now = time.perf_counter()
        sim = self.sim
        assert sim is not None
        replay = frame < len(sim.timeline)  # undo, replay: data shows a recorded frame
        if self.speed is None and not replay:
            return
        if self.speed is not None and not replay:
            now = self._pace(t, now)
        if now - self._last_push >= _PUSH_INTERVAL:
            self._push(frame, t)

    def _pace(self, t: float, now: float) -> float:
        """Wait until simulated time ``t`` (s) is due at ``speed`` x real time; the wall
        clock (s) after the wait."""
        assert self.speed is not None
        if self._anchor is None or t < self._anchor[1]:
            self._anchor = (now, t)
        due = self._anchor[0] + (t - self._anchor[1]) / self.speed
        if due - now > 0:
            time.sleep(due - now)
            now = time.perf_counter()
        elif now - due > 0.1:  # far behind (a slow command, idle before): start again
            self._anchor = (now, t)
        return now

    def _on_physics(self, t: float, data: mujoco.MjData, pairs: list[tuple[str, str]],
                    last: bool) -> None:  # fmt: skip
        """Physics listener (``run_physics``): the replay's frames, paced like a command's
        (``speed=None``: at most 20 a second), its collisions red; its end state stays on
        the page, marked as the physics run's, until the next picture."""
        if self._clients == 0 or self._closed or self.scene is None or self.sim is None:
            return
        now = self._last_frame = time.perf_counter()
        if self._paused:
            self._wait_resumed()
            now = time.perf_counter()
        if self.speed is not None:
            now = self._pace(t, now)
        gap = _PUSH_INTERVAL if self.speed is not None else _END_STATE_INTERVAL
        if not last and now - self._last_push < gap:
            return
        self.scene.show(data, contacts(self.sim.contacts, data, only=pairs))
        self._physics_at = (t, last)
        self._last_push = time.perf_counter()
        self.pushes += 1
        self._status()

    def _wait_resumed(self) -> None:
        with self._resume:
            self._status()
            while self._paused and self._clients > 0 and not self._closed:
                self._resume.wait(0.5)
        self._anchor = None

    def _on_event(self, event: Event) -> None:
        """Event listener: show the command's end state now; the event list, the report,
        the paths and the inputs follow from the painter thread."""
        if self._clients == 0 or self._closed:
            return
        self._anchor = None
        sim = self.sim
        assert sim is not None
        # the state at the event, drawn by the painter (the program does not wait for it)
        self._pending = (len(sim.timeline) - 1, sim.sim_time, sim.data.qpos.copy())
        self._dirty.set()

    def _paint(self) -> None:
        """The painter thread: redraws the panels a moment after events (off the
        program's thread, so a program never waits for them), and the run state."""
        shown = ""
        busy_since = 0.0
        while not self._closed:
            if self._dirty.wait(0.3):
                self._dirty.clear()
                pending, self._pending = self._pending, None
                try:
                    if pending is not None:
                        self._push_state(*pending)
                    busy, now = self.busy, time.perf_counter()
                    if busy and shown != "busy" and busy_since < self._panels_at:
                        busy_since = now  # a run starts: its panels wait (not at once)
                    # less while running: every second, not before a second of the run
                    wait = _PANELS_INTERVAL * (4 if busy else 1)
                    last = max(self._panels_at, busy_since) if busy else self._panels_at
                    if now - last > wait:
                        self._panels_from_sim()
                        self._panels_at = time.perf_counter()
                    else:
                        self._dirty.set()  # the panels a little later
                        # end states at most 20 a second while a program runs (the later
                        # ones replace the earlier: the page keeps up, the program too)
                        time.sleep(_END_STATE_INTERVAL if self.busy else _PUSH_INTERVAL)
                except Exception:  # the program changed the timeline meanwhile: next time
                    self._dirty.set()
            state = "busy" if self.busy else "idle"
            if state != shown and self.sim is not None and self._scrubbed is None:
                self._status()
                shown = state

    # ------------------------------------------------------------------ drawing
    def _push_state(self, frame: int, t: float, qpos: np.ndarray) -> None:
        """Show a recorded state (the painter's data; contacts computed again)."""
        sim = self.sim
        d = self._paint_data
        if sim is None or d is None or len(qpos) != sim.model.nq:
            return
        d.qpos[:] = qpos
        mujoco.mj_kinematics(sim.model, d)
        if sim.check_collisions:
            mujoco.mj_collision(sim.model, d)
        else:
            d.ncon = 0
        self._push(frame, t, d, live=True)

    def _push(self, frame: int, t: float, data: mujoco.MjData | None = None, *,
              live: bool = False) -> None:  # fmt: skip
        """Send the state of ``data`` (default: the simulator's) as ``frame``; ``live``:
        the simulator's state (not a scrubbed frame of the past)."""
        sim = self.sim
        assert sim is not None
        assert self.scene is not None
        d = sim.data if data is None else data
        touching = contacts(sim.contacts, d) if (sim.check_collisions or data is not None) else []
        self.scene.show(d, touching)
        self._physics_at = None
        live = live or data is None
        self._scrubbed = None if live else frame
        self._shown_at = (frame, t)
        self._last_push = time.perf_counter()
        self.pushes += 1
        with self.server.atomic():
            self.timeline_panel.follow(frame, len(sim.timeline))
            self._status(t, frame)
            if live:
                self.jog.follow()

    def _status(self, t: float | None = None, frame: int | None = None) -> None:
        sim = self.sim
        if sim is None:
            self.status.content = "no simulation yet"
            return
        if frame is None:  # what the page shows (a command's frames join the timeline at
            # its end: the timeline's last frame lags behind the live one while it runs)
            frame, t = self._shown_at or (len(sim.timeline) - 1, sim.sim_time)
        t = sim.sim_time if t is None else t
        state = "paused" if self._paused else ("running" if self.busy else "idle")
        if self._scrubbed is not None:
            state = "timeline (scrubbing)"
        red = sorted(self.scene.red) if self.scene is not None else []
        hit = f" · contact: {', '.join(red)}" if red else ""
        if self._physics_at is not None:  # a physics replay's frame (not the timeline's)
            t, done = self._physics_at
            run = "its end state" if done else "running"
            self.status.content = f"**t = {t:.3f} s** · physics replay (mj_step) · {run}{hit}"
            return
        self.status.content = (
            f"**t = {t:.3f} s** · frame {frame} of {len(sim.timeline) - 1} · {state}{hit}"
        )

    def refresh(self) -> None:
        """Redraw everything from the simulator: state, events, report, paths, inputs."""
        sim = self.sim
        if sim is None or self._closed:
            return
        self._push(len(sim.timeline) - 1, sim.sim_time)
        self._panels_from_sim()

    def _panels_from_sim(self) -> None:
        """Events, cycle-time report, tool paths and jog inputs from the simulator."""
        if self.sim is None or self._closed:
            return
        with self.server.atomic():
            self.timeline_panel.draw()
            self.jog.sync()

    def show_frame(self, frame: int) -> None:
        """Show frame ``frame`` of the timeline (the simulator's state is not changed)."""
        self.timeline_panel.show_frame(frame)
