"""Robots (thesis ch. 4.2-4.3): DH chains, the built-in Pumas, grippers, forward and inverse kinematics."""

from workcell.robots.chain import DH, Joint
from workcell.robots.gripper import Gripper, GripperPart, attach_gripper, parallel_gripper
from workcell.robots.puma import puma260, puma560
from workcell.robots.robot import IKSolution, LinkGeometry, Robot

__all__ = [
    "DH",
    "Gripper",
    "GripperPart",
    "IKSolution",
    "Joint",
    "LinkGeometry",
    "Robot",
    "attach_gripper",
    "parallel_gripper",
    "puma260",
    "puma560",
]
