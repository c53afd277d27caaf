"""The command language, cell logic: ``add signal|sensor|conveyor|source|sink``, ``signal
set|wait|show``, ``distance``, ``program``, ``programs``, ``run programs``, ``throughput``,
``gantt``; :mod:`workcell.program.grammar_sim` puts them in the tree. Lengths m (a unit
may follow), belt speeds m/s (``250 mm/s``), times s; a signal value is ``true``,
``false`` (also ``on``/``off``), a whole number or a number.
"""

from __future__ import annotations

import re
from typing import Any

from workcell.program import logiccommands as lc
from workcell.program.grammar_model import TRANSFORM_OPTIONS, TRANSFORM_SYNTAX, transform_of
from workcell.program.keytree import Cursor, Keys, Leaf, Node, Options, Seq, Set
from workcell.program.params import Name, Number, Text, Vector

__all__ = ["ADD_DEVICES", "ALIASES", "BRANCHES", "Value"]

_WORDS = {"true": True, "false": False, "on": True, "off": False}
_INT = re.compile(r"[+-]?\d+")


class Value(Node):
    """A signal value: true/false/on/off, a whole number (an int) or a number (a float)."""

    def __init__(self, key: str) -> None:
        self.key = key

    def expects(self, cur: Cursor) -> list[str]:
        return ["true", "false", "<number>"]

    def match(self, cur: Cursor) -> None:
        tok = cur.peek()
        if tok is None:
            cur.fail("incomplete command: a value is missing", self.expects(cur))
        if tok.kind == "word" and tok.text.lower() in _WORDS:
            cur.take()
            cur.values[self.key] = _WORDS[tok.text.lower()]
            return
        if tok.kind != "number" or tok.unit:
            cur.fail(f"expected true, false or a number, got '{tok.text}'", self.expects(cur))
        cur.take()
        cur.values[self.key] = int(tok.text) if _INT.fullmatch(tok.text) else float(tok.value)


_P3 = {"what": "x y z (m)"}
_ROBOTS = {"robots": Set("robots", True)}


def _sensor(kind: str, v: dict[str, Any]) -> lc.AddSensor:
    keys = ("start", "end", "center", "size", "origin", "direction", "range", "threshold")
    return lc.AddSensor(
        v["name"], kind, **{k: v[k] for k in keys if k in v}, robots=v.get("robots", False)
    )


_SENSOR = Keys(
    {
        "beam": Seq(
            Keys({"from": Vector("start", 3, "length", **_P3)}),
            Keys({"to": Vector("end", 3, "length", **_P3)}),
            Options(_ROBOTS),
            Leaf(
                lambda v: _sensor("beam", v),
                "add sensor NAME beam from X Y Z to X Y Z [robots]",
                "a light beam from one point to another (m): its signal NAME is true while a "
                "movable part crosses it (robots: robot links too)",
                "add sensor beam1 beam from 0.45 0.2 0.43 to 0.45 0.6 0.43",
            ),
        ),
        "presence": Seq(
            Keys({"center": Vector("center", 3, "length", **_P3)}),
            Keys({"size": Vector("size", 3, "length", what="edge lengths (m)")}),
            Options(_ROBOTS),
            Leaf(
                lambda v: _sensor("presence", v),
                "add sensor NAME presence center X Y Z size X Y Z [robots]",
                "a box (full edge lengths, m): true while a part's centroid is inside (robots: "
                "a robot's tool point too)",
                "add sensor here presence center 0.4 0.4 0.45 size 0.1 0.1 0.1",
            ),
        ),
        "proximity": Seq(
            Keys({"at": Vector("origin", 3, "length", **_P3)}),
            Keys({"direction": Vector("direction", 3, None, what="x y z")}),
            Keys({"range": Number("range", "length", what="range (m)")}),
            Keys({"threshold": Number("threshold", "length", what="threshold (m)")}),
            Options(_ROBOTS),
            Leaf(
                lambda v: _sensor("proximity", v),
                "add sensor NAME proximity at X Y Z direction X Y Z range L threshold L [robots]",
                "a ray: 'distance NAME' is the distance to the first surface along it (m), "
                "the signal true while it is within the threshold",
                "add sensor gap proximity at 0.4 0.4 1 direction 0 0 -1 range 1 threshold 0.5",
            ),
        ),
    }
)


def _add_source(v: dict[str, Any]) -> lc.AddSource:
    import numpy as np

    T = transform_of(v)
    count = v.get("count")
    return lc.AddSource(
        v["name"],
        v["part"],
        np.eye(4) if T is None else T,
        v.get("every"),
        None if count is None else int(count),
        v.get("on_signal"),
    )


