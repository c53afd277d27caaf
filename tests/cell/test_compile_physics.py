"""What the compiled cell carries for the physics mode: servos, gravity compensation,
stiff contacts, the timestep and the ``initial`` keyframe (checked on the two-Puma cell,
against MuJoCo's own mass matrix and dynamics)."""

from __future__ import annotations

import math
import subprocess
import sys

import mujoco
import numpy as np
import pytest

from workcell.cell import compile_cell
from workcell.cell.compile import INITIAL_KEY, export_cell
from workcell.errors import GeometryError
from workcell.meshgeoms import CONTACT_SOLIMP, CONTACT_SOLREF
from workcell.robots.mjcf import (
    ARMATURE,
    SERVO_DAMPING,
    SERVO_FREQUENCY,
    robot_spec,
)


@pytest.fixture(scope="module")
def compiled(cell):
    return cell, compile_cell(cell)


def test_a_position_servo_per_arm_joint_and_finger(compiled):
    cell, cc = compiled
    m = cc.model
    names = [m.actuator(a).name for a in range(m.nu)]
    want = [j for r in cell.robots for j in cc.joint_names[r] + cc.finger_joints.get(r, ())]
    assert names == want
    for a in range(m.nu):
        j = m.actuator_trnid[a, 0]
        assert m.joint(j).name == names[a]  # each drives the joint of its name
        kp, kv = m.actuator_gainprm[a, 0], -m.actuator_biasprm[a, 2]
        q0 = m.qpos0[m.jnt_qposadr[j]]  # the joint's initial value
        # force = kp (ctrl + q0 - q) - kv qdot: ctrl is the offset from the initial value
        assert m.actuator_biasprm[a, 1] == -kp
        assert m.actuator_biasprm[a, 0] == pytest.approx(kp * q0, rel=1e-12, abs=1e-12)
        np.testing.assert_allclose(m.actuator_ctrlrange[a], m.jnt_range[j] - q0, atol=1e-12)
        assert m.actuator_ctrllimited[a]
        assert not m.actuator_forcelimited[a]
        assert kp > 0
        assert kv > 0


def test_servo_gains_give_the_stated_frequency_and_damping(cell):
    # kp / I = w^2 and kv / (2 I w) = zeta with I the joint's own inertia at q = 0, from
    # MuJoCo's mass matrix of the robot alone
    robot = cell.robots["puma_1"].robot
    m = robot_spec(robot).compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    w = 2 * math.pi * SERVO_FREQUENCY
    for a in range(m.nu):
        dof = m.jnt_dofadr[m.actuator_trnid[a, 0]]
        inertia = M[dof, dof]
        assert m.actuator_gainprm[a, 0] == pytest.approx(inertia * w * w, rel=1e-9)
        assert -m.actuator_biasprm[a, 2] == pytest.approx(2 * SERVO_DAMPING * inertia * w)
    arm = [m.joint(j).id for j in range(robot.dof)]
    assert m.dof_armature[m.jnt_dofadr[arm]] == pytest.approx(ARMATURE)


def test_gravity_compensation_on_robot_bodies_only(compiled):
    _, cc = compiled
    m = cc.model
    for b in range(1, m.nbody):
        robot = any(m.body(b).name.startswith(p) for p in cc.robot_prefixes.values())
        assert m.body_gravcomp[b] == (1.0 if robot else 0.0), m.body(b).name


def test_stiff_contacts_timestep_and_integrator(cell):
    cc = compile_cell(cell, timestep=0.001)
    m = cc.model
    assert m.opt.timestep == 0.001
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    colliding = np.flatnonzero(m.geom_contype | m.geom_conaffinity)
    np.testing.assert_allclose(m.geom_solref[colliding], [CONTACT_SOLREF] * len(colliding))
    np.testing.assert_allclose(m.geom_solimp[colliding], [CONTACT_SOLIMP] * len(colliding))
    assert compile_cell(cell).model.opt.timestep == 0.002
    for bad in (0.0, -1.0, float("nan"), "1 ms"):
        with pytest.raises(GeometryError, match="timestep"):
            compile_cell(cell, timestep=bad)


def test_initial_key_holds_the_arms_still(compiled):
    cell, cc = compiled
    m = cc.model
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key(INITIAL_KEY).id)
    np.testing.assert_array_equal(d.qpos, m.qpos0)
    adr = [m.jnt_qposadr[m.joint(j).id] for r in cell.robots for j in cc.joint_names[r]]
    want = np.concatenate([cell.robots[r].q for r in cell.robots])
    np.testing.assert_allclose(d.qpos[adr], want, atol=1e-12)
    for _ in range(500):  # 1 s
        mujoco.mj_step(m, d)
    np.testing.assert_allclose(d.qpos[adr], want, atol=1e-6)


_PLAYER = """
import sys, numpy as np
from dm_control import mjcf
phys = mjcf.Physics.from_mjcf_model(mjcf.from_path(sys.argv[1]))
phys.reset(0)  # the 'initial' keyframe
q0 = phys.data.qpos.copy()
for _ in range(250):
    phys.step()
print(phys.model.nu, float(np.abs(phys.data.qpos[14:] - q0[14:]).max()))
"""


def test_exported_cell_plays_in_dm_control(compiled, tmp_path):
    cell, cc = compiled
    path = export_cell(cell, tmp_path / "out")
    res = subprocess.run(
        [sys.executable, "-c", _PLAYER, str(path)],
        cwd="/",
        capture_output=True,
        text=True,
        check=False,
    )
    assert res.returncode == 0, res.stderr
    nu, drift = res.stdout.split()
    assert int(nu) == cc.model.nu
    assert float(drift) < 1e-6  # the arms (after the two free joints) hold their pose


_HOLD = """
import sys, mujoco, numpy as np
m = mujoco.MjModel.from_xml_path(sys.argv[1])
d = mujoco.MjData(m)  # fresh: ctrl 0, no keyframe loaded
mujoco.mj_forward(m, d)
x0, s0 = d.xpos.copy(), d.site_xpos.copy()
while d.time < 5.0:
    mujoco.mj_step(m, d)
drift = np.linalg.norm(d.xpos - x0, axis=1)
for b in range(1, m.nbody):
    print(m.body(b).name, drift[b])
print("sites", np.linalg.norm(d.site_xpos - s0, axis=1).max())
"""


@pytest.mark.slow
def test_a_freshly_loaded_export_holds_its_initial_pose_for_5_s(compiled, tmp_path):
    """Stepped from a new MjData (ctrl 0, as MuJoCo's viewer starts), every robot body and
    tool site of the exported file stays within 1 mm of its initial pose for 5 s (no arm
    swings to q = 0), and a cube resting on a table stays too (the two-Puma cell's cube
    floats in the air and falls, as it should)."""
    from workcell.examples import thesis_pick_place as pp

    cell, _ = compiled
    for c, still in ((cell, ("puma_1.", "puma_2.", "sites")), (pp.build(), ("puma.", "cube"))):
        path = export_cell(c, tmp_path / c.name)
        assert "holds the initial pose" in path.read_text().split("\n")[1]  # the comment
        res = subprocess.run(
            [sys.executable, "-c", _HOLD, str(path)], cwd="/", capture_output=True, text=True
        )
        assert res.returncode == 0, res.stderr
        drift = {k: float(v) for k, v in (line.split() for line in res.stdout.splitlines())}
        held = {b: d for b, d in drift.items() if b.startswith(still)}
        assert len(held) > 10
        for body, d in held.items():
            assert d < 1e-3, (c.name, body, d)
