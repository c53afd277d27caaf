"""Robots (thesis ch. 4.2-4.3): serial chains, the library of built-in arms, grippers, forward and inverse kinematics."""

from workcell.robots.arm_geometry import chain_geometry
from workcell.robots.chain import DH, Joint
from workcell.robots.gripper import Gripper, GripperPart, attach_gripper, parallel_gripper
from workcell.robots.library import get, library
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
    "chain_geometry",
    "get",
    "library",
    "parallel_gripper",
    "puma260",
    "puma560",
]
