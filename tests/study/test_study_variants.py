"""Cell variants made by editing the compiled model agree with compiling the moved cell."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from workcell.cell import Workcell, compile_cell
from workcell.errors import ModelError
from workcell.examples import thesis_handoff, thesis_pick_place
from workcell.sim.contacts import contact_model
from workcell.spatial import rot_z, translation
from workcell.study.variants import Template, moved, rebuild


@pytest.fixture(scope="module")
def pick_place():
    cell = thesis_pick_place.build()
    return cell, Template(cell)


def _state(m: mujoco.MjModel, q: np.ndarray) -> tuple[mujoco.MjData, list[tuple[str, str, float]]]:
    d = mujoco.MjData(m)
    d.qpos[:] = q
    mujoco.mj_kinematics(m, d)
    mujoco.mj_collision(m, d)
    pairs = sorted(
        (m.geom(c.geom1).name, m.geom(c.geom2).name, round(float(c.dist), 9))
        for c in d.contact[: d.ncon]
    )
    return d, pairs


def _same_as_fresh(cell, compiled, q_arm) -> None:
    fresh = compile_cell(cell).model
    m = compiled.model
    q = m.qpos0.copy()
    q[:6] = q_arm
    d1, c1 = _state(m, q)
    d2, c2 = _state(fresh, q)
    np.testing.assert_allclose(d1.xpos, d2.xpos, atol=1e-12)
    np.testing.assert_allclose(d1.xmat, d2.xmat, atol=1e-12)
    np.testing.assert_allclose(d1.geom_xpos, d2.geom_xpos, atol=1e-12)
    np.testing.assert_allclose(d1.geom_xmat, d2.geom_xmat, atol=1e-12)
    np.testing.assert_allclose(m.qpos0, fresh.qpos0, atol=1e-12)
    assert c1 == c2
    if np.array_equal(m.bvh_child, fresh.bvh_child) and np.array_equal(
        m.bvh_nodeid, fresh.bvh_nodeid
    ):
        np.testing.assert_allclose(m.bvh_aabb, fresh.bvh_aabb, atol=1e-12)  # the same tree
    # the simulator's contact model (margins 0) sees the same overlaps
    for model in (m, fresh):
        sim_m = contact_model(model)
        c = _state(sim_m, q)[1]
        if model is m:
            first = c
    assert first == c


@settings(
    max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    dx=st.floats(-0.2, 0.2),
    dy=st.floats(-0.2, 0.2),
    yaw=st.floats(-math.pi, math.pi),
    part_dx=st.floats(-0.1, 0.1),
    seed=st.integers(0, 1000),
)
def test_moved_robots_and_parts_match_a_fresh_compile(pick_place, dx, dy, yaw, part_dx, seed):
    cell, template = pick_place
    bases = {"puma": moved(cell.robots["puma"].base, x=dx, y=dy, yaw=yaw)}
    poses = {
        "stage_1": moved(cell.static_parts["stage_1"].pose, x=0.18 + part_dx, yaw=yaw / 2),
        "cube": moved(cell.movable_parts["cube"].pose, y=-0.2 + part_dx, yaw=-yaw),
    }
    variant, compiled = template.place(bases, poses)
    np.testing.assert_allclose(variant.robots["puma"].base, bases["puma"])
    np.testing.assert_allclose(variant.static_parts["stage_1"].pose, poses["stage_1"])
    q_arm = np.random.default_rng(seed).uniform(-1.5, 1.5, 6)
    _same_as_fresh(variant, compiled, q_arm)


def test_a_moved_static_part_collides_where_a_fresh_compile_says(pick_place):
    cell, template = pick_place
    # stage 1 moved onto the cube: the contacts must show it (stale midphase boxes would not)
    over_cube = moved(cell.static_parts["stage_1"].pose, x=0.2, y=-0.25, yaw=0.3)
    variant, compiled = template.place({}, {"stage_1": over_cube})
    _, pairs = _state(compiled.model, compiled.model.qpos0)
    assert any("stage_1" in a + b and "cube" in a + b for a, b, _ in pairs)
    _same_as_fresh(variant, compiled, compiled.model.qpos0[:6])
    # the template itself is untouched
    assert not np.array_equal(template.compiled.model.geom_pos, compiled.model.geom_pos)
    assert np.array_equal(template.compiled.model.geom_pos, compile_cell(cell).model.geom_pos)


def test_moved_keeps_what_is_not_given():
    T = translation(0.1, 0.2, 0.3) @ rot_z(0.4)
    assert np.allclose(moved(T), T)
    assert np.allclose(moved(T, z=1.0), translation(0.1, 0.2, 1.0) @ rot_z(0.4))
    assert np.allclose(moved(T, yaw=-1.0), translation(0.1, 0.2, 0.3) @ rot_z(-1.0))


def test_robot_choice_rebuilds_through_add_robot():
    cell = thesis_handoff.build()
    other = rebuild(cell, robots={"puma_2": "puma560"})
    assert other.robots["puma_2"].builtin == "puma560"
    assert other.robots["puma_1"].robot is cell.robots["puma_1"].robot  # untouched
    np.testing.assert_allclose(other.robots["puma_2"].base, cell.robots["puma_2"].base)
    assert other.robots["puma_2"].robot.gripper is not None  # the gripper is kept
    # compiled from memory: puma_2's meshes are the 560's, not the 260's of the same names
    small = compile_cell(cell).model  # compiled first, in this process
    big = compile_cell(other).model
    alone = Workcell("alone")
    alone.add_robot("puma_2", "puma560", gripper=True)
    only_560 = compile_cell(alone).model

    def meshes(m):
        return {
            m.mesh(i).name: m.mesh_vert[m.mesh_vertadr[i] : m.mesh_vertadr[i] + m.mesh_vertnum[i]]
            for i in range(m.nmesh)
            if m.mesh(i).name.startswith("puma_2.")
        }

    got, want, old = meshes(big), meshes(only_560), meshes(small)
    assert got.keys() == want.keys() == old.keys()
    for name in got:
        np.testing.assert_array_equal(got[name], want[name])
    assert any(got[n].shape != old[n].shape or not np.allclose(got[n], old[n]) for n in got)


ONE_JOINT_URDF = """<?xml version="1.0"?>
<robot name="one">
  <link name="base"><visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual></link>
  <link name="arm"><visual><geometry><box size="0.3 0.05 0.05"/></geometry></visual></link>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="arm"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" velocity="1.5" effort="10"/>
  </joint>
