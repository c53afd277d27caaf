"""Every arm of rtb-data and pybullet's iiwa and Panda (robot_files.REAL_ROBOTS): the
imported chain's forward kinematics against two independent readers of the same file,
yourdfpy and MuJoCo's own URDF compiler, over random joint values. (Their import times
are printed by scripts/bench_import.py, not timed here.)"""

from __future__ import annotations

import re
import warnings

import mujoco
import numpy as np
import pytest
from robot_files import (
    MUJOCO_BLOCK,
    PYBULLET,
    REAL_ROBOTS,
    RTB,
    random_q,
    real_robot,
    urdf_fk,
)

from workcell.robots import from_urdf


def available(name: str) -> bool:
    return (RTB if REAL_ROBOTS[name][0] == "rtb" else PYBULLET) is not None


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("real_robots")


def mujoco_fk(text: str, names: list[str], Q: np.ndarray, base: str, tip: str) -> np.ndarray:
    """Tip link in base link, by MuJoCo's compile of the URDF ``text`` (geometry left out:
    only the kinematics are compared)."""
    text = re.sub(r"<(visual|collision)\b.*?</\1>", "", text, flags=re.S)
    text = re.sub(r"(<robot\b[^>]*>)", r"\1" + MUJOCO_BLOCK, text, count=1)
    m = mujoco.MjModel.from_xml_string(text)
    d = mujoco.MjData(m)
    out = []
    for q in Q:
        for n, v in zip(names, q, strict=True):
            d.qpos[m.joint(n).qposadr[0]] = v
        mujoco.mj_kinematics(m, d)
        Ts = []
        for b in (base, tip):
            T = np.eye(4)
            T[:3, :3], T[:3, 3] = d.xmat[m.body(b).id].reshape(3, 3), d.xpos[m.body(b).id]
            Ts.append(T)
        out.append(np.linalg.inv(Ts[0]) @ Ts[1])
    return np.array(out)


@pytest.mark.parametrize("name", sorted(REAL_ROBOTS))
def test_real_robot_kinematics_match_yourdfpy_and_mujoco(name, folder):
    if not available(name):
        pytest.skip("its test package is missing")
    path, kw = real_robot(name, folder)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = from_urdf(path, geometry=False, gripper=False, **kw)
    base, tip = robot.source.rsplit("chain ", 1)[1].split(" -> ")
    names = [j.name for j in robot.joints]
    Q = random_q(robot, 30, seed=9)
    ours = robot.fk_batch(Q)  # the tip link (gripper=False: no TCP as the tool)
    np.testing.assert_allclose(ours, urdf_fk(path, names, Q, tip=tip, base=base), atol=1e-9)
    np.testing.assert_allclose(ours, mujoco_fk(path.read_text(), names, Q, base, tip), atol=1e-9)
