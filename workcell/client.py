"""The Python client of the remote program interface (``workcell serve``, protocol v1).

A :class:`Client` has the Simulator's method names (``set_speed``, ``move_joints_absolute``,
``move_end_effector``, ``close_gripper``, ``joints``, ``tool_pose``, ``summary``, the
properties ``robots``, ``frames``, ``sim_time``, ``events`` ...) with the same arguments
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

import json
import math
import os
import socket
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.cell.workcell import Workcell
from workcell.errors import ProtocolError, WorkcellError
from workcell.program.protocol import (
    DEFAULT_PORT,
    MAX_MESSAGE_BYTES,
    PROTOCOL,
    VERSION,
    encode,
    error_class,
)
from workcell.sim.timeline import Event

__all__ = ["Client"]

# commands that never change the cell (the simulation commands and read-backs)
_KEEPS_CELL = frozenset(
    {
        "cell_data", "set_speed", "set_mode", "move_joints_absolute", "move_joints_relative",
        "move_end_effector", "move_straight_line", "close_gripper", "open_gripper", "wait",
        "play", "joints", "tool_pose", "held", "clearance", "summary", "part_positions",
        "robots", "frames", "sim_time", "events", "hello",
    }
)  # fmt: skip


class Client:
    """A connection to a workcell server (see the module doc).

    ``token``: sent in the hello; when None and the server asks for one, the
    ``WORKCELL_TOKEN`` environment variable, else (for a server on this machine) its
    token file (:mod:`workcell.program.tokens`), so local programs need not say it.
    ``timeout`` (s): for connecting and for each reply (None: wait as long as it takes).
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = DEFAULT_PORT,
        *,
        token: str | None = None,
        timeout: float | None = None,
    ) -> None:
        try:
            self._sock = socket.create_connection((host, port), timeout=timeout)
        except OSError as exc:
            raise ProtocolError(f"cannot connect to {host}:{port}: {exc.strerror or exc}") from exc
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._r = self._sock.makefile("rb")
        self._next_id = 0
        self._cell: Workcell | None = None
        self.server_hello = self._read()
        err = self.server_hello.get("error")
        if isinstance(err, dict):  # refused at once (busy): say why
            self.close()
            raise error_class(err.get("type"))(str(err.get("message")))
        if self.server_hello.get("protocol") != PROTOCOL:
            self.close()
            raise ProtocolError(f"{host}:{port} does not speak the workcell protocol")
        if self.server_hello.get("version") != VERSION:
            self.close()
            raise ProtocolError(
                f"server speaks protocol version {self.server_hello.get('version')}, "
                f"this client {VERSION}"
            )
        if token is None and self.server_hello.get("token_required"):
            token = _local_token(host, port)
            if token is None:
                self.close()
                raise ProtocolError(
                    f"the server at {host}:{port} needs a token: pass token=..., set "
                    "WORKCELL_TOKEN, or run on the server's machine as its user (token file)"
                )
        self.call("hello", version=VERSION, token=token)  # required before any command

    # ------------------------------------------------------------------ plumbing
    def _read(self) -> dict[str, Any]:
        line = self._r.readline(MAX_MESSAGE_BYTES + 1)
        if not line:
            raise ProtocolError("the server closed the connection")
        if len(line) > MAX_MESSAGE_BYTES:
            self.close()
            raise ProtocolError(f"the server sent a message over {MAX_MESSAGE_BYTES} bytes")
        try:
            msg = json.loads(line)
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise ProtocolError(f"the server sent malformed JSON: {exc}") from exc
        if not isinstance(msg, dict):
            raise ProtocolError("the server sent something other than a JSON object")
        return msg

    def call(self, command: str, /, *args: Any, **kwargs: Any) -> Any:
        """Send one command (arguments in order, or by name, not both) and return its result.

        Raises the WorkcellError subclass the server names on an error reply.
        """
        if args and kwargs:
            raise WorkcellError("give a command's arguments in order or by name, not both")
        if command not in _KEEPS_CELL:
            self._cell = None  # the cell may change: fetch it again when asked
        self._next_id += 1
        rid = self._next_id
        data = encode({"id": rid, "command": command, "args": list(args) if args else kwargs})
        if len(data) > MAX_MESSAGE_BYTES:
            raise ProtocolError(
                f"request of {len(data)} bytes is over the {MAX_MESSAGE_BYTES} limit"
            )
        try:
            self._sock.sendall(data)
        except OSError as exc:
            raise ProtocolError(f"connection lost: {exc}") from exc
        reply = self._read()
        if "error" in reply:
            err = reply["error"] if isinstance(reply["error"], dict) else {}
            raise error_class(err.get("type"))(str(err.get("message", "error without a message")))
        if reply.get("id") != rid:
            raise ProtocolError(f"reply to request {reply.get('id')!r}, expected {rid}")
        return reply.get("result")

    def close(self) -> None:
        """Close the connection (idempotent)."""
        try:
            self._r.close()
            self._sock.close()
        except OSError:
            pass

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

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

    def move_joints_absolute(self, robot: str, q: ArrayLike) -> None:
        """Move the joints to ``q`` (rad/m)."""
        self.call("move_joints_absolute", robot=robot, q=_list(q))

    def move_joints_relative(self, robot: str, dq: ArrayLike) -> None:
        """Move the joints by ``dq`` (rad/m)."""
        self.call("move_joints_relative", robot=robot, dq=_list(dq))

    def move_end_effector(self, robot: str, T: ArrayLike, config: str | None = None) -> None:
        """Move the tool to world pose ``T`` (4x4, m)."""
        self.call("move_end_effector", robot=robot, T=_list(T), config=config)

    def move_straight_line(self, robot: str, T: ArrayLike, step: float = 0.005) -> None:
        """Move the tool along a straight line to ``T`` (4x4), samples ``step`` (m) apart."""
        self.call("move_straight_line", robot=robot, T=_list(T), step=step)

    def close_gripper(
        self, robot: str, max_distance: float = 0.02, max_angle: float = math.radians(10)
    ) -> str:
        """Grasp a part (tests within ``max_distance`` m and ``max_angle`` rad); its name."""
        return self.call(
            "close_gripper", robot=robot, max_distance=max_distance, max_angle=max_angle
        )

    def open_gripper(self, robot: str) -> str | None:
        """Release the part held (its name, or None)."""
        return self.call("open_gripper", robot=robot)

    def wait(self, seconds: float) -> None:
        """Let ``seconds`` of simulated time pass."""
        self.call("wait", seconds=seconds)

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

    def part_positions(self) -> dict[str, list[float]]:
        """World position (m) of each movable part."""
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
    def events(self) -> tuple[Event, ...]:
        """The timeline's events."""
        return tuple(Event(e["t"], e["robot"], e["kind"], e["detail"]) for e in self.call("events"))

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


def _local_token(host: str, port: int) -> str | None:
    """WORKCELL_TOKEN, else the token file of a server on this machine (never sent to
    another machine's server)."""
    from workcell.program.tokens import is_loopback, read_token_file

    env = os.environ.get("WORKCELL_TOKEN")
    if env:
        return env
    return read_token_file(port) if is_loopback(host) else None


def _list(v: Any) -> Any:
    """A vector or matrix as nested lists; a target object (dict) as it is."""
    if isinstance(v, dict):
        return v
    return np.asarray(v, dtype=np.float64).tolist()
