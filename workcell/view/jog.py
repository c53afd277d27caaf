"""The jog panel of the live view: per robot, joint inputs, a tool gizmo, the
configuration and the gripper.

For each robot of the cell, a folder with one numeric input per joint, labelled exactly
``<robot> <joint name>`` (degrees, millimetres for prismatic joints; the unit and the
limits beside it), a configuration selector (robots with closed-form IK: the letters
l|r, u|d, n|f) and Open/Close gripper; in the scene, a transform gizmo at the tool.

Typing a joint value jogs the robot there (``Simulator.jog``; a value outside the limits
is refused with the joint's range and nothing moves). Dragging the gizmo solves IK for
the gizmo's pose keeping the robot's current configuration and jogs to the solution; a
pose out of reach, or reachable only in another configuration, is refused with the
reason and the gizmo goes back to the tool. Choosing a configuration moves the robot
to the same tool pose in that configuration.
"""

from __future__ import annotations

import math
import threading
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from workcell.errors import WorkcellError
from workcell.robots.ik_closed import config_of, family_of
from workcell.spatial import invert, pose_from_pos_quat, quat_from_matrix

if TYPE_CHECKING:
    from workcell.view.viewer import Viewer

__all__ = ["JogPanel", "solve_keeping"]

Array = NDArray[np.float64]


def solve_keeping(robot: Any, T: Array, q: Array, config: str | None) -> tuple[Array | None, str]:
    """Joint values (rad/m) reaching tool pose ``T`` (robot base frame) in ``config``
    (closed-form robots; None: the numerical IK from ``q``), or (None, the reason)."""
    if config is not None:
        sols = robot.ik_closed_form(T, q)
        inside = [s for s in sols if s.config == config and s.within_limits]
        if inside:
            return inside[0].q, ""
        if any(s.config == config for s in sols):
            return None, f"configuration {config} reaches this pose only outside the joint limits"
        if sols:
            others = ", ".join(sorted({s.config for s in sols if s.within_limits})) or "none"
            return None, f"not reachable in configuration {config} (reachable in: {others})"
        return None, "out of reach: no configuration reaches this pose"
    sol = robot.ik(T, q)
    if sol.success:
        return sol.q, ""
    return None, f"out of reach: {sol.reason}"


