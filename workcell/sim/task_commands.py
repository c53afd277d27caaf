"""Task-level commands (the thesis's future work, §6): pick, place and hand over a part by name.

:class:`TaskCommands` is a mixin of :class:`~workcell.sim.simulator.Simulator`; each command
chooses its poses and IK configurations itself, then runs the same sequence a
hand-written program would (:mod:`workcell.sim.tasks`): a collision-free planned move
(:mod:`workcell.sim.planned`) to an approach pose ``approach`` (m) back along the tool's
axis, a straight line in, the gripper, a straight line out. Every choice is checked
against the cell with the planning clearance before anything moves; a command that fails
changes nothing (it is one transaction).

- ``pick(robot, part)``: the part's grasp poses (:func:`~workcell.plan.grasps.grasp_poses`,
  from above first), each IK solution within the limits (nearest to the current joints
  first), kept when the grasp pose, the approach pose and the straight line between them
  are collision-free (the open fingers may pass close to the part they straddle) and a
  path to the approach pose is found.
- ``place(robot, part, on=support, position=None)``: the part, turned only about the
  vertical from how it is held (tool pointing down), is lowered over ``position`` (x, y
  in m, world; default: the centroid of the support's top face) until it touches what is
  below it (:meth:`~workcell.sim.resting.RestingCommands._resting_pose`): that must be
  ``on``. The robot brings it there (planned move, straight line down), releases it
  (``settle``: it rests exactly) and retreats.
- ``handover(giver, receiver, part)``: a meeting pose in both workspaces (points between
  the two bases, the part held as the giver holds it, tool turned about the vertical)
  where the giver can hold the part and the receiver can grasp it (its grasp poses at
  that part pose) without the two robots coming closer than the clearance; the giver
  brings the part (planned), the receiver comes in (planned, then a straight line),
  grasps, the giver lets go and both back off along their tool axes.

Errors name the part and say why: GraspError (no grasp fits the gripper, not held),
UnreachableError (no grasp or placing pose within reach), PlanningError (every reachable
one collides, or no path found), ProgramError (unknown names, not a support).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from numpy.typing import ArrayLike, NDArray

from workcell.errors import GraspError, ProgramError, UnreachableError
from workcell.plan.choices import Failures, Reach, turns
from workcell.plan.scene import PlanningScene
from workcell.plan.support import top_face
from workcell.sim.cartesian import pose_solutions
from workcell.sim.choosing import ChoiceHelpers
from workcell.sim.tasks import approach_pose
from workcell.spatial import invert

__all__ = ["TaskCommands"]

Array = NDArray[np.float64]
MEETING_FRACTIONS = (0.5, 0.4, 0.6, 0.3, 0.7)  # along the segment between the two bases
MEETING_HEIGHTS = (0.2, 0.25, 0.15, 0.3, 0.1)  # m above the higher base
MEETING_SIDES = (0.0, 0.1, -0.1)  # m across the segment between the bases


class TaskCommands(ChoiceHelpers):
    """``pick``, ``place`` and ``handover`` (a mixin of Simulator; see the module doc)."""

    # ------------------------------------------------------------------ commands
    def pick(self, robot: str, part: str, *, approach: float = 0.08) -> str:
        """Grasp ``part`` with ``robot``: choose a grasp and configuration, move there
        collision-free, grasp, retreat ``approach`` (m) along the tool axis. Returns the
        part's name."""
        name = self._task_robot(robot, "pick", approach)
        self._part_known(part, "pick")
        if name in self._holds:
            raise GraspError(f"pick '{name}': already holds '{self._holds[name].part}'")
        if self._holders[part]:
            raise GraspError(
                f"pick '{name}': '{part}' is held by '{self._holders[part][0]}'; use handover"
            )
        placement = self.cell.robots[name]
        grasps = self._grasps(name, part, self.part_pose(part), "pick")
        grasp_scene = self._planning_scene([name], near=True, grips=[(name, part)])
        free_scene = self._planning_scene([name])
        fails = Failures()
        q0 = self.joints(name)
        options = self._reachable(placement, [g.tool for g in grasps], q0, approach, fails)
        for reach, planned in self._first_paths(
            name, options, grasp_scene, free_scene, fails, "pick", part, approach
        ):
            with self._transaction():
                self._run_waypoints(name, planned.waypoints, "pick", planned)
                self.move_straight_line(name, reach.tool)
                got = self.close_gripper(name, self._grip_distance(part, reach.tool))
                if got != part:
                    raise GraspError(f"pick '{name}': grasped '{got}' instead of '{part}'")
                self.move_straight_line(name, reach.above)
            return part
        raise self._no_way(fails, f"pick '{name}'", part, len(grasps), "grasp")

    def place(
        self,
        robot: str,
        part: str,
        *,
        on: str,
        position: ArrayLike | None = None,
        approach: float = 0.08,
    ) -> None:
        """Put ``part``, held by ``robot``, down on ``on`` (a static or movable part) with its
        centroid over ``position`` (x, y, m; default: the centroid of the support's top
        face): it rests there (its lowest point on what is below it, which must be
        ``on``), released, and the robot retreats ``approach`` (m)."""
        name = self._task_robot(robot, "place", approach)
        self._part_known(part, "place")
        hold = self._holds.get(name)
        if hold is None or hold.part != part:
            held = f"holds '{hold.part}'" if hold else "holds nothing"
            raise GraspError(f"place '{name}': it does not hold '{part}' (it {held})")
        xy = self._place_xy(name, part, on, position)
        placement = self.cell.robots[name]
        T_tool = self.tool_pose(name)
        rel = invert(T_tool) @ self.part_pose(part)  # the part in the tool frame
        top = max(float(p.bounds[1, 2]) for p in self._world_meshes())
        fails = Failures()
        tools, after = [], []
        travel = float(placement.robot.gripper.finger_travel)
        for R in turns(T_tool[:3, :3]):
            P, landed = self._resting_pose(part, R @ rel[:3, :3], xy, top + 0.01)
            if landed.support != on:
                where = landed.support or "nothing"
                fails.other = f"lowered over ({xy[0]:.4g}, {xy[1]:.4g}) m it would rest on {where}"
                continue
            tools.append(P @ invert(rel))
            after.append(
                self._planning_scene(
                    [name],
                    near=True,
                    carry=False,
                    fingers={name: travel},
                    grips=[(name, part)],
                    touching=[(part, on)],
                    parts={part: P},
                )
            )
        if not tools:
            raise ProgramError(f"place '{name}': '{part}' cannot be put on '{on}': {fails.other}")
        scene = self._planning_scene([name], near=True, touching=[(part, on)])
        free_scene = self._planning_scene([name])
        options = self._reachable(placement, tools, self.joints(name), approach, fails)
        for reach, planned in self._first_paths(
            name, options, scene, free_scene, fails, "place", part, approach, after
        ):
            with self._transaction():
                self._run_waypoints(name, planned.waypoints, "place", planned)
                self.move_straight_line(name, reach.tool)
                self.open_gripper(name, settle=True)
                self.move_straight_line(name, reach.above)
            return
        raise self._no_way(fails, f"place '{name}'", part, len(tools), "placing pose")

    def handover(self, giver: str, receiver: str, part: str, *, approach: float = 0.08) -> None:
        """Hand ``part`` from ``giver`` (holding it) to ``receiver`` at a meeting pose found
        in both workspaces; both back off ``approach`` (m) afterwards (module doc)."""
        g = self._task_robot(giver, "handover", approach)
        r = self._task_robot(receiver, "handover", approach)
        self._part_known(part, "handover")
        if g == r:
            raise ProgramError(f"handover: giver and receiver are both '{g}'")
        hold = self._holds.get(g)
        if hold is None or hold.part != part:
            raise GraspError(f"handover '{g}': it does not hold '{part}'")
        if r in self._holds:
            raise GraspError(f"handover '{r}': already holds '{self._holds[r].part}'")
        meet = self._meeting(g, r, part, approach)
        qg, reach = meet
        with self._transaction():
            planned = self._plan_joint_path(g, [qg], "handover")
            self._run_waypoints(g, planned.waypoints, "handover", planned)
            planned = self._plan_joint_path(r, [reach.q_above], "handover")
            self._run_waypoints(r, planned.waypoints, "handover", planned)
            self.move_straight_line(r, reach.tool)
            if self.close_gripper(r, self._grip_distance(part, reach.tool)) != part:
                raise GraspError(f"handover '{r}': did not grasp '{part}'")
            self.open_gripper(g)
            self.move_straight_line(g, approach_pose(self.tool_pose(g), approach))
            self.move_straight_line(r, reach.above)

    # ------------------------------------------------------------------ place
    def _world_meshes(self) -> Iterator:
        for p in self.cell.static_parts.values():
            yield self.cell.model.world_mesh(p.entity).copy().apply_transform(p.pose)
        for p in self.cell.movable_parts.values():
            yield (
                self.cell.model.world_mesh(p.entity).copy().apply_transform(self.part_pose(p.name))
            )

    def _place_xy(self, name: str, part: str, on: object, position: ArrayLike | None) -> Array:
        cell = self.cell
        if (
            not isinstance(on, str)
            or on == part
            or (on not in cell.static_parts and on not in cell.movable_parts)
        ):
            known = [n for n in (*cell.static_parts, *cell.movable_parts) if n != part]
            raise ProgramError(
                f"place '{name}': no support {on!r}; static and movable parts: {', '.join(known)}"
            )
        if self._holders.get(on):
            raise ProgramError(f"place '{name}': '{on}' is held by '{self._holders[on][0]}'")
        if position is None:
            entity = cell.static_parts[on] if on in cell.static_parts else cell.movable_parts[on]
            pose = entity.pose if on in cell.static_parts else self.part_pose(on)
            mesh = cell.model.world_mesh(entity.entity).copy().apply_transform(pose)
            return top_face(mesh)[0][:2]
        try:
            p = np.array(position, dtype=np.float64).ravel()
        except (TypeError, ValueError):
            p = np.empty(0)
        if p.shape not in ((2,), (3,)) or not np.all(np.isfinite(p)):
            raise ProgramError(
                f"place '{name}': position must be x y (m, world; a z is ignored), got {position!r}"
            )
        return p[:2]

    # ------------------------------------------------------------------ handover
    def _meeting(self, g: str, r: str, part: str, approach: float) -> tuple[Array, Reach]:
        """The giver's joints and the receiver's reach at the first meeting pose that works."""
        pg, pr = (self.cell.robots[x].world_base[:3, 3] for x in (g, r))
        across = np.cross([0.0, 0.0, 1.0], pr - pg)
        across = across / max(float(np.linalg.norm(across)), 1e-12)
        height = max(float(pg[2]), float(pr[2]))
        T_now = self.tool_pose(g)
        rel = invert(T_now) @ self.part_pose(part)
        c_tool = rel[:3, :3] @ self._centroids[part] + rel[:3, 3]  # centroid, tool frame
        both = self._planning_scene([g, r], near=True, grips=[(r, part)])
        giver_alone = self._planning_scene([g])
        qr_now = self.joints(r)
        fails = Failures()
        n = 0
        for f in MEETING_FRACTIONS:
            for dz in MEETING_HEIGHTS:
                for side in MEETING_SIDES:
                    p = pg + f * (pr - pg) + side * across
                    p[2] = height + dz
                    for R in turns(T_now[:3, :3]):
                        n += 1
                        T = np.eye(4)
                        T[:3, :3] = R
                        T[:3, 3] = p - R @ c_tool
                        found = self._meet_at(
                            g, r, part, T, rel, approach, both, giver_alone, qr_now, fails
                        )
                        if found is not None:
                            return found
        raise self._no_way(fails, f"handover '{g}' to '{r}'", part, n, "meeting pose")

    def _meet_at(
        self,
        g: str,
        r: str,
        part: str,
        T: Array,
        rel: Array,
        approach: float,
        both: PlanningScene,
        giver_alone: PlanningScene,
        qr_now: Array,
        fails: Failures,
    ) -> tuple[Array, Reach] | None:
        try:
            qgs = pose_solutions(self.cell.robots[g], T, self.joints(g))
        except UnreachableError as exc:
            fails.unreachable += 1
            fails.reason = fails.reason or f"the giver: {exc}"
            return None
        for qg in qgs:
            v = giver_alone.violation({g: qg})
            if v is not None:
                fails.collide(v)
                continue
            P = T @ rel
            grasps = self._grasps(r, part, P, "handover")
            options = self._reachable(
                self.cell.robots[r], [x.tool for x in grasps], qr_now, approach, fails
            )
            giver_line = self._line(self.cell.robots[g], qg, T, approach)
            if giver_line is None:
                fails.unreachable += 1
                continue
            for _, _, Tr, qr in options:
                reach = self._checked_pair(g, qg, r, qr, Tr, approach, both, fails)
                if reach is None:
                    continue
                # once the giver lets go: its fingers open, then it backs off
                opened = self._planning_scene(
                    [g],
                    near=True,
                    carry=False,
                    fingers={g: float(self.cell.robots[g].robot.gripper.finger_travel)},
                    grips=[(g, part), (r, part)],
                    state={r: qr},
                    parts={part: P},
                )
                bad = next((x for x in (qg, *giver_line[0]) if not opened.valid(x, g)), None)
                if bad is not None:
                    fails.collide(opened.violation({g: bad}))
                    continue
                return qg, reach
            return None
        return None

    def _checked_pair(
        self,
        g: str,
        qg: Array,
        r: str,
        qr: Array,
        Tr: Array,
        approach: float,
        both: PlanningScene,
        fails: Failures,
    ) -> Reach | None:
        v = both.violation({g: qg, r: qr})
        if v is not None:
            fails.collide(v)
            return None
        line = self._line(self.cell.robots[r], qr, Tr, approach)
        if line is None:
            fails.unreachable += 1
            return None
        Q, above = line
        for qs in Q:
            if not both.valid_configs({g: qg, r: qs}):
                fails.collide(both.violation({g: qg, r: qs}))
                return None
        return Reach(Tr, qr, above, Q[-1])
