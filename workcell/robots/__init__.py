"""Robots (thesis ch. 4.2-4.3): DH chains, the built-in Pumas, forward and inverse kinematics."""

from workcell.robots.puma import puma260, puma560
from workcell.robots.robot import IKSolution, Joint, LinkGeometry, Robot

__all__ = ["IKSolution", "Joint", "LinkGeometry", "Robot", "puma260", "puma560"]
