"""The workcell exception family.

Every user-facing error is a :class:`WorkcellError`; messages say what was wrong and
what is valid (known names, allowed ranges).
"""

from __future__ import annotations

__all__ = [
    "CollisionError",
    "DeadlockError",
    "DegenerateError",
    "GeometryError",
    "GraspError",
    "JointLimitError",
    "KinematicsError",
    "LimitError",
    "ModelError",
    "NativeCrashError",
    "PlanningError",
    "ProgramError",
    "ProtocolError",
    "RecordError",
    "RenderError",
    "SignalTimeout",
    "StudyError",
    "UnreachableError",
    "ViewError",
    "WorkcellError",
]


class WorkcellError(Exception):
    """Base class of every error the workcell package raises on purpose."""


class ModelError(WorkcellError):
    """A datamodel operation was refused (unknown or duplicate name, entity in use, bad file)."""


class GeometryError(WorkcellError):
    """Geometry is invalid (open or self-intersecting contour, singular transform, bad solid)."""


class DegenerateError(GeometryError, ModelError):
    """A solid or shape too small or too thin to have a volume (a side under
    :data:`workcell.checks.MIN_LENGTH`): both a GeometryError (a bad solid) and a ModelError
    (a bad robot file's shape)."""


class NativeCrashError(ModelError):
    """A child process doing native geometry work (:mod:`workcell.native`) died: an abort,
    a signal, or out of memory; the message names the work."""


class KinematicsError(WorkcellError):
    """A kinematic computation failed or was given inconsistent input."""


class UnreachableError(KinematicsError):
    """No joint configuration reaches the requested pose."""


class JointLimitError(KinematicsError):
    """A joint value lies outside its limits."""


class GraspError(WorkcellError):
    """A grasp was refused: no movable part passed the grasp tests."""


class CollisionError(WorkcellError):
    """A collision occurred while the program was set to stop on collisions."""


class PlanningError(WorkcellError):
    """No collision-free motion was found: the start or goal is in collision (the pair is
    named), the goal cannot be reached, or the planner's time limit ran out."""


class ProgramError(WorkcellError):
    """A command or program could not be parsed or run."""


class ProtocolError(WorkcellError):
    """A remote-protocol message was malformed or broke the protocol."""


class RenderError(WorkcellError):
    """A picture or video could not be made (no OpenGL backend, bad size, closed renderer)."""


class RecordError(WorkcellError):
    """A recording could not be written or streamed (bad path, viewer unreachable)."""


class StudyError(WorkcellError):
    """A study could not be set up or run (bad parameter, output folder of another study)."""


class LimitError(WorkcellError):
    """Work over a limit of :mod:`workcell.limits` was refused before it started (the
    message names the limit and how to raise it)."""


class SignalTimeout(ProgramError):  # noqa: N818 - the contract's name (DESIGN.md)
    """``wait_signal`` ran out of time: the signal did not take the value waited for within
    the timeout (the message names the signal, the value waited for and the value it has)."""


class DeadlockError(ProgramError):
    """Programs run together (``run_programs``) all wait for signals that nothing can
    change any more (the message names each program and what it waits for)."""


class ViewError(WorkcellError):
    """The live view could not start or do what its page asked (a port in use, a file
    name outside the working folder)."""
