"""The session every command runs on: a Model, and optionally a Workcell and a Simulator.

A session is what one user (a shell, a script, one remote client) works on. It starts
with an empty :class:`~workcell.Model`, or with what Python hands in; commands replace
its parts only after they have been built without error (``cell load`` loads the file,
then swaps the cell in), so a failed command leaves the session as it was.

When a cell is present, the session's model *is* the cell's model (parts are modelled
there). Relative file paths are taken from ``base_dir`` (a script's folder); a session
with a ``root`` folder (every session of ``workcell serve``) takes every file name
inside ``root`` and refuses the rest (:func:`workcell.files.resolve_inside`).
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import TYPE_CHECKING, Any

from workcell.confine import confined, resolve_inside
from workcell.errors import ProgramError, ProtocolError, WorkcellError
from workcell.modeller.model import Model

if TYPE_CHECKING:
    from workcell.cell.workcell import Workcell
    from workcell.program.base import Command
    from workcell.sim.simulator import Simulator

__all__ = ["Session"]


class Session:
    """A model, optionally a cell and a simulator, and the folder relative paths start from.

    ``Session(sim=sim)`` takes the simulator's cell and model; ``Session(cell=cell)`` the
    cell's model. ``lock`` serialises commands when several front ends share a session.
    ``root``: when given, file names must stay inside this folder (see :meth:`path`).
    """

    def __init__(
        self,
        model: Model | None = None,
        *,
        cell: Workcell | None = None,
        sim: Simulator | None = None,
        base_dir: str | Path = ".",
        root: str | Path | None = None,
    ) -> None:
        if sim is not None:
            cell = sim.cell if cell is None else cell
            if cell is not sim.cell:
                raise ProgramError("Session: the simulator runs another cell than the one given")
        if cell is not None:
            if model is not None and model is not cell.model:
                raise ProgramError("Session: a cell brings its own model; give one or the other")
            model = cell.model
        self._model = Model() if model is None else model
        self.cell = cell
        self.sim = sim
        self.base_dir = Path(base_dir)
        self.root = None if root is None else Path(root)
        self.reply_bytes: int | None = None  # a server's message bound (check_reply)
        self.lock = threading.RLock()
        self._block: tuple[Simulator, Any] | None = None

    @property
    def block(self) -> tuple[Simulator, Any] | None:
        """The open ``concurrently_begin`` block: (its simulator, the entered context), or
        None (a block of a simulator the session no longer runs is gone with it)."""
        if self._block is not None and self._block[0] is not self.sim:
            self._block = None
        return self._block

    @block.setter
    def block(self, value: tuple[Simulator, Any] | None) -> None:
        self._block = value

    @property
    def model(self) -> Model:
        """The datamodel commands work on (the cell's model when a cell is loaded)."""
        return self.cell.model if self.cell is not None else self._model

    def set_model(self, model: Model) -> None:
        """Replace the model; refused while a cell is loaded (its parts live in its model)."""
        if self.cell is not None:
            raise ProgramError(
                f"cell '{self.cell.name}' is loaded and its parts live in its model; "
                "load a cell file instead (cell load FILE), or start a new session"
            )
        self._model = model

    def set_cell(self, cell: Workcell | None) -> None:
        """Replace the cell (and drop the simulator of the old one)."""
        self.cell = cell
        self.sim = None

    def require_cell(self) -> Workcell:
        """The cell; ProgramError when there is none yet."""
        if self.cell is None:
            raise ProgramError(
                "no cell yet: start one with 'cell new NAME', 'cell load FILE' or "
                "'cell example joints|pick-place|handoff|obstacle'"
            )
        return self.cell

    def require_sim(self) -> Simulator:
        """The simulator; ProgramError when there is none yet."""
        if self.sim is None:
            hint = "" if self.cell is not None else " after loading a cell"
            raise ProgramError(
                f"no simulation running: start one with 'simulate [MODE] [dt SECONDS]'{hint}"
            )
        return self.sim

    def path(self, path: str) -> Path:
        """The file a command names: with a ``root``, ``path`` relative to it and inside it
        (absolute paths, ``~``, ``..``, hidden names and symbolic links leading out are
        refused with ProgramError); without, taken from ``base_dir`` when relative (``~``
        expanded)."""
        if self.root is not None:
            return resolve_inside(self.root, path, error=ProgramError)
        p = Path(path).expanduser()
        return p if p.is_absolute() else self.base_dir / p

    def check_reply(self, numbers: int, what: str) -> None:
        """Before a reply of at least ``numbers`` numbers is built: ProtocolError when it
        cannot fit the session's ``reply_bytes`` (a server's message bound; each number
        takes 2 bytes at least, a digit and a comma). Nothing to check without a bound."""
        if self.reply_bytes is not None and 2 * numbers > self.reply_bytes:
            raise ProtocolError(
                f"{what}: the reply would be at least {2 * numbers:,} bytes ({numbers:,} "
                f"numbers), over the {self.reply_bytes:,}-byte bound of a protocol message; "
                "nothing was built: ask for less, or record the run to a file"
            )

    def execute(self, command: Command) -> Any:
        """Run one command under the session's lock and return its result; with a
        ``root``, every file the command reads must lie inside it
        (:func:`workcell.confine.confined`)."""
        with self.lock, confined(self.root):
            return command.execute(self)

    # ------------------------------------------------------------------ names (completion)
    def names(self, kind: str) -> list[str]:
        """Known names of ``kind`` for completion and checks.

        Kinds: a datamodel level, ``entity`` (every level), ``owner`` (blocks, objects,
        scenes), ``robot``, ``part`` (static and movable), ``movable``, ``cellitem``.
        """
        m = self.model
        if kind in ("surface", "block", "object", "scene"):
            return list(m.list(kind))
        if kind == "entity":
            return [n for lv in ("surface", "block", "object", "scene") for n in m.list(lv)]
        if kind == "owner":
            return [n for lv in ("block", "object", "scene") for n in m.list(lv)]
        cell = self.cell
        if cell is None:
            return []
        if kind == "robot":
            return list(self.sim.robots) if self.sim is not None else list(cell.robots)
        if kind == "part":
            return [*cell.static_parts, *cell.movable_parts]
        if kind == "movable":
            return list(cell.movable_parts)
        if kind == "cellitem":
            return cell.names()
        return []

    def relation_names(self, owner: str | tuple[str, str]) -> list[str]:
        """Relation names of ``owner`` (empty when it is unknown)."""
        try:
            return [r.name for r in self.model.relations(owner)]
        except WorkcellError:  # an unknown or ambiguous owner: nothing to complete
            return []

    def pose_names(self, robot: str) -> list[str] | None:
        """The named poses of ``robot`` ("home" ...), None when the robot is unknown."""
        if self.cell is None or robot not in self.cell.robots:
            return None
        return list(self.cell.robots[robot].robot.poses)

    def joint_kinds(self, robot: str) -> list[bool] | None:
        """For each joint of ``robot``, True when revolute (None when unknown)."""
        if self.cell is None or robot not in self.cell.robots:
            return None
        return [bool(x) for x in self.cell.robots[robot].robot.revolute]

    def __repr__(self) -> str:
        cell = f"cell '{self.cell.name}'" if self.cell is not None else "no cell"
        sim = f"simulator {self.sim.mode}" if self.sim is not None else "no simulator"
        return f"Session({self.model!r}, {cell}, {sim})"
