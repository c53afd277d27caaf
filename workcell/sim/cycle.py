"""The cycle-time report: one record per command, which limit set its time, the total.

Every command that takes part in a program's cycle (the motion commands, the grippers,
``wait``) leaves a record on the event that ends it (``Event.data``), so the report is
always the timeline's own account, undone with it when a command fails and rewritten
when a zone move is blended into the next one. A record is a plain dict:

- ``robot`` (None for ``wait``), ``command`` (the Simulator method),
- ``t_start`` and ``duration_s`` (s of simulated time),
- ``limited_by``: which limit set the time: ``"j<i> speed"``, ``"j<i> acceleration"``,
  ``"j<i> jerk"`` (joint i's own limits, profile "jerk" and Cartesian moves),
  ``"tool speed"``, ``"tool acceleration"`` (the programmed tool speed and
  acceleration), ``"robot speed"``, ``"robot acceleration"`` (the thesis profiles: the
  robot's speed set by ``set_speed``, the simulator's acceleration); the one active for
  the longest part of the command wins; None for commands that take no time,
  ``"wait"`` for waits;
- ``zone_m``: the zone the command's end was blended with (0: it stopped there), and
  ``note`` when there is something to say (a zone clipped, a zone not used);
- ``program`` (kept on the event, left out of the report): what the command was asked to
  do, for :mod:`workcell.robotprog` to write it again in a robot language: ``kind``
  (``"joint"``, ``"linear"``, ``"circular"``, ``"line"``, ``"path"``, ``"gripper"``,
  ``"wait"``), its targets in the robot's base frame (``q`` rad/m, ``pose`` 4x4 m as
  nested lists, ``via`` (3,) m, ``waypoints``), the programmed ``zone`` (m), tool
  ``speed`` (m/s) and ``acceleration`` (m/s^2), the requested ``config``, and the motion
  settings in effect (``profile``, the robot's thesis ``robot_speed`` rad/s, the
  simulator's ``profile_acceleration`` rad/s^2, ``override``).

:func:`cycle_report` collects them; :func:`format_table` prints them for people.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from workcell.sim.timeline import Event

__all__ = ["command_record", "cycle_report", "format_table", "limited_by"]


def limited_by(activity: Mapping[str, float]) -> str | None:
    """The limit active for the longest time (``activity``: seconds per limit name)."""
    live = {k: v for k, v in activity.items() if v > 0.0}
    return max(live, key=lambda k: live[k]) if live else None


def command_record(
    robot: str | None,
    command: str,
    t_start: float,
    duration: float,
    activity: Mapping[str, float] | str | None = None,
    *,
    zone: float = 0.0,
    note: str = "",
    program: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """A command's record (module doc); ``activity``: seconds per limit, or the name;
    ``program``: what the command was asked to do (module doc)."""
    limit = activity if isinstance(activity, str) or activity is None else limited_by(activity)
    rec: dict[str, Any] = {
        "robot": robot,
        "command": command,
        "t_start": float(t_start),
        "duration_s": float(duration),
        "limited_by": limit,
        "zone_m": float(zone),
    }
    if note:
        rec["note"] = note
    if program is not None:
        rec["program"] = dict(program)
    return rec


def cycle_report(events: Iterable[Event], total: float) -> dict[str, Any]:
    """``{"total_s", "commands"}``: the records on ``events``, in order of their start
    (without their ``program``)."""
    recs = [e.data for e in events if e.data is not None]
    order = sorted(range(len(recs)), key=lambda i: (recs[i]["t_start"], i))
    out = [{k: v for k, v in recs[i].items() if k != "program"} for i in order]
    return {"total_s": float(total), "commands": out}


def format_table(report: Mapping[str, Any]) -> str:
    """The report as a text table: start, duration, robot, command, limited by, notes."""
    rows = [("start (s)", "duration (s)", "robot", "command", "limited by", "")]
    for r in report["commands"]:
        extra = []
        if r.get("zone_m"):
            extra.append(f"zone {r['zone_m'] * 1e3:.3g} mm")
        if r.get("note"):
            extra.append(r["note"])
        rows.append(
            (
                f"{r['t_start']:.4f}",
                f"{r['duration_s']:.4f}",
                r["robot"] or "-",
                r["command"],
                r["limited_by"] or "-",
                "; ".join(extra),
            )
        )
    widths = [max(len(row[i]) for row in rows) for i in range(5)]
    lines = [
        "  ".join(
            f"{c:>{w}}" if i < 2 else f"{c:<{w}}"
            for i, (c, w) in enumerate(zip(row, widths, strict=False))
        )
        + (f"  {row[5]}" if row[5] else "")
        for row in rows
    ]
    lines.append(f"total {report['total_s']:.4f} s ({len(report['commands'])} commands)")
    return "\n".join(line.rstrip() for line in lines)
