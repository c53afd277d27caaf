"""workcell: a robotic workcell simulator on MuJoCo.

Model parts with the solid modeller (:class:`Model`, :mod:`workcell.solids`), transform
them with :mod:`workcell.spatial`, define robots and solve their kinematics with
:mod:`workcell.robots`; every deliberate error is a :class:`WorkcellError`.
"""

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the names below are imported on first use (module __getattr__)
    from workcell import limits, robots, sim, solids, spatial
    from workcell.cell import CompiledCell, Workcell, compile_cell, export_cell
    from workcell.errors import (
        CollisionError,
        DeadlockError,
        GeometryError,
        GraspError,
        JointLimitError,
        KinematicsError,
        LimitError,
        ModelError,
        PlanningError,
        ProgramError,
        ProtocolError,
        RecordError,
        RenderError,
        SignalTimeout,
        StudyError,
        UnreachableError,
        WorkcellError,
    )
    from workcell.modeller.meshprops import MassProperties, ValidityReport
    from workcell.modeller.model import EntityInfo, Model, Relation
    from workcell.modeller.surface import Surface
    from workcell.modeller.world import WorldPart
    from workcell.sim import Simulator, Timeline

# where each public name lives: importing ``workcell`` itself stays light (the command
# line starts fast and its Ctrl-C handling covers the heavy imports: MuJoCo, trimesh...)
_SUBMODULES = ("limits", "robots", "sim", "solids", "spatial")
_ERRORS = (
    "CollisionError", "GeometryError", "GraspError", "JointLimitError", "KinematicsError",
    "LimitError", "ModelError", "PlanningError", "ProgramError", "ProtocolError",
    "RecordError", "RenderError", "StudyError", "UnreachableError", "WorkcellError",
    "DeadlockError", "SignalTimeout",
)  # fmt: skip
_HOMES = {
    **dict.fromkeys(_ERRORS, "workcell.errors"),
    **dict.fromkeys(("CompiledCell", "Workcell", "compile_cell", "export_cell"), "workcell.cell"),
    **dict.fromkeys(("MassProperties", "ValidityReport"), "workcell.modeller.meshprops"),
    **dict.fromkeys(("EntityInfo", "Model", "Relation"), "workcell.modeller.model"),
    "Surface": "workcell.modeller.surface",
    "WorldPart": "workcell.modeller.world",
    **dict.fromkeys(("Simulator", "Timeline"), "workcell.sim"),
}


def __getattr__(name: str) -> object:
    import importlib

    if name in _SUBMODULES:
        value: object = importlib.import_module(f"workcell.{name}")
    elif name in _HOMES:
        value = getattr(importlib.import_module(_HOMES[name]), name)
    else:
        raise AttributeError(f"module 'workcell' has no attribute {name!r}")
    globals()[name] = value  # once: later look-ups do not come here
    return value


def __dir__() -> list[str]:
    return sorted(__all__)


__version__ = "0.1.0"

__all__ = [
    "CollisionError",
    "CompiledCell",
    "DeadlockError",
    "EntityInfo",
    "GeometryError",
    "GraspError",
    "JointLimitError",
    "KinematicsError",
    "LimitError",
    "MassProperties",
    "Model",
    "ModelError",
    "PlanningError",
    "ProgramError",
    "ProtocolError",
    "RecordError",
    "Relation",
    "RenderError",
    "SignalTimeout",
    "Simulator",
    "StudyError",
    "Surface",
    "Timeline",
    "UnreachableError",
    "ValidityReport",
    "Workcell",
    "WorkcellError",
    "WorldPart",
    "__version__",
    "compile_cell",
    "export_cell",
    "limits",
    "robots",
    "sim",
    "solids",
    "spatial",
]
