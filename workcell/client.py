"""The Python client of the remote program interface (``workcell serve``, protocol v1).

A :class:`Client` has every public method of the Simulator (``set_speed``,
``move_joints_absolute``, ``move_end_effector``, ``close_gripper``, ``joints``,
``tool_pose``, ``part_pose``, ``trajectory``, ``summary``, ``concurrently()``, the
properties ``robots``, ``frames``, ``sim_time``, ``wall_time``, ``events`` ...; a test
compares the two) with the same arguments
in SI units (rad, m, s; numpy arrays are sent as lists and joint vectors and poses come
back as arrays), so one program runs unchanged in-process or remote::

    def program(sim):                      # thesis_joints.program, for instance
        sim.set_speed("puma", 0.3)
        sim.move_joints_relative("puma", np.radians([-70, -10, 10, 30, -20, -10]))

    with Client(port=5260) as sim:
        sim.example_cell("joints")
        sim.simulate("path", dt=0.01)
        program(sim)
        print(sim.sim_time)

Every other command of the vocabulary is a method too (``client.create_cube("c", 0.04)``,
``client.call("attach", owner="cube1", target="square1")``). An error reply raises the
matching :class:`~workcell.errors.WorkcellError` subclass (JointLimitError, ModelError,
...) with the server's message, which ends the program unless it catches it, as the
thesis's programs end on an error; the connection stays usable.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.cell.workcell import Workcell
from workcell.client_link import ServerLink
from workcell.errors import ProgramError, WorkcellError
from workcell.program.protocol import to_jsonable
from workcell.sim.timeline import Event, Events

__all__ = ["Client"]

# commands that never change the cell (the simulation commands and read-backs)
_KEEPS_CELL = frozenset(
    {
        "cell_data", "set_speed", "set_mode", "move_joints_absolute", "move_joints_relative",
        "move_end_effector", "move_straight_line", "close_gripper", "open_gripper", "wait",
        "move_linear", "move_circular", "set_override", "set_profile", "cycle_time",
        "pick", "place", "handover", "set_planning",
        "play", "joints", "tool_pose", "held", "clearance", "summary", "part_positions",
        "robots", "frames", "sim_time", "events", "hello", "part_pose", "gripper_pose",
        "speed", "trajectory", "wall_time", "concurrently_begin", "concurrently_end",
        "export_program", "run_robot_program",
        "set_signal", "wait_signal", "signal", "signals", "distance", "throughput", "gantt",
        "programs", "run_programs",
    }
)  # fmt: skip


class Client(ServerLink):
    """A connection to a workcell server (see the module doc; the connection itself:
    :mod:`workcell.client_link`).

    ``token``: sent in the hello; when None and the server asks for one, the
    ``WORKCELL_TOKEN`` environment variable, else (for a server on this machine) its
    token file (:mod:`workcell.program.tokens`), so local programs need not say it.
    ``timeout`` (s): for connecting and for each reply (None: wait as long as it takes).
    """

    _cell: Workcell | None = None  # the session's cell as last fetched (None: fetch it)

    def call(self, command: str, /, *args: Any, **kwargs: Any) -> Any:
        """Send one command (arguments in order, or by name, not both) and return its result.

        Raises the WorkcellError subclass the server names on an error reply.
        """
        if args and kwargs:
            raise ProgramError("give a command's arguments in order or by name, not both")
        if command not in _KEEPS_CELL:
            self._cell = None  # the cell may change: fetch it again when asked
        return self._request(command, list(args) if args else kwargs)

    def __getattr__(self, name: str) -> Any:
        from workcell.program.base import COMMANDS

        if name.startswith("_") or name not in COMMANDS:
            raise AttributeError(f"{type(self).__name__} has no command {name!r}")
        return lambda *args, **kwargs: self.call(name, *args, **kwargs)

    # ------------------------------------------------------------------ Simulator API
    def set_speed(self, robot: str, speed: float) -> None:
        """Set the robot's speed (rad/s)."""
        self.call("set_speed", robot=robot, speed=speed)

    def set_mode(self, mode: str) -> None:
        """Switch mode: "path", "joint-by-joint" or "playback"."""
        self.call("set_mode", mode=mode)

    def move_joints_absolute(
        self, robot: str, q: ArrayLike | str, *, zone: float = 0.0, plan: bool = False
    ) -> None:
        """Move the joints to ``q`` (rad/m), or to a named pose of the robot ("home");
        ``zone`` (m): blend into the next move; ``plan``: along a collision-free path."""
        self.call("move_joints_absolute", robot=robot, q=_list(q), zone=zone, plan=plan)

    def jog(self, robot: str, q: ArrayLike) -> None:
        """Set the joints to ``q`` (rad/m) at once: no simulated time passes."""
        self.call("jog", robot=robot, q=_list(q))

    def move_joints_relative(self, robot: str, dq: ArrayLike, *, zone: float = 0.0) -> None:
        """Move the joints by ``dq`` (rad/m); ``zone`` (m): blend into the next move."""
        self.call("move_joints_relative", robot=robot, dq=_list(dq), zone=zone)

    def move_end_effector(
        self,
        robot: str,
        T: ArrayLike,
        config: str | None = None,
        *,
        zone: float = 0.0,
        plan: bool = False,
    ) -> None:
        """Move the tool to world pose ``T`` (4x4, m); ``zone`` (m): blend into the next
        move; ``plan``: along a collision-free path."""
        self.call("move_end_effector", robot=robot, T=_list(T), config=config, zone=zone, plan=plan)

    def move_straight_line(self, robot: str, T: ArrayLike, step: float = 0.005) -> None:
        """Move the tool along a straight line to ``T`` (4x4), samples ``step`` (m) apart."""
        self.call("move_straight_line", robot=robot, T=_list(T), step=step)

    def move_linear(
        self,
        robot: str,
        T: ArrayLike,
        *,
        speed: float,
        acceleration: float | None = None,
        zone: float = 0.0,
    ) -> None:
        """Move the tool point along a line to ``T`` (4x4) at ``speed`` (m/s),
        ``acceleration`` (m/s^2, default 1.2); ``zone`` (m): blend into the next move."""
        self.call(
            "move_linear", robot=robot, T=_list(T), speed=speed,
            acceleration=acceleration, zone=zone,
        )  # fmt: skip

    def move_circular(
        self,
        robot: str,
        via: ArrayLike,
        T: ArrayLike,
        *,
        speed: float,
        acceleration: float | None = None,
        zone: float = 0.0,
    ) -> None:
        """Move the tool point along the arc through ``via`` (a point (3,) or a pose) to
        ``T`` (4x4) at ``speed`` (m/s)."""
        self.call(
            "move_circular", robot=robot, via=_list(via), T=_list(T), speed=speed,
            acceleration=acceleration, zone=zone,
        )  # fmt: skip

    def set_override(self, robot: str, override: float) -> None:
        """Set the robot's speed override, 0 < f <= 1."""
        self.call("set_override", robot=robot, override=override)

    def set_profile(self, profile: str, acceleration: float | None = None) -> None:
        """Set the joint-move profile: linear, trapezoid, quintic or jerk."""
        self.call("set_profile", profile=profile, acceleration=acceleration)

    def cycle_time(self) -> dict[str, Any]:
        """The cycle-time report: ``total_s`` and the records of ``commands``."""
        return self.call("cycle_time")

    def close_gripper(
        self, robot: str, max_distance: float = 0.02, max_angle: float = math.radians(10)
    ) -> str:
        """Grasp a part (tests within ``max_distance`` m and ``max_angle`` rad); its name."""
        return self.call(
            "close_gripper", robot=robot, max_distance=max_distance, max_angle=max_angle
        )

    def open_gripper(self, robot: str, *, settle: bool = False) -> str | None:
        """Release the part held (its name, or None); ``settle``: drop it onto its support."""
        return self.call("open_gripper", robot=robot, settle=settle)

    def set_planning(
        self,
        *,
        clearance: float | None = None,
        time_limit: float | None = None,
        seed: int | None = None,
        near_clearance: float | None = None,
    ) -> dict[str, float]:
        """Change how planned moves search (m, s, seed); the settings in force."""
        return self.call(
            "set_planning",
            clearance=clearance,
            time_limit=time_limit,
            seed=seed,
            near_clearance=near_clearance,
        )

    def pick(self, robot: str, part: str, *, approach: float = 0.08) -> str:
        """Grasp ``part`` (grasp, configuration and collision-free path chosen by the server)."""
        return self.call("pick", robot=robot, part=part, approach=approach)

    def place(
        self,
        robot: str,
        part: str,
        *,
        on: str,
        position: ArrayLike | None = None,
        approach: float = 0.08,
    ) -> None:
        """Put the held ``part`` down resting on ``on``, centroid over ``position`` (x, y m)."""
        pos = None if position is None else _list(position)
        if isinstance(pos, list) and len(pos) > 2 and all(isinstance(v, float) for v in pos):
            pos = pos[:2]  # (x, y) of a point (3,): as Simulator.place takes it
        self.call("place", robot=robot, part=part, on=on, position=pos, approach=approach)

    def handover(self, giver: str, receiver: str, part: str, *, approach: float = 0.08) -> None:
        """Hand ``part`` from ``giver`` to ``receiver`` at a meeting pose the server finds."""
        self.call("handover", giver=giver, receiver=receiver, part=part, approach=approach)

    def wait(self, seconds: float) -> None:
        """Let ``seconds`` of simulated time pass."""
        self.call("wait", seconds=seconds)

    def export_program(
        self,
        robot: str,
        path: str,
        *,
        language: str | None = None,
        signals: dict[str, int] | None = None,
    ) -> list[str]:
        """Write ``robot``'s program as it ran to ``path`` (on the server, inside its root)
        in ``language`` (default from the suffix); the files written."""
        return self.call(
            "export_program", robot=robot, path=path, language=language, signals=signals or {}
        )

    def run_robot_program(
        self, robot: str, path: str, *, language: str | None = None
    ) -> dict[str, Any]:
        """Run the robot program file ``path`` (on the server) on ``robot``: the simulated
        clock (``sim_time_s``) and the ``outputs`` it set."""
        return self.call("run_robot_program", robot=robot, path=path, language=language)

    def play(self, realtime: bool | None = None) -> int:
        """Replay the stored frames; the number shown."""
        return self.call("play", realtime=realtime)

    def joints(self, robot: str) -> NDArray[np.float64]:
        """The robot's joint values (rad/m)."""
        return np.array(self.call("joints", robot=robot), dtype=np.float64)

    def tool_pose(self, robot: str) -> NDArray[np.float64]:
        """The robot's tool pose (4x4 world, m)."""
        return np.array(self.call("tool_pose", robot=robot), dtype=np.float64)

    def held(self, robot: str) -> str | None:
        """The part the robot holds, or None."""
        return self.call("held", robot=robot)

    def clearance(self, a: str, b: str) -> float:
        """The distance (m) between two things of the cell."""
        return float(self.call("clearance", a=a, b=b))

    def summary(self) -> dict[str, Any]:
        """sim_time_s, wall_time_s, frames, events, collisions, objects, mjcf."""
        return self.call("summary")

    def part_pose(self, part: str) -> NDArray[np.float64]:
        """A movable part's frame in the world (4x4, m)."""
        return np.array(self.call("part_pose", part=part), dtype=np.float64)

    def gripper_pose(self, robot: str) -> NDArray[np.float64]:
        """The robot's gripper body in the world (4x4, m)."""
        return np.array(self.call("gripper_pose", robot=robot), dtype=np.float64)

    def speed(self, robot: str) -> float:
        """The robot's speed (rad/s): the speed of the joint that moves most."""
        return float(self.call("speed", robot=robot))

    def trajectory(self, robot: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(simulated times (N,) s, joint values (N, dof) rad/m) of every frame for one
        robot (a long run may exceed the protocol's message bound)."""
        r = self.call("trajectory", robot=robot)
        t = np.array(r["t"], dtype=np.float64)
        return t, np.array(r["q"], dtype=np.float64).reshape(len(t), -1)

    @contextmanager
    def concurrently(self) -> Iterator[None]:
        """The robots' motion commands inside the block run at the same time (the
        Simulator's ``concurrently()``); an error inside the block drops the whole block."""
        self.call("concurrently_begin")
        try:
            yield
        except BaseException:
            with suppress(WorkcellError):  # the server drops the block (or has lost it)
                self.call("concurrently_end", commit=False)
            raise
        self.call("concurrently_end", commit=True)

    def signal(self, name: str) -> bool | int | float:
        """A signal's value now."""
        return self.call("signal", name=name)[name]

    def signals(self) -> dict[str, bool | int | float]:
        """Every signal's value now, by name."""
        return self.call("signals")

    def set_signal(self, name: str, value: bool | int | float) -> None:
        """Give a signal its value now."""
        self.call("set_signal", name=name, value=_plain_value(value))

    def wait_signal(
        self, name: str, value: bool | int | float = True, *, timeout: float | None = None
    ) -> None:
        """Let simulated time pass until the signal has ``value``; at most ``timeout`` s
        (SignalTimeout then)."""
        self.call("wait_signal", name=name, value=_plain_value(value), timeout=timeout)

    def distance(self, name: str) -> float:
        """A proximity sensor's distance (m) to the first surface on its ray (inf: none)."""
        d = self.call("distance", name=name)
        return math.inf if d is None else float(d)

    def run_programs(
        self, programs: dict[str, Any], *, until: float | None = None
    ) -> dict[str, dict[str, Any]]:
        """Run programs together on the server: ``programs`` maps names (a robot's, or a
        controller's) to ``.wcl`` files in the server's folder (Python functions do not
        travel: run them in-process, or send their commands one by one)."""
        if not isinstance(programs, dict):
            raise ProgramError(
                "run_programs: programs must be a dict of names to .wcl files, got "
                f"{type(programs).__name__}"
            )
        for name, body in programs.items():
            if not isinstance(body, (str, os.PathLike)):
                raise ProgramError(
                    f"run_programs over the network: program '{name}' must be a .wcl file on "
                    f"the server, got {type(body).__name__} (Python functions run in-process)"
                )
        files = {k: os.fspath(v) for k, v in programs.items()}
        return self.call("run_programs", programs=files, until=until)

    def throughput(self) -> dict[str, Any]:
        """The cell's results: parts per hour at each sink, signals' rises per hour, each
        robot's moving / waiting / idle fractions."""
        return self.call("throughput")

    def part_positions(self) -> dict[str, list[float]]:
        """World position (m) of each movable part's centroid."""
        return self.call("part_positions")

    @property
    def robots(self) -> tuple[str, ...]:
        """The cell's robot names."""
        return tuple(self.call("robots"))

    @property
    def frames(self) -> int:
        """Frames on the timeline."""
        return int(self.call("frames"))

    @property
    def sim_time(self) -> float:
        """The simulated clock (s)."""
        return float(self.call("sim_time"))

    @property
    def wall_time(self) -> float:
        """The server simulator's wall clock (s): time spent on commands and replays."""
        return float(self.call("wall_time"))

    @property
    def events(self) -> Events:
        """The timeline's events: ``sim.events()`` or ``sim.events`` (the same tuple), as
        on :class:`~workcell.sim.Simulator`."""
        return Events(
            Event(e["t"], e["robot"], e["kind"], e["detail"]) for e in self.call("events")
        )

    @property
    def cell(self) -> Workcell:
        """A copy of the session's cell (fetched once, again after commands that may change
        it), so programs can read robots, poses and parts as from ``Simulator.cell``."""
        if self._cell is None:
            self._cell = Workcell.from_dict(self.call("cell_data"), source="the server's cell")
        return self._cell

    # ------------------------------------------------------------------ session
    def simulate(self, mode: str = "path", dt: float = 0.01, realtime: bool = False) -> None:
        """Start simulating the session's cell (mode, sampling interval dt in s)."""
        self.call("simulate", mode=mode, dt=dt, realtime=realtime)

    def example_cell(self, name: str) -> str:
        """Load one of the thesis's example cells: "joints", "pick-place", "handoff"."""
        return self.call("example_cell", name=name)


def _plain_value(v: Any) -> Any:
    """A signal value as plain JSON (numpy scalars become Python ones)."""
    return v.item() if isinstance(v, np.generic) else v


def _list(v: Any) -> Any:
    """A vector or matrix as nested lists; a target object (dict) or a name as it is; what
    is not numbers is sent as it is, for the server to refuse with a ProgramError."""
    if isinstance(v, (dict, str)):
        return v
    try:
        return np.asarray(v, dtype=np.float64).tolist()
    except (TypeError, ValueError):
        return to_jsonable(v)
