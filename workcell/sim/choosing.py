"""How task-level commands choose: poses checked for reach and collisions, planned paths.

:class:`ChoiceHelpers` is a mixin of :class:`~workcell.sim.simulator.Simulator` used by
:mod:`workcell.sim.task_commands`: for candidate tool poses in order of preference, every IK
solution within the limits (nearest to the current joints first) is kept when the pose,
the straight line back ``approach`` (m) along the tool axis and the approach pose keep
the planning clearances (the near clearance at and along the line, the planner's at the
approach pose; optionally once the gripper has opened), and a collision-free path to the
approach pose is found (a few candidates at most, within one time limit). Why the
others were turned down is counted (:class:`~workcell.plan.choices.Failures`) for the
error message: out of reach (UnreachableError), in collision (PlanningError naming the
nearest pair), no path.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from workcell.errors import GraspError, PlanningError, ProgramError, UnreachableError
from workcell.plan.choices import BACKOFFS, Failures, Reach
from workcell.plan.grasps import GraspPose, grasp_poses, grip_depths
from workcell.plan.motion import PlannedPath, describe
from workcell.plan.scene import PlanningScene
from workcell.sim.cartesian import line_waypoints, pose_solutions
from workcell.sim.tasks import approach_pose

if TYPE_CHECKING:
    from workcell.cell.workcell import RobotPlacement

__all__ = ["ChoiceHelpers"]

Array = NDArray[np.float64]
_LINE_STEP = 0.005  # m, as move_straight_line's default
_MAX_JUMP = math.radians(10)
_PATH_TRIES = 3  # candidates tried with the planner (within one time limit) at most


class ChoiceHelpers:
    """Candidate checks and planned approaches of task-level commands (a mixin of Simulator)."""

    def _task_robot(self, robot: object, command: str, approach: float) -> str:
        name = self._robot(robot)
        self._not_in_block(command)
        self._gripper_id(name, command)
        if not (isinstance(approach, (int, float)) and math.isfinite(approach) and approach > 0):
            raise ProgramError(f"{command} '{name}': approach must be a number of metres > 0")
        return name

    def _part_known(self, part: object, command: str) -> None:
        if not isinstance(part, str) or part not in self._part_body:
            known = ", ".join(self._part_body) or "none"
            raise ProgramError(f"{command}: no movable part {part!r}; movable parts: {known}")

    def _grasps(self, name: str, part: str, pose: Array, command: str) -> list[GraspPose]:
        gripper = self.cell.robots[name].robot.gripper
        opening = float(gripper.max_opening) - 2.0 * self.contacts.tolerance
        lo, hi = self._boxes[part]
        palm, tips = grip_depths(gripper)
        margin = max(self._planning.near_clearance, self.contacts.tolerance)
        out = grasp_poses(
            pose, lo, hi, self._centroids[part], opening=opening, backoffs=BACKOFFS,
            palm=palm, tips=tips, margin=margin,
        )  # fmt: skip
        if not out:
            size = " x ".join(f"{v * 1e3:.4g}" for v in hi - lo)
            raise GraspError(
                f"{command} '{name}': no grasp of '{part}' fits the gripper: its box is "
                f"{size} mm, every width wider than the {opening * 1e3:.4g} mm opening"
            )
        return out

    def _grip_distance(self, part: str, tool: Array) -> float:
        """``close_gripper``'s ``max_distance`` (m) for a grasp at ``tool`` chosen by
        :meth:`_grasps`: its default (20 mm), or more when the grasp backs off further
        from the centroid (a part much taller than the fingers are long)."""
        P = self.part_pose(part)
        c = P[:3, :3] @ self._centroids[part] + P[:3, 3]
        return max(0.02, float(np.linalg.norm(tool[:3, 3] - c)) + 1e-6)

    def _reachable(
        self,
        placement: RobotPlacement,
        tools: Sequence[Array],
        q0: Array,
        approach: float,
        fails: Failures,
    ) -> list[tuple[int, float, Array, Array]]:
        """(preference, joint distance, tool pose, q) of every IK solution of ``tools``
        (in preference order), best first."""
        out = []
        for k, T in enumerate(tools):
            try:
                sols = pose_solutions(placement, T, q0)
            except UnreachableError as exc:
                fails.unreachable += 1
                fails.reason = fails.reason or str(exc)
                continue
            out += [(k, float(np.abs(q - q0).max()), T, q) for q in sols]
        out.sort(key=lambda o: (o[0], o[1]))
        return out

    def _line(
        self, placement: RobotPlacement, q: Array, T: Array, approach: float
    ) -> tuple[Array, Array] | None:
        """The straight line from T (joints q) back ``approach`` along the tool axis:
        (samples (k, dof), the approach pose) or None when it is not possible."""
        above = approach_pose(T, approach)
        try:
            Q, _ = line_waypoints(placement, q, T, above, step=_LINE_STEP, max_jump=_MAX_JUMP)
        except UnreachableError:
            return None
        return Q, above

    def _checked(
        self,
        name: str,
        q: Array,
        T: Array,
        approach: float,
        near: PlanningScene,
        free: PlanningScene,
        fails: Failures,
        after: PlanningScene | None = None,
    ) -> Reach | None:
        """The reach of pose T at q when T, the line out and the approach pose keep the
        clearance (``near``: at and along the line; ``free``: at the approach pose;
        ``after``: at T and along the line once the gripper has opened)."""
        line = self._line(self.cell.robots[name], q, T, approach)
        if line is None:
            fails.unreachable += 1
            fails.reason = fails.reason or "the approach line leaves the reach"
            return None
        Q, above = line
        for sc in (near, after):
            if sc is None:
                continue
            for qs in (q, *Q):
                if not sc.valid(qs, name):
                    fails.collide(sc.violation({name: qs}))
                    return None
        v = free.violation({name: Q[-1]})
        if v is not None:
            fails.collide(v)
            return None
        return Reach(T, q, above, Q[-1])

    def _first_paths(
        self,
        name: str,
        options: list[tuple[int, float, Array, Array]],
        near: PlanningScene,
        free: PlanningScene,
        fails: Failures,
        command: str,
        part: str,
        approach: float,
        after: Sequence[PlanningScene | None] | None = None,
    ) -> Iterator[tuple[Reach, PlannedPath]]:
        """Checked reaches of ``options`` with a planned path to their approach pose, in
        order (at most a few are tried with the planner); ``after``: per tool pose (the
        options' first field), the scene once the gripper has opened there."""
        tried = 0
        deadline = time.perf_counter() + self._planning.time_limit  # one budget for all
        for k, _, T, q in options:
            opened = after[k] if after is not None else None
            reach = self._checked(name, q, T, approach, near, free, fails, opened)
            if reach is None:
                continue
            try:
                left = deadline - time.perf_counter()
                if left <= 0:
                    return
                planned = self._plan_joint_path(
                    name, [reach.q_above], f"{command} '{part}'", time_limit=left
                )
            except PlanningError as exc:
                fails.other = str(exc)
                tried += 1
                if tried >= _PATH_TRIES:
                    return
                continue
            yield reach, planned
            return

    def _no_way(self, fails: Failures, what: str, part: str, n: int, kind: str) -> Exception:
        if fails.other and fails.collisions == 0 and fails.unreachable < n:
            return PlanningError(f"{what}: no collision-free path for '{part}': {fails.other}")
        if fails.collisions:
            why = describe(fails.nearest, self._planning.clearance) if fails.nearest else ""
            extra = f"; {fails.other}" if fails.other else ""
            return PlanningError(
                f"{what}: every reachable {kind} of '{part}' collides ({fails.collisions} "
                f"tried; nearest: {why}){extra}"
            )
        return UnreachableError(
            f"{what}: '{part}' cannot be reached: none of its {n} {kind}s is within reach "
            f"({fails.reason or fails.other or 'outside the joint limits'})"
        )
