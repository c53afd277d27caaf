"""Units at every field the writers print: one short program (KUKA KR 6 at its home, a
100 mm line at 250 mm/s and 0.8 m/s^2 with a 10 mm zone, a 0.5 s wait, the gripper,
override 50 %) and the numbers each language must show for it, worked out here from
the vendors' units (mm, deg, m/s, %, quaternions, rotation vectors)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from workcell import Workcell
from workcell.robotprog import export
from workcell.sim import Simulator
from workcell.spatial import translation

HOME_DEG = [0.0, -90.0, 90.0, 0.0, 90.0, 0.0]


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    cell = Workcell("units")
    cell.add_robot("kr6", "kuka_kr6_r700", base=translation(1.0, 2.0, 0.0))  # no gripper
    sim = Simulator(cell, profile="jerk", check_collisions=False)
    sim.set_override("kr6", 0.5)
    sim.move_joints_absolute("kr6", np.radians(HOME_DEG))
    T = sim.tool_pose("kr6")
    sim.move_linear("kr6", translation(0.1, 0, 0) @ T, speed=0.25, acceleration=0.8, zone=0.01)
    sim.move_linear("kr6", translation(0.1, 0.05, 0) @ T, speed=0.25, acceleration=0.8)
    sim.wait(0.5)
    out = tmp_path_factory.mktemp("units")
    text = {}
    for suffix in (".script", ".src", ".mod", ".ls"):
        for p in export(sim, "kr6", out / f"u{suffix}", signals={"gripper": 7}):
            text[Path(p).suffix] = Path(p).read_text()
    return text


def _numbers(s: str) -> list[float]:
    return [float(x) for x in re.findall(r"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?", s)]


# the KR 6's flange at home, in its base frame (the robot stands at (1, 2, 0) in the
# cell: the files must not show that): 390 mm ahead, 670 mm up, pointing down
FLANGE_MM = (390.0, 0.0, 670.0)


def test_urscript_units(files: dict[str, str]) -> None:
    s = files[".script"]
    q = re.search(r"movej\(\[([^\]]*)\]", s).group(1)  # rad
    assert np.allclose(_numbers(q), np.radians(HOME_DEG), atol=1e-9)
    m = re.search(r"movel\(p\[([^\]]*)\], a=([\d.]+), v=([\d.]+), r=([\d.]+)\)", s)
    x, y, z, rx, ry, rz = _numbers(m.group(1))  # m and a rotation vector (rad)
    assert (x, y, z) == pytest.approx((0.49, 0.0, 0.67), abs=1e-9)
    assert math.hypot(rx, ry, rz) == pytest.approx(math.pi, abs=1e-9)  # a half turn
    # the override (50 %) is applied: v x 0.5 (m/s), a x 0.25 (m/s^2); r is the zone (m)
    assert float(m.group(3)) == pytest.approx(0.125)
    assert float(m.group(2)) == pytest.approx(0.2)
    assert float(m.group(4)) == pytest.approx(0.01)
    assert "sleep(0.5)" in s


def test_krl_units(files: dict[str, str]) -> None:
    src, dat = files[".src"], files[".dat"]
    axis = re.search(r"DECL E6AXIS XP\d+=\{([^}]*)\}", dat).group(1)  # deg
    assert np.allclose([float(v) for v in re.findall(r"A\d (-?[\d.]+)", axis)], HOME_DEG)
    pos = re.search(
        r"DECL E6POS XP\d+=\{X ([-\d.]+),Y ([-\d.]+),Z ([-\d.]+),A ([-\d.]+),B ([-\d.]+),C ([-\d.]+)",
        dat,
    )
    x, y, z, a, b, c = (float(v) for v in pos.groups())
    assert (x, y, z) == pytest.approx((FLANGE_MM[0] + 100.0, 0.0, FLANGE_MM[2]), abs=1e-6)  # mm
    assert (a, b, c) == pytest.approx((0.0, 90.0, 0.0), abs=1e-6)  # deg, KUKA's flange
    assert "$VEL.CP = 0.25" in src  # m/s (the override is $OV_PRO)
    assert "$ACC.CP = 0.8" in src  # m/s^2
    assert "$APO.CDIS = 10.000000" in src  # mm
    assert "$OV_PRO = 50" in src  # %
    assert "WAIT SEC 0.5" in src  # s


def test_rapid_units(files: dict[str, str]) -> None:
    s = files[".mod"]
    j = re.search(r"CONST jointtarget j\d+ := \[\[([^\]]*)\]", s).group(1)  # deg
    assert np.allclose(_numbers(j), HOME_DEG, atol=1e-9)
    p = re.search(r"CONST robtarget p\d+ := \[\[([^\]]*)\],\[([^\]]*)\],\[([^\]]*)\]", s)
    assert _numbers(p.group(1)) == pytest.approx([490.0, 0.0, 670.0], abs=1e-6)  # mm
    w, qx, qy, qz = _numbers(p.group(2))  # quaternion w, x, y, z: half a turn about y
    assert (w, qx, abs(qy), qz) == pytest.approx((0.0, 0.0, 1.0, 0.0), abs=1e-9)
    assert re.search(r"speeddata v_\d+ := \[250\.0+,", s)  # mm/s
    assert "z10," in s  # the predefined 10 mm zone
    assert "PathAccLim TRUE \\AccMax:=0.8" in s  # m/s^2
    assert "VelSet 50, 5000;" in s  # %
    assert "WaitTime 0.5;" in s


def test_fanuc_units(files: dict[str, str]) -> None:
    s = files[".ls"]
    assert "OVERRIDE=50%" in s
    # mm/sec, a 10 mm zone, 0.8 / 1.2 m/s^2 = 67 % (a whole number: the header says so)
    assert re.search(r"L P\[\d+\] 250mm/sec CNT10 ACC67 ;", s)
    assert "rounded" in s  # the header says a number was rounded
    assert "WAIT 0.5(sec)" in s
    j = re.search(r"J1= ([-\d.]+) deg,\s*J2= ([-\d.]+) deg,\s*J3= ([-\d.]+) deg", s)
    assert [float(v) for v in j.groups()] == pytest.approx(
        [0.0, -90.0, 90.0]
    )  # no coupling: a KUKA
    x = re.search(r"X = ([-\d.]+)  mm,\tY = ([-\d.]+)  mm,\tZ = ([-\d.]+)  mm", s)
    assert [float(v) for v in x.groups()] == pytest.approx([490.0, 0.0, 670.0], abs=1e-6)
    w = re.search(r"W = ([-\d.]+) deg,\tP = ([-\d.]+) deg,\tR = ([-\d.]+) deg", s)
    W, P, R = (math.radians(float(v)) for v in w.groups())
    # W, P, R about the fixed X, Y, Z: R = Rz(R) Ry(P) Rx(W) must turn z to straight down
    z_axis = np.array(
        [
            math.cos(R) * math.sin(P) * math.cos(W) + math.sin(R) * math.sin(W),
            math.sin(R) * math.sin(P) * math.cos(W) - math.cos(R) * math.sin(W),
            math.cos(P) * math.cos(W),
        ]
    )
    assert np.allclose(z_axis, [0, 0, -1], atol=1e-9)


def test_signals_number_the_outputs(tmp_path: Path) -> None:
    cell = Workcell("io")
    cell.add_robot("kr6", "kuka_kr6_r700", gripper=True)
    sim = Simulator(cell, profile="jerk", check_collisions=False)
    sim.open_gripper("kr6")
    krl = export(sim, "kr6", tmp_path / "io.src", signals={"gripper": 7})[0]
    text = Path(krl).read_text()
    assert "; I/O: output 7 = gripper" in text
    assert "$OUT[7] = FALSE" in text
    ur = Path(export(sim, "kr6", tmp_path / "io.script")[0]).read_text()
    assert "set_standard_digital_out(1, False)" in ur  # numbered from 1 without signals
