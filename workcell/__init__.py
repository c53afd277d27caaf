"""workcell: a robotic workcell simulator on MuJoCo.

Model parts with the solid modeller (:class:`Model`, :mod:`workcell.solids`), transform
them with :mod:`workcell.spatial`, define robots and solve their kinematics with
:mod:`workcell.robots`; every deliberate error is a :class:`WorkcellError`.
"""

from workcell import limits, robots, sim, solids, spatial
from workcell.cell import CompiledCell, Workcell, compile_cell, export_cell
from workcell.errors import (
    CollisionError,
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
    StudyError,
    UnreachableError,
    WorkcellError,
)
from workcell.modeller.meshprops import MassProperties, ValidityReport
from workcell.modeller.model import EntityInfo, Model, Relation
from workcell.modeller.surface import Surface
from workcell.modeller.world import WorldPart
from workcell.sim import Simulator, Timeline

__version__ = "0.1.0"

__all__ = [
    "CollisionError",
    "CompiledCell",
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
