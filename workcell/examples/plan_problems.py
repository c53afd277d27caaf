"""Seeded random planning problems, and an independent check of a run's frames.

(Example cells for the planners: they build simulators, so they live above the
simulator; formerly ``workcell.plan.scenes``.)

:func:`random_problem` builds, from a seed, a cell with a Puma 260 (gripper on) on a
table and one to three boxes around it (sizes 4-25 cm, anywhere in the arm's reach above
the table but clear of its base and shoulder, which every motion sweeps: a box there can
wall joint 1 in and leave no solution at all), and a start and a goal joint configuration that keep the planning clearance
while the direct (linear in joints) move between them collides (an overlap deeper than
the contact tolerance at one of 39 evenly spaced points): the problems a planner is for. The same seed gives the same problem.

:func:`penetrations` re-checks a finished run without the planner's code: the cell is
exported to MJCF, loaded with plain MuJoCo (its own compile, default margins), and every
frame interval of the timeline is subdivided ``density`` times; at each sample
``mj_kinematics`` + ``mj_collision`` runs and every contact deeper than ``depth`` (m) is
a penetration, except pairs already in contact in the run's first frame.
Units: metres, radians.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray
from shapely.geometry import Point, Polygon

from workcell import solids
from workcell.cell.compile import export_cell
from workcell.cell.workcell import Workcell
from workcell.plan.scene import PlanningScene
from workcell.sim.simulator import Simulator
from workcell.spatial import rot_z, translation

__all__ = ["ROBOT", "Problem", "penetrations", "random_problem"]

Array = NDArray[np.float64]
ROBOT = "puma"
TABLE_TOP = 0.4  # m
SHOULDER_Z = TABLE_TOP + 0.3302  # m: the Puma 260's shoulder joint (d1)
# keep-out around the base and shoulder: cylinder radius and top (m), shoulder distance (m)
SHOULDER = (0.17, TABLE_TOP + 0.80, 0.25)
_PROBE = np.linspace(0.0, 1.0, 41)[1:-1]  # where a direct move is probed for a collision
_JOINT_SPAN = math.radians(170)  # rad: start and goal joints within +-170 deg (and limits)


@dataclass(frozen=True)
class Problem:
    """A planning problem: ``cell`` (the robot at ``start``), joint configurations
    ``start`` and ``goal`` (rad),
    the ``obstacles`` (name, size (3,), centre (3,), yaw) and the ``seed`` it came from."""

    cell: Workcell
    start: Array
    goal: Array
    obstacles: tuple[tuple[str, Array, Array, float], ...]
    seed: int


def _box_distance(point: Array, size: Array, centre: Array, yaw: float) -> float:
    """Distance (m) from ``point`` to a box of ``size`` at ``centre`` turned by ``yaw``."""
    local = rot_z(-yaw)[:3, :3] @ (point - centre)
    return float(np.linalg.norm(local - np.clip(local, -size / 2, size / 2)))


def _clear_of_shoulder(size: Array, centre: Array, yaw: float) -> bool:
    """Whether a box keeps out of what every motion sweeps: the base and shoulder links
    turning about joint 1 (a cylinder of radius SHOULDER[0] up to SHOULDER[1]) and
    SHOULDER[2] around the shoulder joint; otherwise joint 1 can be walled in and a
    problem may have no solution at all."""
    radius, top, around = SHOULDER
    corners = np.array([[x, y] for x in (-1, 1) for y in (-1, 1)]) * size[:2] / 2
    footprint = (rot_z(yaw)[:2, :2] @ corners.T).T + centre[:2]
    low = centre[2] - size[2] / 2
    inside = Polygon(footprint).distance(Point(0.0, 0.0)) < radius
    if inside and low < top:
        return False
    return _box_distance(np.array([0.0, 0.0, SHOULDER_Z]), size, centre, yaw) >= around


def _cell(rng: np.random.Generator, seed: int) -> tuple[Workcell, list]:
    cell = Workcell(f"plan_scene_{seed}")
    m = cell.model
    solids.box(m, "table_block", size=(1.4, 1.4, TABLE_TOP))
    cell.add_static("table", "table_block", translation(-0.7, -0.7, 0.0))
    cell.add_robot(ROBOT, "puma260", gripper=True, base=translation(0.0, 0.0, TABLE_TOP))
    obstacles = []
    for k in range(int(rng.integers(1, 4))):
        while True:
            size = rng.uniform(0.04, 0.25, size=3)
            r, th = rng.uniform(0.25, 0.5), rng.uniform(-math.pi, math.pi)
            z = TABLE_TOP + rng.uniform(0.05, 0.6)
            centre = np.array([r * math.cos(th), r * math.sin(th), z])
            yaw = float(rng.uniform(-math.pi, math.pi))
            if _clear_of_shoulder(size, centre, yaw):
                break
        name = f"obstacle_{k + 1}"
        solids.box(m, f"{name}_block", size=tuple(size))
        pose = translation(*centre) @ rot_z(yaw) @ translation(*(-size / 2))
        cell.add_static(name, f"{name}_block", pose, colour=(0.8, 0.5, 0.2))
        obstacles.append((name, size, centre, yaw))
    return cell, obstacles


def random_problem(seed: int, *, clearance: float = 0.005, attempts: int = 400) -> Problem:
    """The problem of ``seed`` (module doc); ``clearance`` (m) at the start and goal."""
    rng = np.random.default_rng(seed)
    for _ in range(attempts):
        cell, obstacles = _cell(rng, seed)
        sim = Simulator(cell, check_collisions=False)
        robot = cell.robots[ROBOT].robot
        lo = np.maximum(robot.lower, -_JOINT_SPAN)
        hi = np.minimum(robot.upper, _JOINT_SPAN)
        free = PlanningScene(sim, [ROBOT], clearance=clearance)
        touch = PlanningScene(sim, [ROBOT], clearance=sim.contacts.tolerance)
        if free.start_collision is not None:
            continue
        valid = [q for q in rng.uniform(lo, hi, size=(60, len(lo))) if free.valid(q)]
        for a in range(len(valid)):
            for b in range(a + 1, len(valid)):
                q0, q1 = valid[a], valid[b]
                if not all(touch.valid(q) for q in q0 + np.outer(_PROBE, q1 - q0)):
                    base = cell.robots[ROBOT].base
                    cell.remove(ROBOT)  # the robot starts at the start
                    cell.add_robot(ROBOT, "puma260", gripper=True, base=base, q=q0)
                    return Problem(cell, q0, q1, tuple(obstacles), seed)
    raise RuntimeError(f"no problem found for seed {seed} in {attempts} attempts")


def penetrations(
    sim: Simulator,
    *,
    density: int = 10,
    depth: float = 1e-6,
    folder: str | Path | None = None,
) -> tuple[int, int, list[tuple[int, str, str, float]]]:
    """(samples checked, penetrating samples, the first few (frame, geom, geom, depth))
    of ``sim``'s timeline re-checked on the exported MJCF (module doc)."""
    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        xml = export_cell(sim.cell, Path(tmp) / sim.cell.name)
        m = mujoco.MjModel.from_xml_path(str(xml))
    d = mujoco.MjData(m)
    Q = sim.timeline.qpos()

    def contacts(q: Array) -> list[tuple[str, str, float]]:
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_collision(m, d)
        out = []
        for i in range(d.ncon):
            c = d.contact[i]
            out.append((m.geom(c.geom1).name, m.geom(c.geom2).name, float(c.dist)))
        return out

    initial = {(a, b) for a, b, dist in contacts(Q[0]) if dist < -depth}
    samples = bad = 0
    found: list[tuple[int, str, str, float]] = []
    s = np.arange(density) / density
    for k in range(len(Q) - 1):
        for q in Q[k] + np.outer(s, Q[k + 1] - Q[k]):
            samples += 1
            hits = [(a, b, dist) for a, b, dist in contacts(q) if dist < -depth]
            hits = [h for h in hits if (h[0], h[1]) not in initial]
            if hits:
                bad += 1
                if len(found) < 5:
                    a, b, dist = min(hits, key=lambda h: h[2])
                    found.append((k, a, b, -dist))
    samples += 1
    return samples, bad, found
