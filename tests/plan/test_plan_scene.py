"""Planning scenes: validity against MuJoCo's own distances, and the displacement bound.

References: ``mj_geomDistance`` between every pair of collision geoms MuJoCo would
check (no parent/child pair, no ``<exclude>``), called here directly; vertex positions of
the moving collision meshes from ``mj_kinematics`` sampled densely along segments.
"""

from __future__ import annotations

import itertools

import mujoco
import numpy as np
import pytest

from workcell.errors import PlanningError
from workcell.examples import obstacle, thesis_pick_place
from workcell.plan.scene import PlanningScene
from workcell.sim import Simulator

ROBOT = obstacle.ROBOT


@pytest.fixture(scope="module")
def sim() -> Simulator:
    return Simulator(obstacle.build(), check_collisions=False)


def distances(sim: Simulator, q: np.ndarray) -> list[tuple[float, int, int]]:
    """mj_geomDistance of every checked pair with a link of the robot, at q."""
    m = sim.model
    d = mujoco.MjData(m)
    d.qpos[:] = sim.data.qpos
    d.qpos[sim._qadr[ROBOT]] = q
    mujoco.mj_kinematics(m, d)
    robot_bodies = {b for b in range(m.nbody) if m.body(b).name.startswith(f"{ROBOT}.")}
    moving = robot_bodies - {m.body(f"{ROBOT}.link0").id}
    excluded = {(int(s) >> 16, int(s) & 0xFFFF) for s in m.exclude_signature}
    geoms = [g for g in range(m.ngeom) if m.geom_contype[g] or m.geom_conaffinity[g]]
    out = []
    for i in geoms:
        bi = int(m.geom_bodyid[i])
        if bi not in moving:
            continue
        for j in geoms:
            bj = int(m.geom_bodyid[j])
            if bj == bi or (bj in moving and j < i):
                continue
            if m.body_parentid[bi] == bj or m.body_parentid[bj] == bi:
                continue
            if (min(bi, bj), max(bi, bj)) in excluded:
                continue
            out.append((mujoco.mj_geomDistance(m, d, i, j, 1.0, None), i, j))
    return out


def test_valid_means_every_pair_keeps_the_clearance(sim):
    scene = PlanningScene(sim, [ROBOT], clearance=0.02)
    robot = sim.cell.robots[ROBOT].robot
    rng = np.random.default_rng(5)
    seen = {True: 0, False: 0}
    for q in rng.uniform(robot.lower, robot.upper, size=(60, robot.dof)):
        closest = min(dist for dist, _, _ in distances(sim, q))
        if abs(closest - 0.02) < 1e-6:
            continue  # on the boundary: either answer is right
        assert scene.valid(q) == (closest >= 0.02), closest
        seen[closest >= 0.02] += 1
    assert seen[True] >= 5
    assert seen[False] >= 5


def test_a_point_moves_at_most_sum_dq_r_along_a_segment(sim):
    scene = PlanningScene(sim, [ROBOT], clearance=0.005)
    R = scene.radii()
    m = sim.model
    d = mujoco.MjData(m)

    def moves(g: int) -> bool:
        name = m.body(int(m.geom_bodyid[g])).name
        return bool(m.geom_contype[g]) and name.startswith(f"{ROBOT}.") and name != f"{ROBOT}.link0"

    moving = [g for g in range(m.ngeom) if moves(g)]

    def vertices(q: np.ndarray) -> np.ndarray:
        d.qpos[:] = sim.data.qpos
        d.qpos[sim._qadr[ROBOT]] = q
        mujoco.mj_kinematics(m, d)
        pts = []
        for g in moving:
            mid = m.geom_dataid[g]
            V = m.mesh_vert[m.mesh_vertadr[mid] : m.mesh_vertadr[mid] + m.mesh_vertnum[mid]]
            pts.append(V @ d.geom_xmat[g].reshape(3, 3).T + d.geom_xpos[g])
        return np.vstack(pts)

    robot = sim.cell.robots[ROBOT].robot
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(25):
        a = rng.uniform(robot.lower, robot.upper)
        b = a + rng.normal(scale=0.3, size=robot.dof)
        bound = float(np.abs(b - a) @ R)
        P = [vertices(a + (b - a) * t) for t in np.linspace(0, 1, 41)]
        travelled = sum(np.linalg.norm(p1 - p0, axis=1) for p0, p1 in itertools.pairwise(P))
        worst = max(worst, float(travelled.max()) / bound)
        assert travelled.max() <= bound * (1 + 1e-9)
    assert worst > 0.3  # the bound is not absurdly loose


def test_start_collision_names_the_pair_and_touching_pairs_are_allowed():
    # the cube of example 2 rests on the table: touching, allowed
    sim = Simulator(thesis_pick_place.build())
    scene = PlanningScene(sim, ["puma"], clearance=0.005, grips=[("puma", "cube")])
    assert scene.start_collision is None
    # a stage pushed into the arm's base: the start overlaps, named with its depth
    cell = thesis_pick_place.build()
    from workcell import solids
    from workcell.spatial import translation

    solids.box(cell.model, "post", size=(0.05, 0.05, 0.5))
    cell.add_static("post", "post", translation(0.03, -0.1, 0.4))
    sim = Simulator(cell)
    with pytest.raises(
        PlanningError,
        match=r"start in collision: .*post.* overlaps|start in collision: post overlaps",
    ):
        sim.move_joints_absolute("puma", sim.joints("puma") + 0.1, plan=True)
