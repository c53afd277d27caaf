"""The command base class and the registry of every command by its wire name.

A command is a frozen dataclass whose fields are declared with
:func:`workcell.program.args.arg` (a converter per field). Subclasses name themselves
with the class keyword ``wire=``: ``class Wait(Command, wire="wait")``. The registry
:data:`COMMANDS` maps wire names to classes; every front end (the command language, the
shell, the server) builds commands from it and runs them with ``command.execute(session)``.
"""

from __future__ import annotations

import abc
import dataclasses
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

from workcell.errors import ProgramError

if TYPE_CHECKING:
    from workcell.program.session import Session

__all__ = ["COMMANDS", "Command", "command_class", "from_wire"]

COMMANDS: dict[str, type[Command]] = {}


class Command(abc.ABC):
    """Base of every command: ``execute(session)`` runs it; ``wire`` is its protocol name."""

    wire: ClassVar[str] = ""

    def __init_subclass__(cls, wire: str = "", **kw: Any) -> None:
        super().__init_subclass__(**kw)
        if wire:
            if wire in COMMANDS:
                raise TypeError(f"two commands named {wire!r}")
            cls.wire = wire
            COMMANDS[wire] = cls

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            conv = f.metadata.get("convert")
            if conv is not None:
                value = getattr(self, f.name)
                object.__setattr__(self, f.name, conv(value, f"{self.wire}: {f.name}"))

    @abc.abstractmethod
    def execute(self, session: Session) -> Any:
        """Run the command on ``session``; return its result (plain values, arrays)."""

    def to_args(self) -> dict[str, Any]:
        """The command's arguments as JSON-able plain values (tuples as lists)."""
        return {f.name: _plain(getattr(self, f.name)) for f in dataclasses.fields(self)}  # type: ignore[arg-type]

    @classmethod
    def from_args(cls, args: Mapping[str, Any] | list[Any] | tuple[Any, ...] | None) -> Command:
        """Build the command from keyword (mapping) or positional (list) arguments.

        Raises ProgramError naming a missing, unknown or badly typed argument and listing
        the valid ones.
        """
        fields = dataclasses.fields(cls)  # type: ignore[arg-type]
        names = [f.name for f in fields]
        signature = f"{cls.wire}({', '.join(names)})"
        if args is None:
            args = {}
        if isinstance(args, (list, tuple)):
            if len(args) > len(fields):
                raise ProgramError(
                    f"{cls.wire} takes at most {len(fields)} arguments, got {len(args)}: "
                    f"{signature}"
                )
            args = dict(zip(names, args, strict=False))
        if not isinstance(args, Mapping):
            raise ProgramError(
                f"{cls.wire}: args must be an object or a list, got {type(args).__name__}"
            )
        unknown = [k for k in args if k not in names]
        if unknown:
            raise ProgramError(
                f"{cls.wire}: unknown argument(s) {', '.join(map(str, unknown))}; "
                f"valid: {', '.join(names) or 'none'}"
            )
        required = [
            f.name
            for f in fields
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        ]
        missing = [n for n in required if n not in args]
        if missing:
            raise ProgramError(f"{cls.wire}: missing argument(s) {', '.join(missing)}: {signature}")
        return cls(**args)


def _plain(v: Any) -> Any:
    if isinstance(v, tuple):
        return [_plain(x) for x in v]
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        return {f.name: _plain(getattr(v, f.name)) for f in dataclasses.fields(v)}
    return v


def command_class(wire: str) -> type[Command]:
    """The command class named ``wire``; ProgramError listing the names when unknown."""
    cls = COMMANDS.get(wire) if isinstance(wire, str) else None
    if cls is None:
        import difflib

        close = difflib.get_close_matches(str(wire), list(COMMANDS), n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise ProgramError(
            f"unknown command {wire!r}{hint} (commands: {', '.join(sorted(COMMANDS))})"
        )
    return cls


def from_wire(wire: str, args: Mapping[str, Any] | list[Any] | None = None) -> Command:
    """Build the command named ``wire`` from its arguments (see :meth:`Command.from_args`)."""
    return command_class(wire).from_args(args)
