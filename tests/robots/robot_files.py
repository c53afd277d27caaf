"""Robot files the tests write: URDF and MJCF arms with meshes, primitives, branches.

Nothing third-party: every file is generated here (meshes by trimesh), except the real
ROS-Industrial files that the test-only ``rtb-data`` package ships (:data:`RTB`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

try:
    import rtbdata

    RTB: Path | None = Path(rtbdata.__path__[0]) / "xacro"
except ImportError:  # pragma: no cover - rtb-data is a test dependency
    RTB = None

RTB_FILES = {
    "kr16": "kuka_description/kuka_kr16/urdf/kr16_2.urdf",
    "kr210": "kuka_description/kuka_kr210/urdf/kr210l150.urdf",
    "kr120": "kuka_description/kuka_kr120/urdf/kr120r2500pro.urdf",
    "irb140": "abb_irb140_description/urdf/irb140.urdf",
}

# what MuJoCo needs to compile a URDF whose links have no <inertial> and keep every link
MUJOCO_BLOCK = (
    '<mujoco><compiler fusestatic="false" discardvisual="false" boundmass="0.001" '
    'boundinertia="1e-6" strippath="false"/></mujoco>'
)


def l_shape() -> trimesh.Trimesh:
    """A closed, non-convex L-shaped prism (0.2 x 0.2 x 0.05 m, 0.1 m wide arms)."""
    outline = [(0, 0), (0.2, 0), (0.2, 0.1), (0.1, 0.1), (0.1, 0.2), (0, 0.2)]
    from shapely.geometry import Polygon

    return trimesh.creation.extrude_polygon(Polygon(outline), 0.05)


def write_meshes(folder: Path) -> None:
    """meshes/arm.stl (a box), meshes/arm.obj (a cylinder), meshes/ell.stl (an L)."""
    (folder / "meshes").mkdir(parents=True, exist_ok=True)
    trimesh.creation.box(extents=(0.3, 0.06, 0.05)).export(folder / "meshes/arm.stl")
    trimesh.creation.cylinder(radius=0.04, height=0.2, sections=16).export(
        folder / "meshes/arm.obj"
    )
    l_shape().export(folder / "meshes/ell.stl")


def arm_urdf(mesh_dir: str = "meshes", *, mujoco: bool = True, extra: str = "") -> str:
    """A 5-joint test arm: rotated origins, fixed joints inside the chain, a continuous
    joint, a prismatic joint, a skew axis, a fixed sensor branch, a movable side branch,
    primitives and meshes (STL with scale, OBJ), named and inline materials, tool0."""
    return f"""<?xml version="1.0"?>
