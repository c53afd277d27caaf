"""A robot standing on a table: its link 1 and the table may touch (the Panda's link 1
collision capsule reaches 60 mm below its base), everything else still collides.

The robot is the real KUKA KR 16 of rtb-data with one collision cylinder added to its
link 1 that reaches 60 mm below the base's underside, as the Panda's does; the numbers
checked (depths, what touches what) follow from the cylinder's and the table's sizes.
"""

from __future__ import annotations

import json
import re
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parents[1] / "robots"))  # the real-robot registry
from robot_files import real_robot

from workcell import Workcell, solids, spatial
from workcell.cli import main
from workcell.robots import from_urdf
from workcell.sim import Simulator

rtbdata = pytest.importorskip("rtbdata")
KR16 = Path(rtbdata.__path__[0]) / "xacro" / "kuka_description" / "kuka_kr16"
H = 0.5  # m: the table's height
# link_1's frame is 0.675 m above the base's underside (joint_a1); a cylinder 0.255 m
# long centred 0.6075 m below it ends 0.060 m below the underside
REACH_DOWN = 0.060
CYLINDER = (
    '<collision><origin xyz="0 0 -0.6075"/>'
    '<geometry><cylinder radius="0.12" length="0.255"/></geometry></collision>'
)


@pytest.fixture(scope="module")
def robot(tmp_path_factory):
    text = (KR16 / "urdf" / "kr16_2.urdf").read_text()
    at = text.index('<link name="link_1">') + len('<link name="link_1">')
    path = tmp_path_factory.mktemp("kr16") / "kr16_down.urdf"
    path.write_text(text[:at] + CYLINDER + text[at:])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = from_urdf(path, search=[KR16])
    assert min(g.mesh.vertices[:, 2].min() for g in r.geometry if g.link == 0) == 0.0
    return r


def cell_with(robot, lift: float = 0.0) -> Workcell:
    """The robot on a 2 x 2 m table (its base ``lift`` m above the top), a cube in reach."""
    cell = Workcell("mounted")
    m = cell.model
    solids.box(m, "table_block", size=(2.0, 2.0, H))
    solids.cube(m, "cube_block", size=0.04)
    cell.add_static("table", "table_block", spatial.translation(-1.0, -1.0, 0.0))
    cell.add_movable("cube", "cube_block", spatial.translation(0.9, -0.02, H), density=500.0)
    q0 = np.radians([0, -90, 90, 0, 45, 0])
    cell.add_robot("arm", robot, base=spatial.translation(0, 0, H + lift), gripper=True, q=q0)
    return cell


def depths(sim: Simulator) -> dict[str, float]:
    """Collision events as {"a with b": depth in mm}."""
    out = {}
    for e in sim.events:
        if e.kind == "collision":
            what, mm = re.match(r"(.*): depth ([0-9.e+-]+) mm", e.detail).groups()
            out[what] = float(mm)
    return out


def test_a_mounted_robot_has_no_false_collision_and_picks(robot):
    sim = Simulator(cell_with(robot))
    assert sim.contacts.mounts == {"arm": ["table"]}  # not the ground: the table is between
    assert sim.contacts.allowed == {("arm.link1", "table")}
    assert depths(sim) == {}
    sim.pick("arm", "cube")
    assert [e.kind for e in sim.events].count("grasp") == 1
    assert depths(sim) == {}
    assert sim.summary()["collisions"] == 0


def test_an_arm_link_through_the_table_is_still_a_collision(robot):
    sim = Simulator(cell_with(robot))
    sim.move_joints_absolute("arm", np.radians([0, 0, 90, 0, 0, 0]))  # the wrist dips
    hit = depths(sim)
    assert any(k.startswith(("arm.link4 ", "arm.link5 ")) and k.endswith("with table") for k in hit)
    assert "arm.link1 with table" not in hit


def test_a_base_that_does_not_touch_is_not_mounted(robot):
    lift = 0.05  # the base floats 50 mm up: its link 1 still reaches 10 mm into the table
    sim = Simulator(cell_with(robot, lift))
    assert sim.contacts.mounts == {"arm": []}
    assert depths(sim)["arm.link1 with table"] == pytest.approx((REACH_DOWN - lift) * 1e3, abs=0.01)


def test_workcell_info_shows_the_mount(robot, tmp_path, capsys):
    cell = cell_with(robot)
    cell.save(tmp_path / "cell.json")
    assert main(["info", str(tmp_path / "cell.json"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["robots"][0]["stands_on"] == ["table"]
    assert main(["info", str(tmp_path / "cell.json")]) == 0
    assert "stands on 'table': its link 1 may touch it" in capsys.readouterr().out


def test_a_wall_touching_the_base_from_the_side_is_no_mount(robot):
    cell = cell_with(robot)
    above = [  # the base's collision pieces above its lowest 100 mm
        p.copy().apply_transform(g.transform).slice_plane((0, 0, 0.1), (0, 0, 1))
        for g in robot.geometry
        if g.link == 0
        for p in g.collision
    ]
    x = max(float(p.vertices[:, 0].max()) for p in above)  # its side there
    solids.box(cell.model, "wall_block", size=(0.1, 2.0, 0.5))
    cell.add_static("wall", "wall_block", spatial.translation(x, -1.0, H + 0.1))
    sim = Simulator(cell)
    assert abs(sim.clearance("arm.link0", "wall")) < 1e-6  # it touches the base
    assert sim.contacts.mounts == {"arm": ["table"]}


def test_in_physics_link_1_turns_freely_on_its_mount_and_parts_still_rest_on_it(robot):
    from workcell.sim.physics import run_physics

    sim = Simulator(cell_with(robot))
    sim.move_joints_absolute("arm", np.radians([60, -80, 90, 0, 45, 0]))
    s = run_physics(sim).summary()
    tracking = s["physics"]["tracking"]["arm"]["joint_max_each_rad"]
    assert tracking[0] < 0.01  # held back by its contact with the table: 0.9 rad
    assert s["collisions"] == 0
    assert s["physics"]["parts"]["cube"]["resting"]
    assert s["physics"]["parts"]["cube"]["distance_m"] < 1e-4  # on the table, not through it


def test_the_issues_panda_on_a_table_has_no_false_collision_and_picks(tmp_path):
    path, kw = real_robot("panda", tmp_path)  # rtb-data's Franka (its link 1 reaches down)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        panda = from_urdf(path, **kw)
    cell = Workcell("panda_table")
    solids.box(cell.model, "table_block", size=(1.0, 1.0, 0.4))
    solids.cube(cell.model, "cube_block", size=0.04)
    cell.add_static("table", "table_block", spatial.translation(-0.5, -0.5, 0.0))
    cell.add_movable("cube", "cube_block", spatial.translation(0.45, -0.02, 0.4), density=500.0)
    q0 = np.clip(np.zeros(panda.dof), panda.lower, panda.upper)
    cell.add_robot("arm", panda, base=spatial.translation(0, 0, 0.4), q=q0)
    sim = Simulator(cell)
    assert sim.contacts.mounts == {"arm": ["table"]}
    assert depths(sim) == {}  # before: "arm.link1 with table: depth 60 mm"
    sim.pick("arm", "cube")
    assert [e.kind for e in sim.events].count("grasp") == 1
    assert not [k for k in depths(sim) if "link1" in k or k.endswith("with table")]
