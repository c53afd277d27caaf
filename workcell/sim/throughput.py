"""Cell results: parts per hour at each sink, each robot's moving / waiting / idle time,
and the activity intervals a Gantt chart draws (:mod:`workcell.record.gantt`).

All of it is read from the timeline's events, so it is the run's own account:

- a sink's parts are its ``sink`` events; parts per hour = parts x 3600 / the simulated
  time of the whole timeline;
- a bool signal's rising edges (false -> true ``signal`` events) are counted the same way
  (a cell without a sink counts its work this way, e.g. a robot setting ``placed``);
- a robot is *moving* during its motion commands (the records of ``summary()["commands"]``
  whose ``limited_by`` is not a wait), *waiting* during its ``wait`` and ``wait_signal``
  records (and, in ``run_programs``, while its program waits for it to stop: that is
  moving), *idle* the rest of the time; the three fractions of the timeline's simulated
  time add up to 1;
- :func:`activity` lists, per robot and per controller program of ``run_programs``, the
  intervals (start, end, "moving" | "waiting"), sorted.

Times in seconds.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

from workcell.sim.timeline import Event

__all__ = ["WAIT_COMMANDS", "activity", "format_throughput", "throughput"]

WAIT_COMMANDS = ("wait", "wait_signal")


def _records(events: Iterable[Event]) -> list[dict[str, Any]]:
    return [e.data for e in events if e.data is not None and "command" in e.data]


def activity(events: Sequence[Event], total: float) -> dict[str, list[tuple[float, float, str]]]:
    """Per robot (by name) and per controller program (by its program name) the intervals
    of its commands that take time, clipped to [0, ``total``] s: (start, end, kind) with
    kind "moving" or "waiting", sorted by start."""
    rows: dict[str, list[tuple[float, float, str]]] = {}
    for r in _records(events):
        who = r.get("robot") or r.get("program_name")
        if who is None or r["duration_s"] <= 0:
            continue
        t0 = max(0.0, float(r["t_start"]))
        t1 = min(total, t0 + float(r["duration_s"]))
        if t1 <= t0:
            continue
        kind = "waiting" if r["command"] in WAIT_COMMANDS else "moving"
        rows.setdefault(who, []).append((t0, t1, kind))
    return {k: sorted(v) for k, v in rows.items()}


def _covered(intervals: list[tuple[float, float, str]], kind: str) -> float:
    """Length (s) of the union of the intervals of ``kind``."""
    total, end = 0.0, -1.0
    for t0, t1, k in intervals:
        if k != kind:
            continue
        if t0 > end:
            total += t1 - t0
            end = t1
        elif t1 > end:
            total += t1 - end
            end = t1
    return total


def throughput(
    events: Sequence[Event],
    total: float,
    robots: Iterable[str],
    sinks: Iterable[str] = (),
    bool_signals: Iterable[str] = (),
) -> dict[str, Any]:
    """The cell's results over ``total`` s of simulated time (module doc):
    ``{"time_s", "sinks": {name: {"parts", "parts_per_hour"}}, "signals": {name: {"rising",
    "per_hour"}}, "robots": {name: {"moving", "waiting", "idle"} (fractions) and
    "moving_s", "waiting_s", "idle_s"}}``."""
    T = float(total)
    per_hour = (lambda n: n * 3600.0 / T) if T > 0 else (lambda n: 0.0)
    counts = dict.fromkeys(sinks, 0)
    rising = dict.fromkeys(bool_signals, 0)
    last: dict[str, object] = dict.fromkeys(rising, False)
    for e in events:
        d = e.data or {}
        if e.kind == "sink" and d.get("sink") in counts:
            counts[d["sink"]] += 1
        elif e.kind == "signal" and d.get("signal") in rising:
            v = d.get("value")
            if v is True and last[d["signal"]] is not True:
                rising[d["signal"]] += 1
            last[d["signal"]] = v
    rows = activity(events, T)
    out_robots = {}
    for r in robots:
        iv = rows.get(r, [])
        moving, waiting = _covered(iv, "moving"), _covered(iv, "waiting")
        idle = max(T - moving - waiting, 0.0)
        f = (lambda x: x / T) if T > 0 else (lambda x: 0.0)
        out_robots[r] = {
            "moving": f(moving), "waiting": f(waiting), "idle": f(idle),
            "moving_s": moving, "waiting_s": waiting, "idle_s": idle,
        }  # fmt: skip
    return {
        "time_s": T,
        "sinks": {k: {"parts": n, "parts_per_hour": per_hour(n)} for k, n in counts.items()},
        "signals": {k: {"rising": n, "per_hour": per_hour(n)} for k, n in rising.items()},
        "robots": out_robots,
    }


def format_throughput(result: dict[str, Any]) -> str:
    """:func:`throughput`'s result as text for people."""
    lines = [f"over {result['time_s']:.6g} s of simulated time:"]
    for k, v in result["sinks"].items():
        lines.append(f"  sink {k}: {v['parts']} parts, {v['parts_per_hour']:.4g} per hour")
    for k, v in result["signals"].items():
        if v["rising"]:
            lines.append(f"  signal {k}: rose {v['rising']} times, {v['per_hour']:.4g} per hour")
    for k, v in result["robots"].items():
        lines.append(
            f"  robot {k}: moving {100 * v['moving']:.1f} %, waiting {100 * v['waiting']:.1f} %, "
            f"idle {100 * v['idle']:.1f} %"
        )
    return "\n".join(lines)