<robot name="test_arm">
  {MUJOCO_BLOCK if mujoco else ""}
  <material name="orange"><color rgba="1 0.5 0 1"/></material>
  <link name="base_link">
    <visual><geometry><box size="0.3 0.3 0.1"/></geometry><material name="orange"/></visual>
    <collision><origin xyz="0 0 0.05"/><geometry><cylinder radius="0.12" length="0.1"/></geometry></collision>
  </link>
  <link name="link1">
    <visual><origin xyz="0.1 0 0" rpy="0 0 0.1"/>
      <geometry><mesh filename="{mesh_dir}/arm.stl" scale="0.5 1 2"/></geometry>
      <material name="blue"><color rgba="0 0 1 1"/></material></visual>
    <collision><geometry><box size="0.15 0.06 0.1"/></geometry></collision>
  </link>
  <link name="link1b"/>
  <link name="link2">
    <visual><geometry><mesh filename="{mesh_dir}/arm.obj"/></geometry></visual>
    <collision><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <link name="link3"><visual><geometry><cylinder radius="0.03" length="0.2"/></geometry></visual></link>
  <link name="link4"><visual><geometry><sphere radius="0.04"/></geometry></visual></link>
  <link name="link5"/>
  <link name="tool0"/>
  <link name="sensor"><visual><geometry><box size="0.02 0.02 0.02"/></geometry></visual></link>
  <link name="side"/>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="link1"/>
    <origin xyz="0 0 0.3" rpy="0 0 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="2" effort="100"/></joint>
  <joint name="mount" type="fixed"><parent link="link1"/><child link="link1b"/>
    <origin xyz="0.05 0 0.1" rpy="0.2 -0.1 0.4"/></joint>
  <joint name="j2" type="continuous"><parent link="link1b"/><child link="link2"/>
    <origin xyz="0 0.1 0" rpy="1.5707963 0 0"/><axis xyz="0 1 0"/></joint>
  <joint name="j3" type="prismatic"><parent link="link2"/><child link="link3"/>
    <origin xyz="0.3 0 0" rpy="0 0.5 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.2" velocity="0.1"/></joint>
  <joint name="j4" type="revolute"><parent link="link3"/><child link="link4"/>
    <origin xyz="0 0.02 0.2" rpy="-0.3 0.2 0.1"/><axis xyz="0.6 0.8 0"/>
    <limit lower="-2" upper="2.5" velocity="3"/></joint>
  <joint name="j5" type="revolute"><parent link="link4"/><child link="link5"/>
    <origin xyz="0.1 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="3"/></joint>
  <joint name="flange" type="fixed"><parent link="link5"/><child link="tool0"/>
    <origin xyz="0 0 0.1" rpy="0 1.5707963 0"/></joint>
  <joint name="sensor_mount" type="fixed"><parent link="link2"/><child link="sensor"/>
    <origin xyz="0 0 0.05"/></joint>
  <joint name="side_joint" type="revolute"><parent link="link1"/><child link="side"/>
    <axis xyz="1 0 0"/><limit lower="-1" upper="1" velocity="1"/></joint>
  {extra}
</robot>
"""


def gripper_urdf() -> str:
    """A 2-joint arm with a parallel gripper on a fixed palm: two fingers sliding along
    the palm's x axis (the gripper frame must turn them onto y), 0 = closed."""
    return """<?xml version="1.0"?>
<robot name="gripper_arm">
  <link name="base"><visual><geometry><box size="0.2 0.2 0.1"/></geometry></visual></link>
  <link name="a"><visual><geometry><box size="0.05 0.05 0.4"/></geometry></visual></link>
  <link name="b"><visual><geometry><box size="0.3 0.05 0.05"/></geometry></visual></link>
  <link name="palm"><visual><geometry><box size="0.1 0.03 0.02"/></geometry></visual>
    <collision><geometry><box size="0.1 0.03 0.02"/></geometry></collision></link>
  <link name="fa"><visual><origin xyz="0.005 0 0.03"/><geometry><box size="0.01 0.02 0.05"/></geometry></visual>
    <collision><origin xyz="0.005 0 0.03"/><geometry><box size="0.01 0.02 0.05"/></geometry></collision></link>
  <link name="fb"><visual><origin xyz="-0.005 0 0.03"/><geometry><box size="0.01 0.02 0.05"/></geometry></visual>
    <collision><origin xyz="-0.005 0 0.03"/><geometry><box size="0.01 0.02 0.05"/></geometry></collision></link>
  <joint name="q1" type="revolute"><parent link="base"/><child link="a"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1"/></joint>
  <joint name="q2" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0 0.4"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="1"/></joint>
  <joint name="wrist" type="fixed"><parent link="b"/><child link="palm"/>
    <origin xyz="0.3 0 0" rpy="0 1.5707963267948966 0"/></joint>
  <joint name="left" type="prismatic"><parent link="palm"/><child link="fa"/><origin xyz="0 0 0.01"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.04" velocity="0.1"/></joint>
  <joint name="right" type="prismatic"><parent link="palm"/><child link="fb"/><origin xyz="0 0 0.01"/>
    <axis xyz="-1 0 0"/><limit lower="0" upper="0.04" velocity="0.1"/></joint>
</robot>
"""


