"""Programs (thesis §2.2, §4.6): one command vocabulary and its front ends.

- :mod:`workcell.program.base`, :mod:`~workcell.program.commands`,
  :mod:`~workcell.program.solidcommands`, :mod:`~workcell.program.cellcommands`,
  :mod:`~workcell.program.simcommands`: the commands, frozen dataclasses in SI units,
  each run by ``command.execute(session)``; :data:`COMMANDS` maps wire names to them;
- :mod:`~workcell.program.session`: the :class:`Session` they run on (a model, a cell,
  a simulator);
- the command language (:mod:`~workcell.program.language`), its shell and scripts, and
  the remote program interface (:mod:`~workcell.program.server`,
  :mod:`workcell.client`).
"""

from workcell.program import cellcommands, commands, progcommands, simcommands, solidcommands
from workcell.program.base import COMMANDS, Command, from_wire
from workcell.program.session import Session
from workcell.program.targets import Target

__all__ = [
    "COMMANDS",
    "Command",
    "Session",
    "Target",
    "cellcommands",
    "commands",
    "from_wire",
    "progcommands",
    "simcommands",
    "solidcommands",
]
