"""Results of commands as text for people (the shell and scripts): degrees and metres.

Joint values are shown in degrees (metres for prismatic joints), tool poses as a
position (m) and fixed-axes x, y, z angles (deg, the ``rpy`` of the language), so what
is read back can be typed in again.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.spatial.transform import Rotation

from workcell.program import cellcommands as cellc
from workcell.program import commands as cmd
from workcell.program import simcommands as simc

if TYPE_CHECKING:
    from workcell.program.base import Command
    from workcell.program.session import Session

__all__ = ["format_result", "joint_by_joint_clocks", "rpy_degrees"]


def _nums(v: Any, digits: int = 6) -> str:
    return "(" + ", ".join(f"{float(x):.{digits}g}" for x in np.ravel(v)) + ")"


def rpy_degrees(T: np.ndarray) -> np.ndarray:
    """Fixed-axes x, y, z angles (deg) of a pose's rotation: R = Rz Ry Rx."""
    with warnings.catch_warnings():  # gimbal lock: scipy warns, the angles still rebuild R
        warnings.simplefilter("ignore", UserWarning)
        return Rotation.from_matrix(np.asarray(T)[:3, :3]).as_euler("xyz", degrees=True)


def _joints(q: np.ndarray, session: Session | None, robot: str) -> str:
    kinds = session.joint_kinds(robot) if session is not None else None
    if kinds is None or len(kinds) != len(q):
        kinds = [True] * len(q)
    if all(kinds):
        return _nums(np.degrees(q)) + " deg"
    parts = [
        f"{np.degrees(v):.6g} deg" if r else f"{v:.6g} m" for v, r in zip(q, kinds, strict=True)
    ]
    return "(" + ", ".join(parts) + ")"


def joint_by_joint_clocks(sim_time: float, frames: int, dt: float) -> str:
    """The two clocks of joint-by-joint mode, side by side, for people: the simulated time
    (s, the thesis's clock) and frames x dt (s)."""
    return (
        "joint-by-joint mode keeps two clocks:\n"
        f"  sim time (thesis clock) {sim_time:9.3f} s: each move lasts its largest joint "
        "motion / speed (eq. 4.27), as in path mode\n"
        f"  frames x dt             {(frames - 1) * dt:9.3f} s: {frames - 1} steps of {dt:g} s, "
        "the joints moving one after another"
    )


def format_result(command: Command, result: Any, session: Session | None = None) -> str:
    """The text the shell prints after ``command`` returned ``result`` ("" for nothing)."""
    if result is None:
        return ""
    given = (getattr(command, "name", None), getattr(command, "new_name", None))
    if isinstance(result, str) and (result in given or result == getattr(command, "relation", 0)):
        return ""  # a created or renamed thing's own name: nothing new to say
    if isinstance(command, (cellc.ExampleCell, cellc.LoadCell)) and session is not None:
        return repr(session.cell)
    if isinstance(command, cellc.SaveCell):
        sim = session.sim if session is not None else None
        if sim is not None and sim.frames > 1:  # say what a save mid-simulation holds
            return (
                f"{result}: the cell as set up (the state programs start from); the "
                f"simulation's state at t = {sim.sim_time:.6g} s is not in it"
            )
        return str(result)
    if isinstance(command, simc.Joints):
        return _joints(result, session, command.robot)
    if isinstance(command, simc.ToolPose):
        return f"at {_nums(result[:3, 3])} m, rpy {_nums(rpy_degrees(result))} deg"
    if isinstance(command, cmd.Properties):
        inertia = np.asarray(result["inertia"])
        return "\n".join(
            [
                f"area {result['area']:.6g} m^2, volume {result['volume']:.6g} m^3",
                f"centroid {_nums(result['centroid'])} m",
                "inertia about the centroid (unit density, m^5):",
                *(f"  {_nums(row)}" for row in inertia),
            ]
        )
    if isinstance(command, cmd.WorldMesh):
        lo, hi = np.asarray(result["bounds"])
        text = (
            f"{result['vertices']} vertices, {result['faces']} faces, volume "
            f"{result['volume']:.6g} m^3, {'watertight' if result['watertight'] else 'open'}; "
            f"bounds {_nums(lo)} .. {_nums(hi)} m"
        )
        return text + (f"; written to {result['path']}" if result["path"] else "")
    if isinstance(command, simc.Events):
        return "\n".join(_event(e) for e in result) or "no events"
    if isinstance(command, simc.Summary):
        lines = [
            f"simulated time {result['sim_time_s']:.6g} s, wall time {result['wall_time_s']:.4g} s, "
            f"{result['frames']} frames, {result['collisions']} collisions"
        ]
        sim = session.sim if session is not None else None
        if sim is not None and sim.mode == "joint-by-joint":
            lines.append(joint_by_joint_clocks(result["sim_time_s"], result["frames"], sim.dt))
        objects = result.get("objects", {}).items()
        lines += [f"  {name} centroid at {_nums(p)} m" for name, p in objects]
        return "\n".join(lines)
    if isinstance(command, simc.SimTime):
        return f"{result:.6g} s"
    if isinstance(command, simc.CycleTime):
        from workcell.sim.cycle import format_table

        return format_table(result)
    if isinstance(command, simc.Clearance):
        return f"{result:.6g} m"
    if isinstance(command, simc.Frames):
        return f"{result} frames"
    if isinstance(command, simc.PartPositions):
        text = "\n".join(f"{k} centroid at {_nums(v)} m" for k, v in result.items())
        return text or "no movable parts"
    if isinstance(command, cmd.Remove):
        return "removed " + ", ".join(result)
    if isinstance(result, dict):
        return "\n".join(f"{k}: {_plain(v)}" for k, v in result.items())
    return _plain(result)


def _event(e: dict[str, Any]) -> str:
    return f"t = {e['t']:9.4f} s  {e['robot'] or '-':10s} {e['kind']:8s} {e['detail']}"


def _plain(v: Any) -> str:
    if isinstance(v, (list, tuple)):
        return ", ".join(map(str, v)) if v else "none"
    if isinstance(v, np.ndarray):
        return _nums(v)
    return str(v)
