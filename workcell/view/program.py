"""The program panel of the live view: Teach, the program text, Save, Run, Step, Stop.

``Teach`` records the current tool pose of the chosen robot as a named target
(``p1``, ``p2`` ...) and appends a command line of the command language to the program
text: ``move joints absolute ROBOT J1 ... Jn`` (the joints, deg/mm, 10 significant
digits: the same pose again) or ``move linear ROBOT matrix M11 ... M44 speed V`` (the
tool pose, m; V from the panel), after a comment naming the target and its position.
The text can be edited on the page.

``Run`` runs the text line by line on the viewer's simulator (the session's file
names stay inside the viewer's ``root``), ``Step`` runs the next line only (the status
says which comes next), ``Stop`` ends a run after the command running now, and the
page's Pause holds it inside a command. ``Save`` writes the text as a ``.wcl`` file
inside ``root`` (a name with a folder outside it, ``..`` or a hidden name is refused).
An error stops the run and is shown on the page with its line.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING, Any

import numpy as np

from workcell.errors import ViewError, WorkcellError
from workcell.files import atomic_write_text, resolve_inside
from workcell.program.lexer import split_lines

if TYPE_CHECKING:
    from workcell.view.viewer import Viewer

__all__ = ["ProgramPanel", "teach_line"]


def teach_line(sim: Any, robot: str, name: str, kind: str = "joints", speed: float = 0.25) -> str:
    """The comment and command line that move ``robot`` back to its current pose:
    ``kind`` "joints" (a joint move) or "linear" (a straight tool move at ``speed`` m/s)."""
    T = sim.tool_pose(robot)
    where = " ".join(f"{v:.4f}" for v in T[:3, 3])
    head = f"# {name}: {robot} tool at {where} m\n"
    if kind == "linear":
        m = " ".join(f"{v:.12g}" for v in T.reshape(-1))
        return f"{head}move linear {robot} matrix {m} speed {speed:.6g}"
    r = sim.cell.robots[robot].robot
    q = sim.joints(robot)
    vals = np.where(r.revolute, np.degrees(q), q * 1e3)
    unit = "" if all(r.revolute) else " mm" if not any(r.revolute) else ""
    return f"{head}move joints absolute {robot} " + " ".join(f"{v:.10g}" for v in vals) + unit


class ProgramPanel:
    """Teach, program text, Save, Run, Step, Stop (module doc)."""

    def __init__(self, viewer: Viewer) -> None:
        self.viewer = viewer
        sim = viewer.sim
        assert sim is not None
        gui = viewer.server.gui
        self.targets: dict[str, np.ndarray] = {}  # taught name -> world tool pose
        self.running = False
        self._stop = False
        self._next = 0  # index of the next line for Step
        self._thread: threading.Thread | None = None
        ro = not viewer.control
        self.folder = gui.add_folder("Program", expand_by_default=False)
        with self.folder:
            self.robot = gui.add_dropdown("teach robot", tuple(sim.robots) or ("-",), disabled=ro)
            self.kind = gui.add_dropdown("teach as", ("joints", "linear"), disabled=ro)
            self.speed = gui.add_number("linear speed (m/s)", 0.25, min=0.001, max=5.0,
                                        step=0.001, disabled=ro)  # fmt: skip
            self.teach_button = gui.add_button("Teach", disabled=ro)
            self.text = gui.add_text("program", "", multiline=True, disabled=ro)
            self.file = gui.add_text("file", "taught.wcl", disabled=ro)
            self.save_button = gui.add_button("Save", disabled=ro)
            self.buttons = gui.add_button_group("run", ("Run", "Step", "Stop"), disabled=ro)
            self.state = gui.add_markdown("")
        self.teach_button.on_click(lambda e: self._teach(e.client))
        self.save_button.on_click(lambda e: self._save(e.client))
        self.buttons.on_click(self._pressed)
        self.text.on_update(lambda e: self._edited(e))

    def remove(self) -> None:
        """Take the panel off the page."""
        self.folder.remove()

    # ------------------------------------------------------------------ teach, save
    def teach(self, robot: str | None = None, kind: str | None = None, client: Any = None) -> str:
        """Record the tool pose of ``robot`` (default: the panel's choice) as the next
        target and append its line (``kind`` "joints" or "linear"); returns the name."""
        sim = self.viewer.sim
        robot = self.robot.value if robot is None else robot
        kind = self.kind.value if kind is None else kind
        if robot not in sim.robots:
            raise ViewError(f"teach: no robot {robot!r}; robots: {', '.join(sim.robots) or 'none'}")
        name = f"p{len(self.targets) + 1}"
        line = teach_line(sim, robot, name, kind, float(self.speed.value))
        self.targets[name] = sim.tool_pose(robot)
        text = self.text.value.rstrip("\n")
        self.text.value = (text + "\n" if text else "") + line + "\n"
        self.viewer.notify("taught", f"{name}: {line.splitlines()[-1][:60]}", client)
        return name

    def _teach(self, client: Any) -> None:
        if not self.viewer.control:
            return
        try:
            self.teach(client=client)
        except WorkcellError as exc:
            self.viewer.notify("not taught", str(exc), client, error=True)

    def save(self, name: str) -> str:
        """Write the program text to ``name`` inside the viewer's root; returns the path."""
        path = resolve_inside(self.viewer.root, name, error=ViewError)
        if path.suffix != ".wcl":
            raise ViewError(f"a program file must end in .wcl, got {name!r}")
        atomic_write_text(path, self.text.value, error=ViewError)
        return str(path)

    def _save(self, client: Any) -> None:
        try:
            path = self.save(self.file.value)
        except WorkcellError as exc:
            self.viewer.notify("not saved", str(exc), client, error=True)
            return
        self.viewer.notify("saved", path, client)

    def _edited(self, event: Any) -> None:
        if event.client is not None:
            self._next = 0

    # ------------------------------------------------------------------ running
    def _pressed(self, event: Any) -> None:
        which = self.buttons.value
        if which == "Stop":
            self.stop()
        elif which in ("Run", "Step"):
            self.start(step=which == "Step", client=event.client)

    def stop(self) -> None:
        """End a run after the command running now (and release a pause)."""
        self._stop = True
        self.viewer.set_paused(False)

    def start(self, *, step: bool = False, client: Any = None) -> threading.Thread | None:
        """Run the program (or its next line) in a thread; None when refused."""
        v = self.viewer
        if self.running or v.busy:
            v.notify("busy", "a program is running: wait for it, or Stop it", client, error=True)
            return None
        if not v.control:
            v.notify("read-only", "this view does not run programs", client, error=True)
            return None
        self.running, self._stop = True, False
        self._thread = threading.Thread(target=self._run, args=(step, client), daemon=True)
        self._thread.start()
        return self._thread

    def join(self, timeout: float | None = None) -> None:
        """Wait for a run started from the page to end."""
        if self._thread is not None:
            self._thread.join(timeout)

    def _run(self, step: bool, client: Any) -> None:
        from workcell.program.interpreter import Interpreter, QuitRequest
        from workcell.program.session import Session

        v = self.viewer
        lines = split_lines(self.text.value)
        out: list[str] = []
        session = Session(sim=v.sim, base_dir=v.root, root=v.root)
        interp = Interpreter(session, out.append)
        try:
            if self._next >= len(lines):
                self._next = 0
            while self._next < len(lines) and not self._stop:
                i = self._next
                self.state.content = f"running line {i + 1} of {len(lines)}"
                with v.lock:
                    interp.run_line(lines[i], f"line {i + 1}: ")
                self._next = i + 1
                if session.sim is not None and session.sim is not v.sim:
                    v.attach(session.sim)  # 'simulate' started another simulator
                    return
                if step:
                    break
            done = self._next >= len(lines)
            if done:
                self._next = 0
            self.state.content = (
                "done" if done else f"next: line {self._next + 1} of {len(lines)}"
            ) + (" (stopped)" if self._stop else "")
        except QuitRequest:
            self._next = 0
            self.state.content = "quit"
        except WorkcellError as exc:
            self.state.content = f"stopped on an error: {type(exc).__name__}"
            v.notify("program stopped", f"{type(exc).__name__}: {exc}", client, error=True)
        finally:
            self.running = False
            if v.sim is not None:
                v.refresh()