ADD_DEVICES: dict[str, Node] = {
    "signal": Seq(
        Name("name", new=True, what="signal name"),
        Value("initial"),
        Leaf(
            lambda v: lc.AddSignal(v["name"], v["initial"]),
            "add signal NAME VALUE",
            "declare a signal and its initial value: true/false, a whole number or a number "
            "(its kind)",
            "add signal placed false",
        ),
    ),
    "sensor": Seq(Name("name", new=True, what="sensor name"), _SENSOR),
    "conveyor": Seq(
        Name("name", new=True, what="conveyor name"),
        Keys({"from": Vector("start", 3, "length", **_P3)}),
        Keys({"to": Vector("end", 3, "length", **_P3)}),
        Keys({"width": Number("width", "length", what="width (m)")}),
        Keys({"speed": Number("speed", "tool_speed", what="speed (m/s)")}),
        Options({"run": Name("run_signal", what="signal")}),
        Leaf(
            lambda v: lc.AddConveyor(
                v["name"], v["start"], v["end"], v["width"], v["speed"], v.get("run_signal")
            ),
            "add conveyor NAME from X Y Z to X Y Z width W speed V [run SIGNAL]",
            "a belt whose top surface runs from one point to the other (m, one height) at V "
            "(m/s) while the bool SIGNAL is true (always without one); an end stop holds parts",
            "add conveyor belt from -1 0.4 0.4 to 0.55 0.4 0.4 width 0.2 speed 250 mm/s run go",
        ),
    ),
    "source": Seq(
        Name("name", new=True, what="source name"),
        Name("part", "movable", what="movable part"),
        Options(
            {
                **TRANSFORM_OPTIONS,
                "every": Number("every", "time", what="seconds"),
                "count": Number("count", integer=True, what="count"),
                "on": Name("on_signal", what="signal"),
            }
        ),
        Leaf(
            _add_source,
            f"add source NAME PART {TRANSFORM_SYNTAX} (every T | on SIGNAL) [count N]",
            "copies of a movable part (PART_1, PART_2, ...) at the transform (of the part "
            "frame), every T s from t = 0 or at each rising edge of SIGNAL, at most N",
            "add source feeder box translate -1 0.37 0.4 every 6 count 8",
        ),
    ),
    "sink": Seq(
        Name("name", new=True, what="sink name"),
        Keys({"center": Vector("center", 3, "length", **_P3)}),
        Keys({"size": Vector("size", 3, "length", what="edge lengths (m)")}),
        Leaf(
            lambda v: lc.AddSink(v["name"], v["center"], v["size"]),
            "add sink NAME center X Y Z size X Y Z",
            "a box (full edge lengths, m) that removes and counts the parts whose centroid "
            "enters it",
            "add sink out center 2 0 0.45 size 0.3 0.3 0.3",
        ),
    ),
}


_SIGNAL = Keys(
    {
        "set": Seq(
            Name("name", "signal", what="signal"),
            Value("value"),
            Leaf(
                lambda v: lc.SetSignal(v["name"], v["value"]),
                "signal set NAME VALUE",
                "give a signal its value now",
                "signal set placed true",
            ),
        ),
        "show": Keys(
            {},
            other=Seq(
                Name("name", "signal", what="signal"),
                Leaf(lambda v: lc.Signal(v["name"]), "", "", ""),
            ),
            empty=Leaf(
                lambda v: lc.Signals(),
                "signal show [NAME]",
                "a signal's value, or every signal's",
                "signal show beam",
            ),
        ),
    }
)
# signal wait NAME [VALUE] [timeout T]: the value is optional (true)
_SIGNAL.branches["wait"] = Seq(
    Name("name", "signal", what="signal"),
    Keys(
        {"timeout": Seq(Number("timeout", "time", what="seconds"), Set("value", True))},
        other=Seq(Value("value"), Options({"timeout": Number("timeout", "time", what="seconds")})),
        empty=Set("value", True),
    ),
    Leaf(
        lambda v: lc.WaitSignal(v["name"], v["value"], v.get("timeout")),
        "signal wait NAME [VALUE] [timeout T]",
        "let simulated time pass (the cell alive: belts, sources, sensors, other programs) "
        "until the signal has VALUE (true); after T s: an error (the time has passed)",
        "signal wait beam true timeout 20",
    ),
)

BRANCHES: dict[str, Node] = {
    "signal": _SIGNAL,
    "distance": Seq(
        Name("name", "sensor", what="proximity sensor"),
        Leaf(
            lambda v: lc.Distance(v["name"]),
            "distance SENSOR",
            "a proximity sensor's distance to the first surface on its ray (m)",
            "distance gap",
        ),
    ),
    "program": Seq(
        Name("name", what="robot or controller name"),
        Text("path", "program file (.wcl)"),
        Leaf(
            lambda v: lc.Program(v["name"], v["path"]),
            "program NAME FILE",
            "name a .wcl file as a robot's program (NAME a robot) or a controller's (any "
            "other NAME), for 'run programs'",
            "program ur5e pick.wcl",
        ),
    ),
    "programs": Leaf(lambda v: lc.Programs(), "programs", "the programs named so far", "programs"),
    "run": Keys(
        {
            "programs": Seq(
                Options({"until": Number("until", "time", what="simulated time (s)")}),
                Leaf(
                    lambda v: lc.RunPrograms(None, v.get("until")),
                    "run programs [until T]",
                    "run the named programs together on one simulated clock, until they end "
                    "or until the simulated time T (s)",
                    "run programs until 60",
                ),
            )
        }
    ),
    "throughput": Leaf(
        lambda v: lc.Throughput(),
        "throughput",
        "parts per hour at each sink, signals' rises per hour, each robot's moving / "
        "waiting / idle time",
        "throughput",
    ),
    "gantt": Seq(
        Text("path", "PNG file"),
        Leaf(
            lambda v: lc.Gantt(v["path"]),
            "gantt FILE",
            "write the Gantt chart of the run (every robot and controller program) as a PNG",
            "gantt run.png",
        ),
    ),
}

ALIASES: dict[str, Node] = {
    "set_signal": _SIGNAL.branches["set"],
    "wait_signal": _SIGNAL.branches["wait"],
    "run_programs": BRANCHES["run"].branches["programs"],  # type: ignore[attr-defined]
}
