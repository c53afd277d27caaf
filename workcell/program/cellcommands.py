"""The command vocabulary, cell part: build, load, save and show the session's workcell.

A cell holds parts (blocks or objects of the session's model placed in the world),
robots and cameras (:class:`~workcell.Workcell`). Cell edits are refused while the cell
is being simulated (the simulator compiled it): ``simulate stop`` first.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from workcell.errors import ProgramError
from workcell.examples import CELLS
from workcell.program import args as a
from workcell.program.args import arg
from workcell.program.base import Command
from workcell.robots.library import library

if TYPE_CHECKING:
    from workcell.cell.workcell import Workcell
    from workcell.program.session import Session

__all__ = [
    "EXAMPLES",
    "AddCamera",
    "AddMovable",
    "AddRobot",
    "AddStatic",
    "CellData",
    "ExampleCell",
    "ImportRobot",
    "LoadCell",
    "NewCell",
    "RemoveFromCell",
    "SaveCell",
    "ShowCell",
]

EXAMPLES = CELLS  # the thesis's example cells (ch. 5): name -> module with build()
_opt_matrix = a.optional(a.matrix)


def _T(m: tuple[tuple[float, ...], ...] | None) -> np.ndarray | None:
    return None if m is None else np.array(m, dtype=np.float64)


def _editable(session: Session) -> Workcell:
    cell = session.require_cell()
    if session.sim is not None:
        raise ProgramError(
            f"cell '{cell.name}' is being simulated; end the simulation first ('simulate stop')"
        )
    return cell


@dataclass(frozen=True)
class NewCell(Command, wire="new_cell"):
    """Start a new, empty cell named ``name`` on the session's current model."""

    name: str = arg(a.name)

    def execute(self, session: Session) -> str:
        from workcell.cell.workcell import Workcell

        if session.cell is not None:
            raise ProgramError(
                f"cell '{session.cell.name}' is loaded; a new cell starts in a new session "
                "or after 'cell load' of another file"
            )
        session.set_cell(Workcell(self.name, model=session.model))
        return self.name


@dataclass(frozen=True)
class LoadCell(Command, wire="load_cell"):
    """Replace the cell (and its model) by the one saved in ``path``; ends any simulation."""

    path: str = arg(a.file_name)

    def execute(self, session: Session) -> str:
        from workcell.cell.workcell import Workcell

        cell = Workcell.load(session.path(self.path), root=session.root)
        session.set_cell(cell)
        return cell.name


@dataclass(frozen=True)
class SaveCell(Command, wire="save_cell"):
    """Write the cell to ``path`` as versioned JSON (atomic)."""

    path: str = arg(a.file_name)

    def execute(self, session: Session) -> str:
        p = session.path(self.path)
        session.require_cell().save(p)
        return str(p)


@dataclass(frozen=True)
class ExampleCell(Command, wire="example_cell"):
    """Replace the cell by an example cell: the thesis's joints, pick-place, handoff,
    obstacle (a wall between two stages) or conveyor (a belt, a light beam, a UR5e)."""

    name: str = arg(a.choice(*EXAMPLES))

    def execute(self, session: Session) -> str:
        from workcell.cell.workcell import Workcell

        try:
            module = importlib.import_module(EXAMPLES[self.name])
        except ModuleNotFoundError as exc:
            raise ProgramError(f"example cell '{self.name}' is not available yet") from exc
        cell = module.build()
        if not isinstance(cell, Workcell):
            raise ProgramError(f"example '{self.name}': build() did not return a Workcell")
        session.set_cell(cell)
        return cell.name


@dataclass(frozen=True)
class AddRobot(Command, wire="add_robot"):
    """Add a library robot (``workcell.robots.library()``: puma260, ur5e, kuka_kr6_r700, ...)
    at world ``base`` (4x4) with initial joint values ``q`` (rad/m; default: its home pose),
    optionally with the parallel gripper."""

    name: str = arg(a.name)
    robot: str = arg(a.choice(*library()), "puma260")
    gripper: bool = arg(a.boolean, False)
    base: tuple[tuple[float, ...], ...] | None = arg(_opt_matrix, None)
    q: tuple[float, ...] | None = arg(a.optional(a.vector), None)

    def execute(self, session: Session) -> str:
        _editable(session).add_robot(
            self.name,
            self.robot,
            gripper=True if self.gripper else None,
            base=_T(self.base),
            q=None if self.q is None else np.array(self.q),
        )
        return self.name


_URDF_ONLY = ("base_link", "tip_link", "search")
_MJCF_ONLY = ("base_body", "tip_body", "tool_site")


