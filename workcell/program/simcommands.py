"""The command vocabulary, simulation part (thesis §4.4-4.6): every simulation command,
in one namespace.

``simulate`` starts a :class:`~workcell.sim.Simulator` on the session's cell (see
:mod:`workcell.program.cellcommands`). Simulation commands carry the
Simulator's method names and SI arguments (rad, m, s; a pose is a 4x4 world pose of the
robot's tool, or a :class:`~workcell.program.targets.Target`) and call that method; the
Simulator validates before it changes anything, so a failed command changes nothing.
Commands for Simulator methods that this build of the simulator does not have yet raise
ProgramError saying so.

They are defined by idea: run control in :mod:`~workcell.program.runcommands`, moves and
motion settings in :mod:`~workcell.program.motioncommands`, grippers and task-level
commands in :mod:`~workcell.program.taskcommands`, read-backs in
:mod:`~workcell.program.readcommands`, devices, signals, programs that run together and
results in :mod:`~workcell.program.logiccommands`; this module gathers them.
"""

from __future__ import annotations

from workcell.program.logiccommands import (
    AddConveyor,
    AddSensor,
    AddSignal,
    AddSink,
    AddSource,
    Distance,
    Gantt,
    Program,
    Programs,
    RunPrograms,
    SetSignal,
    Signal,
    Signals,
    Throughput,
    WaitSignal,
)
from workcell.program.motioncommands import (
    Jog,
    MoveCircular,
    MoveEndEffector,
    MoveJointsAbsolute,
    MoveJointsRelative,
    MoveLinear,
    MoveStraightLine,
    SetOverride,
    SetProfile,
    SetSpeed,
)
from workcell.program.readcommands import (
    Clearance,
    CycleTime,
    Events,
    Frames,
    GripperPose,
    Held,
    Joints,
    PartPose,
    PartPositions,
    Robots,
    SimTime,
    Speed,
    Summary,
    ToolPose,
    Trajectory,
    WallTime,
)
from workcell.program.runcommands import (
    MODES,
    ConcurrentlyBegin,
    ConcurrentlyEnd,
    Play,
    SetMode,
    Simulate,
    StopSimulation,
    Wait,
)
from workcell.program.taskcommands import (
    CloseGripper,
    Handover,
    OpenGripper,
    Pick,
    Place,
    SetPlanning,
)

__all__ = [
    "MODES",
    "AddConveyor",
    "AddSensor",
    "AddSignal",
    "AddSink",
    "AddSource",
    "Clearance",
    "CloseGripper",
    "ConcurrentlyBegin",
    "ConcurrentlyEnd",
    "CycleTime",
    "Distance",
    "Events",
    "Frames",
    "Gantt",
    "GripperPose",
    "Handover",
    "Held",
    "Jog",
    "Joints",
    "MoveCircular",
    "MoveEndEffector",
    "MoveJointsAbsolute",
    "MoveJointsRelative",
    "MoveLinear",
    "MoveStraightLine",
    "OpenGripper",
    "PartPose",
    "PartPositions",
    "Pick",
    "Place",
    "Play",
    "Program",
    "Programs",
    "Robots",
    "RunPrograms",
    "SetMode",
    "SetOverride",
    "SetPlanning",
    "SetProfile",
    "SetSignal",
    "SetSpeed",
    "Signal",
    "Signals",
    "SimTime",
    "Simulate",
    "Speed",
    "StopSimulation",
    "Summary",
    "Throughput",
    "ToolPose",
    "Trajectory",
    "Wait",
    "WaitSignal",
    "WallTime",
]