class JogPanel:
    """Joint inputs, gizmos, configuration and gripper controls (module doc)."""

    def __init__(self, viewer: Viewer) -> None:
        self.viewer = viewer
        sim = viewer.sim
        assert sim is not None
        gui, sc = viewer.server.gui, viewer.server.scene
        self.inputs: dict[str, list[Any]] = {}
        self.gizmos: dict[str, Any] = {}
        self.configs: dict[str, Any] = {}
        self.grippers: dict[str, Any] = {}
        self._dragging: set[str] = set()
        self._ik_lock = threading.Lock()
        self.folders = []
        cc = sim.compiled
        for robot in sim.robots:
            r = sim.cell.robots[robot].robot
            prefix = cc.robot_prefixes.get(robot, "")
            names = [j.removeprefix(prefix) for j in cc.joint_names[robot]]
            q = sim.joints(robot)
            folder = gui.add_folder(f"Jog {robot}", expand_by_default=len(sim.robots) == 1)
            self.folders.append(folder)
            with folder:
                boxes, lines = [], []
                for k, name in enumerate(names):
                    rev = bool(r.revolute[k])
                    f = math.degrees if rev else (lambda v: v * 1e3)
                    unit = "deg" if rev else "mm"
                    lo, hi = f(float(r.lower[k])), f(float(r.upper[k]))
                    box = gui.add_number(
                        f"{robot} {name}", round(f(float(q[k])), 6),
                        min=lo if math.isfinite(lo) else None,
                        max=hi if math.isfinite(hi) else None, step=0.001,
                        hint=f"{unit}, {lo:.6g} ... {hi:.6g}", disabled=not viewer.control,
                    )  # fmt: skip
                    box.on_update(lambda e, robot=robot: self._typed(robot, e))
                    boxes.append(box)
                    lines.append(f"{name}: {unit}, {lo:.6g} ... {hi:.6g}")
                self.inputs[robot] = boxes
                gui.add_markdown("<small>" + " · ".join(lines) + "</small>")
                if family_of(r) is not None:
                    opts = tuple(f"{a}{e}{w}" for a in "lr" for e in "ud" for w in "nf")
                    c = gui.add_dropdown(f"{robot} configuration", opts,
                                         initial_value=config_of(r, q),
                                         disabled=not viewer.control)  # fmt: skip
                    c.on_update(lambda e, robot=robot: self._config_chosen(robot, e))
                    self.configs[robot] = c
                if robot in sim._gripper:
                    b = gui.add_button(f"{robot} open/close gripper", disabled=not viewer.control)
                    b.on_click(lambda e, robot=robot: self._gripper(robot, e))
                    self.grippers[robot] = b
            T = sim.tool_pose(robot)
            g = sc.add_transform_controls(f"/gizmo/{robot}", scale=0.15, position=T[:3, 3],
                                          wxyz=quat_from_matrix(T[:3, :3]),
                                          visible=viewer.control)  # fmt: skip
            g.on_update(lambda e, robot=robot: self._dragged(robot, e))
            self.gizmos[robot] = g

    def remove(self) -> None:
        """Take the panel off the page."""
        for f in self.folders:
            f.remove()
        for g in self.gizmos.values():
            g.remove()

    # ------------------------------------------------------------------ following
    def sync(self) -> None:
        """Inputs, configuration and gizmos from the simulator's current joints."""
        sim = self.viewer.sim
        assert sim is not None
        for robot, boxes in self.inputs.items():
            r = sim.cell.robots[robot].robot
            q = sim.joints(robot)
            for k, box in enumerate(boxes):
                box.value = round(math.degrees(q[k]) if r.revolute[k] else q[k] * 1e3, 6)
            if robot in self.configs:
                self.configs[robot].value = config_of(r, q)
        self.follow()

    def follow(self) -> None:
        """Gizmos at the tools (except one being dragged)."""
        sim = self.viewer.sim
        assert sim is not None
        for robot, g in self.gizmos.items():
            if robot in self._dragging:
                continue
            T = sim.tool_pose(robot)
            g.position = T[:3, 3]
            g.wxyz = quat_from_matrix(T[:3, :3])

    # ------------------------------------------------------------------ actions
    def _refuse_busy(self, client: Any) -> bool:
        v = self.viewer
        if not v.control:
            v.notify("read-only", "this view does not change the simulation", client, error=True)
            return True
        if v.busy or (v.program is not None and v.program.running):
            v.notify("busy", "a program is running: wait for it, or Stop it", client, error=True)
            return True
        return False

    def jog(self, robot: str, q: Array, client: Any = None) -> bool:
        """Jog ``robot`` to ``q`` (rad/m) under the viewer's lock; a refusal is shown on
        the page. True when the robot moved."""
        v = self.viewer
        try:
            with v.lock:
                v._own = True
                try:
                    v.sim.jog(robot, q)
                finally:
                    v._own = False
        except WorkcellError as exc:
            v.notify(f"{robot}: not moved", str(exc), client, error=True)
            self.sync()
            return False
        return True

    def _typed(self, robot: str, event: Any) -> None:
        if event.client is None:  # set from here (sync), not typed
            return
        if self._refuse_busy(event.client):
            self.sync()
            return
        sim = self.viewer.sim
        r = sim.cell.robots[robot].robot
        vals = np.array([float(b.value) for b in self.inputs[robot]])
        q = np.where(r.revolute, np.radians(vals), vals * 1e-3)
        self.jog(robot, q, event.client)

    def _dragged(self, robot: str, event: Any) -> None:
        phase = getattr(event, "phase", "update")
        if phase == "start":
            self._dragging.add(robot)
            return
        if phase == "end":
            self._dragging.discard(robot)
        if event.client is None or self._refuse_busy(event.client):
            self.follow()
            return
        if phase != "end" and not self._ik_lock.acquire(blocking=False):
            return  # an IK for an earlier pose of this drag is still running: skip this one
        if phase == "end":
            self._ik_lock.acquire()
        try:
            g = self.gizmos[robot]
            self.move_tool(robot, pose_from_pos_quat(g.position, g.wxyz), event.client,
                           quiet=phase != "end")  # fmt: skip
        finally:
            self._ik_lock.release()

    def move_tool(self, robot: str, T_world: Array, client: Any = None, *,
                  config: str | None = None, quiet: bool = False) -> bool:  # fmt: skip
        """Jog ``robot`` so that its tool is at ``T_world`` (4x4), keeping its current
        configuration (or ``config``); unreachable: the reason on the page, nothing moves."""
        v = self.viewer
        sim = v.sim
        placement = sim.cell.robots[robot]
        r = placement.robot
        q = sim.joints(robot)
        if config is None and family_of(r) is not None:
            config = config_of(r, q)
        q_new, why = solve_keeping(r, invert(placement.base) @ T_world, q, config)
        if q_new is None:
            if not quiet:
                v.notify(f"{robot}: not moved", why, client, error=True)
                self.follow()
            return False
        moved = self.jog(robot, q_new, client)
        if moved:
            self.sync()
        return moved

    def _config_chosen(self, robot: str, event: Any) -> None:
        if event.client is None or self._refuse_busy(event.client):
            return
        sim = self.viewer.sim
        self.move_tool(robot, sim.tool_pose(robot), event.client,
                       config=self.configs[robot].value)  # fmt: skip

    def _gripper(self, robot: str, event: Any) -> None:
        if self._refuse_busy(event.client):
            return
        v = self.viewer
        try:
            with v.lock:
                if v.sim.held(robot) is None:
                    part = v.sim.close_gripper(robot)
                    v.notify(f"{robot}: gripper closed", f"holds '{part}'", event.client)
                else:
                    v.sim.open_gripper(robot)
        except WorkcellError as exc:
            v.notify(f"{robot}: gripper", str(exc), event.client, error=True)
