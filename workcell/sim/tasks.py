"""Pick and place as short command sequences (a step towards the thesis's task-level
programming, §6): approach along the tool's axis, grasp or release, retreat.

The approach pose backs off ``approach`` (m) along the tool's -z axis from the grasp
pose (for a top grasp, straight up); the robot reaches it with ``move_end_effector``
(joint space), then goes to the grasp pose and back along straight lines, so the
fingers never sweep through what they are about to hold or what lies under it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from numpy.typing import ArrayLike

from workcell.spatial import as_transform, translation

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["approach_pose", "pick", "place"]


def approach_pose(T: ArrayLike, approach: float) -> ArrayLike:
    """``T`` (4x4 world tool pose) backed off ``approach`` (m) along its own -z axis."""
    return as_transform(T, rigid=True) @ translation(0.0, 0.0, -approach)


def pick(
    sim: Simulator,
    robot: str,
    T: ArrayLike,
    *,
    approach: float = 0.08,
    config: str | None = None,
    **grasp: float,
) -> str:
    """Approach, reach ``T`` along a line, close the gripper (``grasp``: its tests'
    options), retreat; returns the part grasped."""
    above = approach_pose(T, approach)
    sim.move_end_effector(robot, above, config=config)
    sim.move_straight_line(robot, T)
    part = sim.close_gripper(robot, **grasp)
    sim.move_straight_line(robot, above)
    return part


def place(
    sim: Simulator,
    robot: str,
    T: ArrayLike,
    *,
    approach: float = 0.08,
    config: str | None = None,
) -> str | None:
    """Approach, reach ``T`` along a line, open the gripper, retreat; returns the part
    released (None if the gripper was empty)."""
    above = approach_pose(T, approach)
    sim.move_end_effector(robot, above, config=config)
    sim.move_straight_line(robot, T)
    part = sim.open_gripper(robot)
    sim.move_straight_line(robot, above)
    return part
