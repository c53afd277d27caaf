"""Gripper commands of the simulator (thesis §4.5): grasp tests, weld carry, handoff.

:class:`GripperCommands` is a mixin of :class:`~workcell.sim.simulator.Simulator` (it uses
the simulator's model, data, timeline and transaction). A grasp is recorded as a
:class:`Hold`.

``close_gripper`` runs the thesis's three tests (:mod:`workcell.sim.grasp`) on every
movable part; the first that passes is grasped: the weld equality of that gripper and
part is activated with the captured relative pose (``eq_data``), the fingers close on the
part, and from then on the part's free joint is written every frame as gripper pose x
relative pose (exact carry; the timeline stores it). ``open_gripper`` releases it where
it is. A part may be held by two robots at once (a handoff): the first holder carries it
and may not move while the second also holds it; when the first opens, the second
carries it.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import NDArray

from workcell.checks import is_finite_number, quote_angle, quote_length
from workcell.errors import GraspError, ProgramError
from workcell.sim.cycle import command_record
from workcell.sim.grasp import PartBox, describe_failure, grasp_candidates
from workcell.spatial import invert, pos_quat_from_pose

if TYPE_CHECKING:
    pass

__all__ = ["Carried", "GraspRecord", "GripperCommands", "Hold"]

Array = NDArray[np.float64]
Carried = tuple[int, int, Array, Array]  # gripper body, free-joint qpos address, pos, wxyz


class Hold(NamedTuple):
    """A grasp: ``part`` held by a robot's gripper at relative pose ``relative`` (4x4, the
    part's body frame in the gripper body's frame), as position (3,) and wxyz quaternion."""

    part: str
    relative: Array
    pos: Array
    quat: Array


class GraspRecord(NamedTuple):
    """A grasp or release on the timeline: at frame ``frame`` (the frame where the fingers
    have closed or opened; simulated time ``t``, s) ``robot`` did ``kind`` ("grasp" or
    "release") on ``part``; ``pos`` (3,) and ``quat`` (wxyz) the weld's relative pose
    (the part's body frame in the gripper body's frame)."""

    frame: int
    t: float
    robot: str
    part: str
    kind: str
    pos: Array
    quat: Array


class GripperCommands:
    """Gripper commands and read-back (a mixin of Simulator)."""

    def held(self, robot: str) -> str | None:
        """The part the robot's gripper holds, or None."""
        h = self._holds.get(self._robot(robot))
        return None if h is None else h.part

    def part_pose(self, part: str) -> Array:
        """World pose (4x4) of a movable part's body frame."""
        if part not in self._part_body:
            known = ", ".join(self._part_body) or "none"
            raise ProgramError(f"no movable part {part!r}; movable parts: {known}")
        b = self._part_body[part]
        T = np.eye(4)
        T[:3, :3] = self.data.xmat[b].reshape(3, 3)
        T[:3, 3] = self.data.xpos[b]
        return T

    def gripper_pose(self, robot: str) -> Array:
        """World pose (4x4) of the robot's gripper body (the weld's body1)."""
        b = self._gripper_id(self._robot(robot), "gripper_pose")
        T = np.eye(4)
        T[:3, :3] = self.data.xmat[b].reshape(3, 3)
        T[:3, 3] = self.data.xpos[b]
        return T

    def close_gripper(
        self, robot: str, max_distance: float = 0.02, max_angle: float = math.radians(10)
    ) -> str:
        """Close the robot's gripper; grasp the first part passing the thesis's tests.

        ``max_distance`` (m) from the tool-centre point to the part's centroid,
        ``max_angle`` (rad) between the tool's z axis and a box axis; the part's width
        across the grasp must fit the opening. Returns the part's name; raises
        GraspError naming the nearest candidate and the test it failed.
        """
        name = self._robot(robot)
        self._not_in_block("close_gripper")
        self._gripper_id(name, "close_gripper")
        for what, v, quote in (
            ("max_distance", max_distance, quote_length),
            ("max_angle", max_angle, quote_angle),
        ):
            if not (is_finite_number(v) and v >= 0):
                raise ProgramError(f"close_gripper '{name}': {what} must be >= 0, got {quote(v)}")
        if name in self._holds:
            raise GraspError(f"close_gripper '{name}': already holds '{self._holds[name].part}'")
        gripper = self.cell.robots[name].robot.gripper
        opening = float(gripper.max_opening)
        boxes = []
        for p in self._part_body:
            if name in self._holders[p]:
                continue
            P = self.part_pose(p)
            lo, hi = self._boxes[p]
            boxes.append(
                PartBox(p, P[:3, :3], (hi - lo) / 2.0, P[:3, :3] @ self._centroids[p] + P[:3, 3])
            )
        tests = dict(opening=opening, max_distance=float(max_distance), max_angle=float(max_angle))
        cands = grasp_candidates(self.tool_pose(name), boxes, **tests)
        chosen = next((c for c in cands if c.failed is None), None)
        if chosen is None:
            raise GraspError(describe_failure(name, cands, **tests))
        part = chosen.part
        G = self.gripper_pose(name)
        rel = invert(G) @ self.part_pose(part)
        pos, quat = pos_quat_from_pose(rel)
        with self._transaction():
            e = self._weld[(name, part)]
            self.model.eq_data[e, 3:6] = pos
            self.model.eq_data[e, 6:10] = quat
            self.data.eq_active[e] = 1
            self._holds[name] = Hold(part, rel, pos, quat)
            self._holders[part].append(name)
            self._update_exclusions()
            # the fingers stop a contact tolerance short of the part: touching, no overlap
            travel = float(self.cell.robots[name].robot.gripper.finger_travel)
            self._set_fingers(name, min(chosen.width / 2.0 + self.contacts.tolerance, travel))
            self.grasps.append(
                GraspRecord(len(self.timeline) - 1, self.sim_time, name, part, "grasp", pos, quat)
            )
            self.timeline.add_event(
                self.sim_time,
                name,
                "grasp",
                f"grasp '{part}': axis {math.degrees(chosen.angle):.3g} deg, width "
                f"{chosen.width * 1e3:.4g} mm, distance {chosen.distance * 1e3:.3g} mm",
                data=command_record(
                    name,
                    "close_gripper",
                    self.sim_time,
                    0.0,
                    program={"kind": "gripper", "closed": True},
                ),
            )
        return part

    def open_gripper(self, robot: str, *, settle: bool = False) -> str | None:
        """Open the robot's gripper; release the part it holds (returned; None if empty).

        A released part stays where it is, unless another robot holds it too (a handoff):
        that robot carries it from now on. Released in mid-air (more than the contact
        tolerance above what is below it), it gets a ``warning`` event; with ``settle`` it
        drops straight onto the highest support below it instead, in one frame
        (:mod:`workcell.sim.resting`).
        """
        name = self._robot(robot)
        self._not_in_block("open_gripper")
        self._gripper_id(name, "open_gripper")
        hold = self._holds.get(name)
        with self._transaction():
            if hold is not None:
                del self._holds[name]
                self._holders[hold.part].remove(name)
                self.data.eq_active[self._weld[(name, hold.part)]] = 0
                self._update_exclusions()
            travel = float(self.cell.robots[name].robot.gripper.finger_travel)
            self._set_fingers(name, travel)
            if hold is not None:
                self.grasps.append(
                    GraspRecord(
                        len(self.timeline) - 1,
                        self.sim_time,
                        name,
                        hold.part,
                        "release",
                        hold.pos,
                        hold.quat,
                    )
                )
            rec = command_record(
                name, "open_gripper", self.sim_time, 0.0,
                program={"kind": "gripper", "closed": False},
            )  # fmt: skip
            if hold is None:
                self.timeline.add_event(
                    self.sim_time, name, "open", "open_gripper: nothing held", data=rec
                )
            else:
                others = self._holders[hold.part]
                to = f", now carried by '{others[0]}'" if others else ""
                where = ", ".join(
                    f"{round(v, 4) + 0.0:.4f}" for v in self.part_positions()[hold.part]
                )
                self.timeline.add_event(
                    self.sim_time,
                    name,
                    "release",
                    f"release '{hold.part}': centroid ({where}) m{to}",
                    data=rec,
                )
                self._after_release(name, hold.part, bool(settle))
        return None if hold is None else hold.part

    def _gripper_id(self, name: str, command: str) -> int:
        if name not in self._gripper:
            raise ProgramError(
                f"{command} '{name}': the robot has no gripper; robots with one: "
                f"{', '.join(self._gripper) or 'none'}"
            )
        return self._gripper[name]

    def _update_exclusions(self) -> None:
        """A held part never collides with the gripper(s) holding it."""
        ex: set[tuple[int, int]] = set()
        for robot, hold in self._holds.items():
            ex |= self.contacts.exclude(self._gripper_tree[robot], {self._part_body[hold.part]})
        self.contacts.excluded = ex

    def _set_fingers(self, name: str, q_each: float) -> None:
        """Put both fingers at ``q_each`` (m from closed): one frame, no simulated time."""
        row = self.data.qpos.copy()
        row[self._fingers[name]] = q_each
        self._emit(np.array([self.sim_time]), row[None, :], [], name)

    def _carried(self, name: str) -> list[tuple[int, int, Array, Array]]:
        """(gripper body, free-joint qpos address, relative pos, quat) of what ``name`` carries."""
        hold = self._holds.get(name)
        if hold is None:
            return []
        others = [r for r in self._holders[hold.part] if r != name]
        if others:
            raise ProgramError(
                f"'{name}' cannot move: '{hold.part}' is also held by '{others[0]}'; "
                f"open one of the two grippers first"
            )
        return [(self._gripper[name], self._free_adr[hold.part], hold.pos, hold.quat)]
