"""The simulator's timeline: frames (two clocks and the full ``qpos``) and events.

Frames are stored column-wise in fixed-size numpy chunks (``chunk`` frames each), never
as one Python object per frame: a frame costs ``(2 + nq) * 8`` bytes. Each frame holds

- ``sim_time``: the simulated clock (s), the time the program would take on the real
  robot (thesis §4.4.3, eq. 4.27);
- ``wall_time``: the wall clock (s) of the simulator's stopwatch when the frame was
  computed (path, joint-by-joint) or displayed (playback);
- ``qpos``: MuJoCo's full position vector (every robot's joints; later the parts' free
  joints and the fingers too).

Memory is bounded: when the frames held in memory exceed ``memory_limit`` bytes, the
oldest full blocks are written to an anonymous temporary file (the thesis's play-back
frames "spilled to disk when memory runs out", §4.4.2) and read back one block at a time
when replayed (:meth:`Timeline.iter_blocks`).

Events are few (one per command, grasp, collision, ...) and kept as a list of
:class:`Event`. :meth:`Timeline.mark` and :meth:`Timeline.truncate` let the simulator undo
a failing command exactly. ``Timeline.listeners`` are called with each event as it is
recorded (an event undone later disappears from :attr:`Timeline.events`).
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Iterator
from typing import IO, Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell import limits

__all__ = [
    "DEFAULT_CHUNK",
    "DEFAULT_MEMORY_LIMIT",
    "Event",
    "Events",
    "Timeline",
    "TimelineMark",
]

DEFAULT_CHUNK = 4096
DEFAULT_MEMORY_LIMIT = 32 * 2**20  # bytes of frames kept in memory before spilling
Array = NDArray[np.float64]


class Event(NamedTuple):
    """Something that happened at simulated time ``t`` (s): ``robot`` (None: the whole
    cell), ``kind`` ("move", "wait", "grasp", "release", "collision", "error", ...), a
    human-readable ``detail``, and ``frame``: the frame showing it (for a command, the last
    frame on the timeline when it was recorded, its result; for a collision, the first
    frame in which the pair overlaps; several frames may share one time); ``data``: the
    command's cycle-time record, for the events that end a command (see
    :mod:`workcell.sim.cycle`), else None."""

    t: float
    robot: str | None
    kind: str
    detail: str
    frame: int = -1
    data: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, object]:
        """The DESIGN.md ``{t, robot, kind, detail}`` object, plus ``frame``."""
        return {
            "t": self.t,
            "robot": self.robot,
            "kind": self.kind,
            "detail": self.detail,
            "frame": self.frame,
        }


class Events(tuple[Event, ...]):
    """The events of a run, in order: a tuple that is also callable.

    Read-outs of a run are calls (``sim.events()``, ``sim.summary()``,
    ``sim.cycle_time()``, ``sim.part_positions()``); ``sim.events`` without the call is
    the same tuple, as DESIGN.md's contract spells it, and keeps working unchanged."""

    __slots__ = ()

    def __call__(self) -> Events:
        """The events (this tuple): ``sim.events()`` reads like ``sim.summary()``."""
        return self


class TimelineMark(NamedTuple):
    """A position in a timeline (frames, events) to truncate back to."""

    frames: int
    events: int