@dataclass(frozen=True)
class ImportRobot(Command, wire="import_robot"):
    """Add a robot read from a robot file: ``format`` urdf or mjcf, ``path`` (inside the
    server's root folder, as are its meshes), the chain's ends (URDF ``base_link`` and
    ``tip_link``; MJCF ``base_body``, ``tip_body``, ``tool_site``; defaults: see
    ``from_urdf``/``from_mjcf``), ``search`` folders for a URDF's ``package://`` meshes; at
    world ``base`` (4x4) with initial joint values ``q`` (rad/m; with ``q_degrees``, deg
    for revolute joints and m for prismatic ones, as the command language writes them),
    optionally with the parallel gripper (a robot file's own gripper is kept anyway)."""

    name: str = arg(a.name)
    format: str = arg(a.choice("urdf", "mjcf"))
    path: str = arg(a.file_name)
    base_link: str | None = arg(a.optional(a.name), None)
    tip_link: str | None = arg(a.optional(a.name), None)
    base_body: str | None = arg(a.optional(a.name), None)
    tip_body: str | None = arg(a.optional(a.name), None)
    tool_site: str | None = arg(a.optional(a.name), None)
    search: tuple[str, ...] = arg(a.list_of(a.file_name), ())
    gripper: bool = arg(a.boolean, False)
    base: tuple[tuple[float, ...], ...] | None = arg(_opt_matrix, None)
    q: tuple[float, ...] | None = arg(a.optional(a.vector), None)
    q_degrees: bool = arg(a.boolean, False)

    def execute(self, session: Session) -> str:
        from workcell.robots import from_mjcf, from_urdf

        path = session.path(self.path)  # a server's root folder first
        search = [session.path(s) for s in self.search]
        cell = _editable(session)
        other = _MJCF_ONLY if self.format == "urdf" else _URDF_ONLY
        given = [k for k in other if getattr(self, k)]
        if given:
            raise ProgramError(
                f"import_robot: {', '.join(given)} do(es) not apply to a {self.format} file; "
                f"give {', '.join(_URDF_ONLY if self.format == 'urdf' else _MJCF_ONLY)}"
            )
        if self.format == "urdf":
            robot = from_urdf(
                path,
                search=search,
                base_link=self.base_link,
                tip_link=self.tip_link,
                root=session.root,
            )
        else:
            robot = from_mjcf(
                path,
                base_body=self.base_body,
                tip_body=self.tip_body,
                tool_site=self.tool_site,
                root=session.root,
            )
        q = None if self.q is None else np.array(self.q)
        if q is not None and self.q_degrees and len(q) == robot.dof:
            q = np.where(robot.revolute, np.radians(q), q)
        cell.add_robot(
            self.name, robot, gripper=True if self.gripper else None, base=_T(self.base), q=q
        )
        return self.name


@dataclass(frozen=True)
class AddStatic(Command, wire="add_static"):
    """Add a fixed part: block or object ``entity`` at world ``pose`` (4x4 rigid, m)."""

    name: str = arg(a.name)
    entity: str | tuple[str, str] = arg(a.ref)
    pose: tuple[tuple[float, ...], ...] | None = arg(_opt_matrix, None)
    colour: tuple[float, ...] | None = arg(a.optional(a.colour), None)

    def execute(self, session: Session) -> str:
        _editable(session).add_static(self.name, self.entity, _T(self.pose), colour=self.colour)
        return self.name


@dataclass(frozen=True)
class AddMovable(Command, wire="add_movable"):
    """Add a movable part of ``density`` (kg/m^3): ``entity`` at world ``pose`` (4x4, m)."""

    name: str = arg(a.name)
    entity: str | tuple[str, str] = arg(a.ref)
    density: float = arg(a.number, doc="kg/m^3")
    pose: tuple[tuple[float, ...], ...] | None = arg(_opt_matrix, None)
    colour: tuple[float, ...] | None = arg(a.optional(a.colour), None)

    def execute(self, session: Session) -> str:
        _editable(session).add_movable(
            self.name, self.entity, _T(self.pose), density=self.density, colour=self.colour
        )
        return self.name


@dataclass(frozen=True)
class AddCamera(Command, wire="add_camera"):
    """Add a camera at ``position`` looking at ``target`` (m), vertical field ``fovy`` (deg)."""

    name: str = arg(a.name)
    position: tuple[float, ...] = arg(a.sized(3))
    target: tuple[float, ...] = arg(a.sized(3))
    fovy: float = arg(a.number, 45.0, "deg")

    def execute(self, session: Session) -> str:
        _editable(session).add_camera(self.name, self.position, self.target, self.fovy)
        return self.name


@dataclass(frozen=True)
class RemoveFromCell(Command, wire="remove_from_cell"):
    """Remove part, robot or camera ``name`` from the cell (the model's entities stay)."""

    name: str = arg(a.name)

    def execute(self, session: Session) -> None:
        _editable(session).remove(self.name)


@dataclass(frozen=True)
class CellData(Command, wire="cell_data"):
    """The cell as its versioned JSON data (what ``cell save`` writes); a robot read from
    a file also carries its kinematics, for a client without the file."""

    def execute(self, session: Session) -> dict:
        return session.require_cell().to_dict(kinematics=True)


@dataclass(frozen=True)
class ShowCell(Command, wire="show_cell"):
    """A readable summary of the cell: robots with joints (deg), parts, cameras."""

    def execute(self, session: Session) -> str:
        cell = session.require_cell()
        lines = [repr(cell)]
        for name, r in cell.robots.items():
            q = session.sim.joints(name) if session.sim is not None else r.q
            deg = ", ".join(f"{v:.4g}" for v in np.degrees(q))
            grip = " with gripper" if r.robot.gripper is not None else ""
            lines.append(f"  robot {name}: {r.builtin or r.robot.name}{grip}, q = ({deg}) deg")
        for kind, parts in (("static", cell.static_parts), ("movable", cell.movable_parts)):
            for name, p in parts.items():
                pos = ", ".join(f"{v:.4g}" for v in p.pose[:3, 3])
                lines.append(f"  {kind} {name}: {p.entity[0]} '{p.entity[1]}' at ({pos}) m")
        for name, c in cell.cameras.items():
            lines.append(f"  camera {name}: at {c.position.tolist()} m")
        if session.sim is not None:
            s = session.sim
            lines.append(f"  simulating: mode {s.mode}, dt {s.dt:g} s, t = {s.sim_time:.4f} s")
        return "\n".join(lines)
