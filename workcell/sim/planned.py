"""Planned joint moves of the simulator: ``plan=True`` on the move commands.

:class:`PlanningCommands` is a mixin of :class:`~workcell.sim.simulator.Simulator`; the
planners it calls take plain values (:mod:`workcell.plan`). With ``plan=True``,
``move_joints_absolute`` and ``move_end_effector`` do not move linearly in
joints: a :class:`~workcell.plan.scene.PlanningScene` of the robot (holding what it
holds) in the cell as it is now checks the start (a pair overlapping by more than the
contact tolerance: PlanningError naming it) and the goal (every IK solution of a pose, in
the order ``move_end_effector`` prefers them; all in collision: PlanningError naming the
nearest pair), then :func:`~workcell.plan.rrt.plan_path` finds a collision-free path to
the first goal that has one, every motion checked densely enough that no moving point
travels more than the clearance between two checks. No path within the time limit:
PlanningError. A failure changes nothing.

The path is run segment by segment, each straight joint-space segment as one joint move
of the simulator's own motion profile (``profile``: the thesis's constant speed,
trapezoid, quintic, and whatever profiles the simulator gains), stopping at each
waypoint, so the frames stay on the checked segments. All joints move together in every
mode (joint-by-joint mode would leave the checked segments). Planned moves cannot run
inside ``concurrently()`` (the other robots' motions are not known to the planner).

Without ``plan`` and without ``config``, ``move_end_effector`` takes, among the in-limit
IK solutions (nearest to the current joints first), the first whose joint move (straight
in joint space; in joint-by-joint mode joint 1, then joint 2, ...) keeps the planning
clearance, checked as planned motions are (:meth:`PlanningCommands._default_solution`:
its end and its motion, densely); when none does, the nearest, as before. The move's
event says which configuration and why.

Settings (:class:`~workcell.plan.motion.PlanningOptions`, changed with
``sim.set_planning(...)``): ``clearance`` (m, default 5 mm; never below the contact
tolerance), ``time_limit`` (s per search, default 5) and ``seed`` (default 0): the same
cell, program and seed give the same paths; ``near_clearance`` (m, default 1 mm) for the
close work of task-level commands.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Sequence
from dataclasses import asdict, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from workcell.errors import PlanningError
from workcell.plan.motion import PlannedPath, PlanningOptions, describe
from workcell.plan.rrt import plan_path, segment_failure
from workcell.plan.scene import PlanningScene
from workcell.robots.ik_closed import config_of
from workcell.sim.cycle import command_record

__all__ = ["PlanningCommands"]

Array = NDArray[np.float64]


class PlanningCommands:
    """Planned moves (a mixin of Simulator; see the module doc)."""

    _planning: PlanningOptions = PlanningOptions()

    def set_planning(
        self,
        *,
        clearance: float | None = None,
        time_limit: float | None = None,
        seed: int | None = None,
        near_clearance: float | None = None,
    ) -> dict[str, float]:
        """Change how planned moves search (the values given; see :class:`PlanningOptions`:
        ``clearance`` and ``near_clearance`` in m, ``time_limit`` in s, ``seed``) and return
        the settings now in force."""
        changes = {
            k: v
            for k, v in dict(
                clearance=clearance, time_limit=time_limit, seed=seed, near_clearance=near_clearance
            ).items()
            if v is not None
        }
        self._planning = replace(self._planning, **changes)
        return asdict(self._planning)

    def _planning_scene(
        self, robots: Sequence[str], *, near: bool = False, **options: Any
    ) -> PlanningScene:
        """A planning scene of ``robots`` in the cell as it is now, with the clearance of
        ``planning`` (``near``: its near clearance; never below the contact tolerance);
        ``options``: the other arguments of :class:`~workcell.plan.scene.PlanningScene`."""
        c = self._planning.near_clearance if near else self._planning.clearance
        clearance = max(c, self.contacts.tolerance)
        return PlanningScene(self, robots, clearance=clearance, **options)

    def _plan_joint_path(
        self,
        robot: str,
        goals: Sequence[Array],
        command: str,
        scene: PlanningScene | None = None,
        resolution: float | None = None,
        time_limit: float | None = None,
    ) -> PlannedPath:
        """A collision-free path of ``robot`` from its joints now to the first of ``goals``
        (rad/m, in order of preference) that has one; PlanningError otherwise (module doc).
        Changes nothing. ``resolution``: OMPL's fixed motion resolution instead of the
        scene's (for comparisons; see :func:`~workcell.plan.rrt.plan_path`);
        ``time_limit`` (s): the search budget (default: the planning settings')."""
        name = self._robot(robot)
        sc = scene or self._planning_scene([name])
        if sc.start_collision is not None:
            raise PlanningError(
                f"{command} '{name}': start in collision: {describe(sc.start_collision, sc.clearance)}"
            )
        ok, nearest = [], None
        for q in goals:
            v = sc.violation({name: q})
            if v is None:
                ok.append(np.asarray(q, dtype=np.float64))
            elif nearest is None or v[2] < nearest[2]:
                nearest = v
        if not ok:
            what = "the goal is" if len(goals) == 1 else f"all {len(goals)} IK solutions are"
            raise PlanningError(
                f"{command} '{name}': goal in collision: {what} in collision; "
                f"{describe(nearest, sc.clearance)}"  # type: ignore[arg-type]
            )
        robot_ = self.cell.robots[name].robot
        q0 = self.joints(name)
        radii = sc.radii(name)
        budget = self._planning.time_limit if time_limit is None else time_limit
        t0 = time.perf_counter()
        for q in ok:
            left = budget - (time.perf_counter() - t0)
            if left <= 0:
                break
            path = plan_path(
                sc.valid,
                q0,
                q,
                robot_.lower,
                robot_.upper,
                radii=radii,
                clearance=sc.clearance,
                time_limit=left,
                seed=self._planning.seed,
                resolution=resolution,
            )
            if path is not None:
                return PlannedPath(path, time.perf_counter() - t0, radii)
        raise PlanningError(
            f"{command} '{name}': time limit reached: no collision-free path found in "
            f"{budget:.3g} s (clearance {sc.clearance * 1e3:.3g} mm); "
            "raise the time limit or lower the clearance (set_planning)"
        )

    def _default_solution(self, name: str, goals: Sequence[Array]) -> tuple[int, str]:
        """Which of ``goals`` (IK solutions, rad/m, nearest first) a move with no
        configuration takes, and why, in words (module doc): (index, reason)."""
        robot = self.cell.robots[name].robot
        if robot.ik_family is None or len(goals) < 2:
            return 0, ""
        letters = [config_of(robot, q) for q in goals]
        sc = self._planning_scene([name])
        if sc.start_collision is not None:
            why = describe(sc.start_collision, sc.clearance)
            return 0, f"configuration '{letters[0]}', the nearest (start in collision: {why})"
        first = None
        for i, q in enumerate(goals):
            hit = self._joint_move_hit(sc, name, np.asarray(q, dtype=np.float64))
            if hit is None:
                if i == 0:
                    return 0, f"configuration '{letters[0]}', the nearest (its move is clear)"
                return i, (
                    f"configuration '{letters[i]}', the nearest whose move is clear "
                    f"('{letters[0]}' is nearer: {first})"
                )
            first = first or hit
        return 0, (
            f"configuration '{letters[0]}', the nearest (no solution's move is clear: {first})"
        )

    def _joint_move_hit(self, sc: PlanningScene, name: str, q: Array) -> str | None:
        """Why the joint move of ``name`` from its joints now to ``q``, as the simulator's
        mode runs it, breaks the scene's clearance (a pair and where), or None."""
        q0 = self.joints(name)
        ends = [q0, q]
        if self.mode == "joint-by-joint":  # joint 1 first, then joint 2, ...
            ends = [q0]
            for i in np.flatnonzero(q != q0):
                w = ends[-1].copy()
                w[i] = q[i]
                ends.append(w)
        radii = sc.radii(name)
        total = float(np.abs(q - q0) @ radii)
        done = 0.0
        for a, b in itertools.pairwise(ends):
            f = segment_failure(sc.valid, a, b, radii, sc.clearance)
            if f is not None:
                v = sc.violation({name: a + (b - a) * f})
                at = (done + f * float(np.abs(b - a) @ radii)) / total if total > 0 else 1.0
                return f"{describe(v, sc.clearance)} at {at:.0%} of its move"  # type: ignore[arg-type]
            done += float(np.abs(b - a) @ radii)
        v = sc.violation({name: q})
        return None if v is None else f"{describe(v, sc.clearance)} at its end"

    def _move_planned(self, name: str, goals: Sequence[Array], command: str) -> None:
        """Plan a path to the first reachable of ``goals`` and run it (module doc)."""
        self._not_in_block(f"{command} with plan=True")
        planned = self._plan_joint_path(name, goals, command)
        self._run_waypoints(name, planned.waypoints, command, planned)

    def _run_waypoints(
        self, name: str, waypoints: Array, command: str, planned: PlannedPath | None = None
    ) -> None:
        """Run joint waypoints (row 0: where the robot is) as one command: each segment a
        joint move of the simulator's profile, all joints together."""
        times, rows = [np.empty(0)], [np.empty((0, len(waypoints[0])))]
        start = t0 = self._start_time(name)
        activity: dict[str, float] = {}
        for a, b in itertools.pairwise(waypoints):
            m = self._plan(name, a, b, command, together=True)
            if len(m.t):
                times.append(start + m.t)
                rows.append(m.rows_of())
                start = float(times[-1][-1])
                for k, v in m.activity.items():
                    activity[k] = activity.get(k, 0.0) + v
        deg = ", ".join(f"{v:.6g}" for v in np.degrees(waypoints[-1]))
        how = f"{len(waypoints) - 2} via point(s)"
        if planned is not None:
            how += f", planned in {planned.seconds:.3g} s"
        program = self._program_settings(
            name, {"kind": "path", "waypoints": np.asarray(waypoints[1:]).tolist(), "zone": 0.0}
        )
        program["q"] = np.asarray(waypoints[-1], dtype=np.float64).tolist()
        record = command_record(name, command, t0, start - t0, activity, program=program)
        self._run(
            name,
            np.concatenate(times),
            np.concatenate(rows),
            command,
            f"to ({deg}) deg, {how}",
            record,
        )
