"""Programs that run together: one program per robot plus controller programs, on one
simulated clock, each blocking only itself (:mod:`workcell.logic.scheduler`; the
programs and what they see of the simulator: :mod:`workcell.logic.programs`).
``Simulator.run_programs`` is the way in.
"""

from workcell.logic.programs import Program, ProgramSim
from workcell.logic.scheduler import ProgramBlock, Run, run_programs

__all__ = ["Program", "ProgramBlock", "ProgramSim", "Run", "run_programs"]