</robot>
"""


def test_a_variant_saves_its_robots_as_the_cell_did(tmp_path):
    """Library robots stay library names (with their gripper parameters) and file robots
    stay their files; only what the variant changes differs."""
    from workcell.robots import from_urdf

    (tmp_path / "one.urdf").write_text(ONE_JOINT_URDF)
    cell = thesis_handoff.build()
    cell.add_robot("one", from_urdf(tmp_path / "one.urdf"), base=translation(2, 0, 0), q=[0.5])
    B = translation(0.1, 0.2, 0.0) @ rot_z(0.3)
    variant = rebuild(cell, bases={"puma_1": B})
    before, after = cell.to_dict(tmp_path), variant.to_dict(tmp_path)
    for old, new in zip(before["robots"], after["robots"], strict=True):
        if new["name"] == "puma_1":
            assert new.pop("base") == B.tolist()
            old.pop("base")
        assert new == old
    assert after["robots"][0]["builtin"] == "puma260"
    assert after["robots"][0]["gripper"] is not None
    assert after["robots"][2]["file"]["path"] == "one.urdf"
    assert variant.robots["puma_2"].robot is cell.robots["puma_2"].robot  # not rebuilt
    with pytest.raises(ModelError, match="keeps its gripper"):
        Workcell("w").add_robot("p", cell.robots["puma_1"], gripper=True)
