"""Programs that run together: one program per robot plus controller programs, on one
simulated clock, each blocking only itself (:mod:`workcell.logic.scheduler`; the
programs and what they see of the simulator: :mod:`workcell.logic.programs`).
``Simulator.run_programs`` is the way in: the scheduler drives the simulator it is handed
and sits below it in the import layers; the command language plugs in ``.wcl`` programs
(:mod:`workcell.program.wcl_programs`).
"""

from workcell.logic.programs import Program, ProgramSim
from workcell.logic.scheduler import ProgramBlock, Run, run_programs

__all__ = ["Program", "ProgramBlock", "ProgramSim", "Run", "run_programs"]