def write(folder: Path, name: str, text: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / name
    p.write_text(text)
    return p


def random_q(robot, n: int, seed: int = 0) -> np.ndarray:
    """``n`` joint vectors uniform in the robot's limits."""
    return np.random.default_rng(seed).uniform(robot.lower, robot.upper, (n, robot.dof))


def arm_mjcf(*, mesh: str = "meshes/arm.stl", extra_body: str = "", gripper: bool = True) -> str:
    """A 5-joint MJCF arm: degrees, default classes, a fixed body inside the chain, a joint
    ``ref``, a joint ``pos`` off the body origin, an unlimited hinge, a slide, a scaled
    mesh and primitive geoms (visual-only, colliding, hidden collision), materials, a
    tool site, two keyframes and (optionally) a parallel gripper with finger slides."""
    hand = (
        """
              <body name="hand" pos="0 0 0.05" euler="0 0 30">
                <geom type="box" size="0.02 0.05 0.01" rgba="0.2 0.2 0.2 1"/>
                <body name="finger_l" pos="0 0 0.01">
                  <joint name="fl" type="slide" axis="0 1 0" range="0 0.03"/>
                  <geom type="box" size="0.01 0.005 0.02" pos="0 0.006 0.02"/>
                </body>
                <body name="finger_r" pos="0 0 0.01" euler="0 0 180">
                  <joint name="fr" type="slide" axis="0 1 0" range="0 0.03"/>
                  <geom type="box" size="0.01 0.005 0.02" pos="0 0.006 0.02"/>
                </body>
              </body>"""
        if gripper
        else ""
    )
    return f"""<mujoco model="mjcf_arm">
  <compiler angle="degree" autolimits="true"/>
  <default>
    <joint axis="0 0 1" range="-170 170"/>
    <default class="visual"><geom contype="0" conaffinity="0" group="2"/></default>
    <default class="collision"><geom group="3"/></default>
  </default>
  <asset>
    <material name="paint" rgba="0.9 0.4 0.1 1"/>
    <mesh name="arm" file="{mesh}" scale="1 1 2"/>
  </asset>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="base" pos="0.1 0.2 0.05" euler="0 0 20">
      <geom type="cylinder" size="0.1 0.05" material="paint"/>
      <body name="l1" pos="0 0 0.1">
        <joint name="j1"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.3" size="0.04" class="visual" rgba="0 0 1 1"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.3" size="0.05" class="collision"/>
        <body name="l2" pos="0 0.05 0.3" euler="90 0 0">
          <joint name="j2" ref="30" pos="0.01 0 0"/>
          <geom type="mesh" mesh="arm" pos="0.15 0 0" class="visual" material="paint"/>
          <body name="bracket" pos="0.3 0 0" euler="0 20 0">
            <geom type="sphere" size="0.03"/>
            <body name="l3">
              <joint name="j3" type="slide" axis="1 0 0" range="0 0.15" ref="0.02"/>
              <geom type="box" size="0.05 0.02 0.02"/>
              <body name="l4" pos="0.1 0 0" euler="-10 30 5">
                <joint name="j4" axis="0.6 0.8 0" limited="false"/>
                <geom type="ellipsoid" size="0.03 0.02 0.025"/>
                <body name="l5" pos="0.05 0 0">
                  <joint name="j5" axis="0 1 0" range="-90 120"/>
                  <geom type="cylinder" size="0.02 0.02"/>
                  <site name="flange" pos="0 0 0.04" euler="0 90 0"/>{hand}
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
      {extra_body}
    </body>
  </worldbody>
  <keyframe>
    <key name="home" qpos="0.1 0.2 0.05 0.3 0.4{" 0.03 0.03" if gripper else ""}"/>
    <key qpos="0 0.5 0.02 0 0{" 0 0" if gripper else ""}"/>
  </keyframe>
</mujoco>
"""


def urdf_fk(path, joint_names, Q, tip="tool0", base="base_link") -> np.ndarray:
    """Poses (m, 4, 4) of link ``tip`` in link ``base`` of URDF file ``path`` at joint rows
    Q (m, n) of the joints ``joint_names``, by yourdfpy (an independent URDF reader)."""
    import yourdfpy

    u = yourdfpy.URDF.load(
        str(path), load_meshes=False, build_scene_graph=True, load_collision_meshes=False
    )
    out = []
    for q in Q:
        u.update_cfg(dict(zip(joint_names, q, strict=True)))
        out.append(u.get_transform(tip, base))
    return np.array(out)