class Timeline:
    """Frames and events of one simulation (see the module doc).

    ``nq`` is the width of a frame's ``qpos``; ``chunk`` the number of frames per
    storage block; ``memory_limit`` the bytes of frame blocks kept in memory (None: no
    limit) before the oldest full blocks spill to a temporary file in ``spill_dir``
    (default: the system's temporary folder).
    """

    def __init__(
        self,
        nq: int,
        chunk: int = DEFAULT_CHUNK,
        *,
        memory_limit: int | None = DEFAULT_MEMORY_LIMIT,
        spill_dir: str | None = None,
    ) -> None:
        if not (isinstance(nq, (int, np.integer)) and nq >= 0):
            raise ValueError(f"nq must be an integer >= 0, got {nq!r}")
        if not (isinstance(chunk, (int, np.integer)) and chunk >= 1):
            raise ValueError(f"chunk must be an integer >= 1, got {chunk!r}")
        if memory_limit is not None and not (
            isinstance(memory_limit, (int, np.integer)) and memory_limit >= 0
        ):
            raise ValueError(f"memory_limit must be None or bytes >= 0, got {memory_limit!r}")
        self.nq = int(nq)
        self.chunk = int(chunk)
        self.memory_limit = memory_limit
        self.spill_dir = spill_dir
        # one (chunk, 2 + nq) block per chunk: columns sim_time, wall_time, qpos...;
        # None where the block lives in the spill file (at index * block bytes)
        self._blocks: list[Array | None] = []
        self._n = 0
        self._events: list[Event] = []
        # called with each event as it is recorded (observers such as the live view)
        self.listeners: list[Callable[[Event], None]] = []
        self._file: IO[bytes] | None = None
        self._block_bytes = self.chunk * (2 + self.nq) * 8

    # ------------------------------------------------------------------ storage
    def _get(self, b: int) -> Array:
        """Block b: the array in memory, or a fresh copy read from the spill file."""
        block = self._blocks[b]
        if block is not None:
            return block
        assert self._file is not None
        self._file.seek(b * self._block_bytes)
        data = self._file.read(self._block_bytes)
        return np.frombuffer(data, dtype=np.float64).reshape(self.chunk, 2 + self.nq).copy()

    def _put(self, b: int, block: Array) -> None:
        """Write block b back to the spill file (it stays spilled)."""
        assert self._file is not None
        self._file.seek(b * self._block_bytes)
        self._file.write(np.ascontiguousarray(block).tobytes())

    def _unspill(self, b: int) -> Array:
        if self._blocks[b] is None:
            self._blocks[b] = self._get(b)
        return self._blocks[b]  # type: ignore[return-value]

    def _spill(self) -> None:
        """Move the oldest full in-memory blocks to disk while over the memory limit."""
        if self.memory_limit is None:
            return
        full = self._n // self.chunk  # blocks 0..full-1 are full
        b = 0
        while self.memory_bytes > self.memory_limit:
            while b < full and self._blocks[b] is None:
                b += 1
            if b >= full:
                return
            if self._file is None:
                self._file = tempfile.TemporaryFile(dir=self.spill_dir)  # noqa: SIM115
            self._put(b, self._blocks[b])  # type: ignore[arg-type]
            self._blocks[b] = None

    @property
    def memory_bytes(self) -> int:
        """Bytes of frame blocks held in memory."""
        return sum(blk.nbytes for blk in self._blocks if blk is not None)

    @property
    def spilled_blocks(self) -> int:
        """Number of blocks written to the spill file."""
        return sum(1 for blk in self._blocks if blk is None)

    def close(self) -> None:
        """Drop every frame and event and delete the spill file."""
        self._blocks.clear()
        self._n = 0
        self._events.clear()
        if self._file is not None:
            self._file.close()
            self._file = None

    # ------------------------------------------------------------------ frames
    def __len__(self) -> int:
        return self._n

    def reserve(self, k: int, what: str = "the simulation") -> None:
        """Refuse (LimitError) ``k`` more frames over the ``max_frames`` or
        ``max_spill_bytes`` limit (:mod:`workcell.limits`); :meth:`extend` checks too."""
        n = self._n + k
        limits.check("max_frames", n, f"{what}: the simulation's frames")
        if self.memory_limit is not None:
            spill = n * (2 + self.nq) * 8 - self.memory_limit
            limits.check("max_spill_bytes", spill, f"{what}: the timeline's spill file")

    def append(self, sim_time: float, wall_time: float, qpos: ArrayLike) -> None:
        """Add one frame."""
        q = np.asarray(qpos, dtype=np.float64).reshape(1, -1)
        self.extend([sim_time], [wall_time], q)

    def extend(self, sim_times: ArrayLike, wall_times: ArrayLike, qpos: ArrayLike) -> None:
        """Add frames: ``sim_times`` (k,), ``wall_times`` (k,), ``qpos`` (k, nq)."""
        t = np.asarray(sim_times, dtype=np.float64).reshape(-1)
        w = np.asarray(wall_times, dtype=np.float64).reshape(-1)
        Q = np.asarray(qpos, dtype=np.float64)
        k = len(t)
        if Q.ndim != 2 or Q.shape != (k, self.nq) or w.shape != (k,):
            raise ValueError(
                f"frames must be sim_times (k,), wall_times (k,) and qpos (k, {self.nq}); "
                f"got {t.shape}, {w.shape}, {Q.shape}"
            )
        self.reserve(k)
        done = 0
        while done < k:
            j = self._n % self.chunk
            if j == 0 and self._n // self.chunk >= len(self._blocks):
                self._blocks.append(np.empty((self.chunk, 2 + self.nq)))
            block = self._unspill(self._n // self.chunk)
            take = min(self.chunk - j, k - done)
            block[j : j + take, 0] = t[done : done + take]
            block[j : j + take, 1] = w[done : done + take]
            block[j : j + take, 2:] = Q[done : done + take]
            self._n += take
            done += take
        self._spill()

    def _column(self, cols: slice, start: int = 0, stop: int | None = None) -> Array:
        stop = self._n if stop is None else min(stop, self._n)
        start = max(0, start)
        if start >= stop:
            return np.empty((0, cols.stop - cols.start))
        parts = []
        for b in range(start // self.chunk, (stop - 1) // self.chunk + 1):
            lo = max(start - b * self.chunk, 0)
            hi = min(stop - b * self.chunk, self.chunk)
            parts.append(self._get(b)[lo:hi, cols])
        return np.concatenate(parts, axis=0)

    def sim_times(self, start: int = 0, stop: int | None = None) -> Array:
        """Simulated clock of frames ``start:stop`` (s), a new array."""
        return self._column(slice(0, 1), start, stop).reshape(-1)

    def wall_times(self, start: int = 0, stop: int | None = None) -> Array:
        """Wall clock of frames ``start:stop`` (s), a new array."""
        return self._column(slice(1, 2), start, stop).reshape(-1)

    def qpos(self, start: int = 0, stop: int | None = None) -> Array:
        """``qpos`` of frames ``start:stop``, shape (k, nq), a new array."""
        return self._column(slice(2, 2 + self.nq), start, stop).reshape(-1, self.nq)

    def frame(self, i: int) -> tuple[float, float, Array]:
        """Frame ``i`` (negative counts from the end) as (sim_time, wall_time, qpos copy)."""
        n = self._n
        if not -n <= i < n:
            raise IndexError(f"frame {i} out of range: the timeline has {n} frames")
        i %= n
        row = self._get(i // self.chunk)[i % self.chunk]
        return float(row[0]), float(row[1]), row[2:].copy()

    def iter_blocks(self, start: int = 0) -> Iterator[tuple[int, Array]]:
        """(first frame index, view of rows) for each stored block from frame ``start`` on.

        A row is ``[sim_time, wall_time, *qpos]``; views must not be kept past a write.
        Spilled blocks are read back one at a time (writes to them are not kept).
        """
        i = max(0, start)
        while i < self._n:
            b, j = divmod(i, self.chunk)
            hi = min(self.chunk, self._n - b * self.chunk)
            yield i, self._get(b)[j:hi]
            i += hi - j

    def set_wall_times(self, start: int, wall_times: ArrayLike) -> None:
        """Overwrite the wall clock of frames ``start, start+1, ...`` (playback display times)."""
        w = np.asarray(wall_times, dtype=np.float64).reshape(-1)
        if start < 0 or start + len(w) > self._n:
            raise IndexError(f"frames {start}..{start + len(w)} out of range 0..{self._n}")
        done, i = 0, start
        while done < len(w):
            b, j = divmod(i, self.chunk)
            take = min(self.chunk - j, len(w) - done)
            block = self._get(b)
            block[j : j + take, 1] = w[done : done + take]
            if self._blocks[b] is None:
                self._put(b, block)
            done += take
            i += take

    # ------------------------------------------------------------------ events
    @property
    def events(self) -> Events:
        """Every event, in order (a tuple, also callable: :class:`Events`)."""
        return Events(self._events)

    def add_event(
        self,
        t: float,
        robot: str | None,
        kind: str,
        detail: str = "",
        frame: int | None = None,
        data: dict[str, Any] | None = None,
    ) -> Event:
        """Record an event and return it; its ``frame`` defaults to the last frame so far
        (give it for an event that belongs to a frame about to be added, e.g. a collision
        found while a batch of frames is computed); ``data``: its command record."""
        e = Event(
            float(t), robot, str(kind), str(detail), self._n - 1 if frame is None else frame, data
        )
        self._events.append(e)
        for listener in self.listeners:
            listener(e)
        return e

    # ------------------------------------------------------------------ undo
    def mark(self) -> TimelineMark:
        """The current length, for :meth:`truncate`."""
        return TimelineMark(self._n, len(self._events))

    def truncate(self, mark: TimelineMark) -> None:
        """Drop every frame and event after ``mark`` (frees whole blocks past it)."""
        if not (0 <= mark.frames <= self._n and 0 <= mark.events <= len(self._events)):
            raise ValueError(f"mark {mark} is past the end ({self._n}, {len(self._events)})")
        self._n = mark.frames
        keep = -(-self._n // self.chunk)
        del self._blocks[keep:]
        if self._n % self.chunk:  # the last block is written to again: keep it in memory
            self._unspill(keep - 1)
        if self._file is not None:
            self._file.truncate(keep * self._block_bytes)
        del self._events[mark.events :]

    def __repr__(self) -> str:
        return f"Timeline({self._n} frames, {len(self._events)} events, nq={self.nq})"
