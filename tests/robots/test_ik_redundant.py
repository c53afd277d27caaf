"""Numerical IK of redundant, hard-limit arms, against FK from outside the solver.

- The Panda (rtb-data's ``panda_arm.urdf.xacro``, compiled with xacrodoc) and the LBR
  iiwa 14 (rtb-data's URDF): 500 random reachable targets each (``fk(q)``, q uniform
  within the limits), at least 99 % reached, and every success re-checked by yourdfpy
  (an independent URDF FK) within the tolerances and within the limits: never a false
  success.
- A Menagerie-like Panda MJCF written here (the published Franka kinematics, the body
  layout and joint ranges of MuJoCo Menagerie's ``panda.xml``, primitive geoms instead
  of meshes): the same, re-checked by MuJoCo's own compile of the file.
- Targets out of reach fail with a reason, never succeed.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import mujoco
import numpy as np
import pytest
from robot_files import RTB, urdf_fk

from workcell import spatial
from workcell.robots import from_mjcf, from_urdf

needs_rtb = pytest.mark.skipif(RTB is None, reason="rtb-data (a test dependency) is missing")
TOL = 1e-6  # m and rad: Robot.ik's default tolerances
IIWA = "kuka_description/kuka_lbr_iiwa/urdf/lbr_iiwa_14_r820.urdf"


def angle(Ra, Rb):
    return float(np.arccos(np.clip((np.trace(Ra.T @ Rb) - 1.0) / 2.0, -1.0, 1.0)))


def quiet_urdf(path, **kw):
    with warnings.catch_warnings():  # the files' missing visual meshes
        warnings.simplefilter("ignore")
        return from_urdf(path, geometry=False, **kw)


def compile_panda(folder: Path) -> Path:
    from xacrodoc import XacroDoc, packages

    frankie = RTB / "qut_frankie_description"
    packages.update_package_cache({"qut_frankie_description": str(frankie)})
    doc = XacroDoc.from_file(frankie / "robots/panda_arm.urdf.xacro", resolve_packages=False)
    path = folder / "panda_arm.urdf"
    path.write_text(doc.to_urdf_string())
    return path


def reach_rate(robot, n, seed, reference_fk):
    """Success rate of Robot.ik on n random reachable targets; every success re-checked
    by ``reference_fk`` (joint vectors (m, dof) -> poses (m, 4, 4), not the project's FK)."""
    rng = np.random.default_rng(seed)
    Q = rng.uniform(robot.lower, robot.upper, (n, robot.dof))
    targets = reference_fk(Q)
    np.testing.assert_allclose(robot.fk_batch(Q), targets, atol=1e-9)  # same chain
    sols = [robot.ik(T) for T in targets]
    good = [s for s in sols if s.success]
    if good:
        got = reference_fk(np.array([s.q for s in good]))
        reached = [t for t, s in zip(targets, sols, strict=True) if s.success]
        for s, T, P in zip(good, reached, got, strict=True):
            assert np.linalg.norm(P[:3, 3] - T[:3, 3]) <= TOL  # never a false success
            assert angle(P[:3, :3], T[:3, :3]) <= TOL
            assert robot.within_limits(s.q)
    for s in sols:
        if not s.success:
            assert s.reason
    return len(good) / n


@needs_rtb
@pytest.mark.parametrize("arm", ["panda", "iiwa"])
def test_redundant_arms_reach_99_percent_of_random_reachable_targets(arm, tmp_path):
    if arm == "panda":
        path, tip, base = compile_panda(tmp_path), "panda_link8", "panda_link0"
    else:
        path, tip, base = RTB / IIWA, "tool0", "base_link"
    robot = quiet_urdf(path, tip_link=tip)
    assert robot.dof == 7
    assert robot.ik_family is None
    names = [j.name for j in robot.joints]

    def fk(Q):
        return urdf_fk(path, names, Q, tip, base)

    assert reach_rate(robot, 500, 1, fk) >= 0.99


PANDA_XML = """<mujoco model="panda_like">
  <compiler angle="radian" autolimits="true"/>
  <default>
    <default class="panda">
      <joint axis="0 0 1" range="-2.8973 2.8973"/>
      <default class="finger"><joint axis="0 1 0" type="slide" range="0 0.04"/></default>
    </default>
  </default>
  <worldbody>
    <body name="link0" childclass="panda">
      <geom type="cylinder" size="0.06 0.05" pos="0 0 0.05"/>
      <body name="link1" pos="0 0 0.333">
        <joint name="joint1"/>
        <geom type="capsule" size="0.06" fromto="0 0 -0.2 0 0 0"/>
        <body name="link2" quat="1 -1 0 0">
          <joint name="joint2" range="-1.7628 1.7628"/>
          <geom type="capsule" size="0.06" fromto="0 0 0 0 -0.3 0"/>
          <body name="link3" pos="0 -0.316 0" quat="1 1 0 0">
            <joint name="joint3"/>
            <geom type="capsule" size="0.05" fromto="0 0 -0.1 0.08 0 0"/>
            <body name="link4" pos="0.0825 0 0" quat="1 1 0 0">
              <joint name="joint4" range="-3.0718 -0.0698"/>
              <geom type="capsule" size="0.05" fromto="0 0 0 -0.08 0.38 0"/>
              <body name="link5" pos="-0.0825 0.384 0" quat="1 -1 0 0">
                <joint name="joint5"/>
                <geom type="capsule" size="0.04" fromto="0 0 -0.2 0 0 0"/>
                <body name="link6" quat="1 1 0 0">
                  <joint name="joint6" range="-0.0175 3.7525"/>
                  <geom type="capsule" size="0.04" fromto="0 0 0 0.088 0 0"/>
                  <body name="link7" pos="0.088 0 0" quat="1 1 0 0">
                    <joint name="joint7"/>
                    <geom type="cylinder" size="0.04 0.05" pos="0 0 0.05"/>
                    <body name="link8" pos="0 0 0.107">
                      <body name="hand" quat="0.9238795 0 0 -0.3826834">
                        <geom type="box" size="0.02 0.1 0.03" pos="0 0 0.03"/>
                        <body name="left_finger" pos="0 0 0.0584">
                          <joint name="finger_joint1" class="finger"/>
                          <geom type="box" size="0.01 0.01 0.02" pos="0 0.01 0.02"/>
                        </body>
                        <body name="right_finger" pos="0 0 0.0584" quat="0 0 0 1">
                          <joint name="finger_joint2" class="finger"/>
                          <geom type="box" size="0.01 0.01 0.02" pos="0 0.01 0.02"/>
                        </body>
                      </body>
                    </body>
                  </body>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <keyframe>
    <key name="home" qpos="0 0 0 -1.57079 0 1.57079 -0.7853 0.04 0.04"/>
  </keyframe>
</mujoco>
"""


def test_a_menagerie_like_panda_reaches_99_percent_and_mujoco_agrees(tmp_path):
    path = tmp_path / "panda.xml"
    path.write_text(PANDA_XML)
    robot = from_mjcf(path, geometry=False, tip_body="hand")
    assert robot.dof == 7
    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    hand = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "hand")
    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "link0")

    def fk(Q):  # MuJoCo's own compile of the file: hand in link0 (at the world origin)
        out = []
        for q in Q:
            data.qpos[:7] = q
            mujoco.mj_kinematics(model, data)
            T = np.eye(4)
            T[:3, :3] = data.xmat[hand].reshape(3, 3)
            T[:3, 3] = data.xpos[hand] - data.xpos[base]
            out.append(T)
        return np.array(out)

    assert reach_rate(robot, 200, 3, fk) >= 0.99


def test_targets_out_of_reach_fail_with_a_reason(tmp_path):
    path = tmp_path / "panda.xml"
    path.write_text(PANDA_XML)
    robot = from_mjcf(path, geometry=False, tip_body="hand")
    for T in (spatial.translation(1.5, 0, 0.3), spatial.translation(0, 0, 1.4)):
        sol = robot.ik(T)
        assert not sol.success
        assert "unreachable" in sol.reason
        assert sol.position_error > 0.1
