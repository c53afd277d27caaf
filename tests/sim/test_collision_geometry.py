"""Collision geometry of non-convex parts in the simulator, ``workcell info`` and pictures.

References: the bin's walls and floor are boxes of known size (a resting part touches at
depth 0, a part through a wall overlaps by the wall's thickness); MuJoCo's own
collision check of the convex hull gives the answer the decomposition must avoid.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from workcell import Workcell, solids, spatial
from workcell.cell import compile_cell
from workcell.cli import main
from workcell.meshgeoms import collision_pieces
from workcell.sim import Simulator

WALL = 0.01  # m


def bin_cell(part_at: tuple[float, float, float]) -> Workcell:
    """A 200 x 150 x 100 mm bin (10 mm walls) at x = 0.3 and a 40 mm cube at ``part_at``."""
    cell = Workcell("bin_cell")
    m = cell.model
    solids.box(m, "outer", size=(0.2, 0.15, 0.1))
    solids.box(m, "inner", size=(0.2 - 2 * WALL, 0.15 - 2 * WALL, 0.1))
    solids.difference(
        m, "bin", "outer", "inner", transforms=[None, spatial.translation(WALL, WALL, WALL)]
    )
    solids.cube(m, "cube", size=0.04)
    cell.add_static("bin_1", "bin", spatial.translation(0.3, 0.0, 0.0))
    cell.add_movable("part", "cube", spatial.translation(*part_at), density=1000.0)
    cell.add_camera("top", (0.4, -0.4, 0.6), (0.4, 0.075, 0.0))
    return cell


def collisions(sim: Simulator) -> list[str]:
    return [e.detail for e in sim.events if e.kind == "collision"]


def test_a_bin_holds_a_part_and_its_wall_stops_one():
    resting = Simulator(bin_cell((0.38, 0.05, WALL)))  # on the inner floor
    assert collisions(resting) == []
    assert resting.clearance("part", "bin_1") == pytest.approx(0.0, abs=2e-5)  # touching
    # the convex hull (MuJoCo's default for one mesh) would have swallowed the part
    hull = resting.cell.model.world_mesh(("block", "bin")).convex_hull
    centre = np.array([[0.08 + 0.02, 0.05 + 0.02, WALL + 0.02]])  # in the bin's frame
    assert hull.contains(centre)[0]
    # pushed through the wall at x = 0.30..0.31 (cube x = 0.28..0.32): it must move back
    # 20 mm to come free (the penetration depth)
    through = Simulator(bin_cell((0.3 - 0.02, 0.05, 0.03)))
    assert collisions(through) == ["bin_1 with part: depth 20 mm"]
    assert through.clearance("part", "bin_1") == pytest.approx(-0.02, abs=1e-4)


def test_a_cell_compiles_from_the_cache_the_second_time(monkeypatch):
    cell = bin_cell((0.38, 0.05, WALL))
    first = compile_cell(cell)

    def no_coacd(*args, **kwargs):
        raise AssertionError("CoACD ran again")

    monkeypatch.setattr("workcell.native.run", no_coacd)
    again = compile_cell(cell)
    n = len(collision_pieces(cell.model, "bin").pieces)
    for cc in (first, again):
        names = [cc.model.geom(g).name for g in range(cc.model.ngeom)]
        assert sum(s.startswith("bin_1.col") for s in names) == n > 1


def test_info_and_picture_show_the_collision_pieces(tmp_path, capsys):
    cell = bin_cell((0.38, 0.05, WALL))
    path = tmp_path / "bin.json"
    cell.save(path)
    n = len(collision_pieces(cell.model, "bin").pieces)
    assert main(["info", str(path)]) == 0
    text = capsys.readouterr().out
    assert f"bin_1: block 'bin' at (0.300, 0.000, 0.000) m; collides as {n} CoACD pieces" in text
    assert "part: block 'cube'" in text
    assert "collides as convex, its own piece" in text
    assert main(["info", str(path), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    col = info["static_parts"][0]["collision"]
    assert (col["method"], col["pieces"], col["concavity"]) == ("coacd", n, 0.05)
    assert 0 <= col["volume_excess"] < 0.01
    pngs = {}
    for flag in ([], ["--collision"]):
        out = tmp_path / f"bin{len(flag)}.png"
        assert main(["render", str(path), "--out", str(out), "--camera", "top", *flag]) == 0
        pngs[bool(flag)] = np.asarray(Image.open(out).convert("RGB"), dtype=float)
    assert "collision pieces" in capsys.readouterr().out

    # the pieces are drawn in several strong colours where the visual picture is grey
    def colours(img: np.ndarray) -> int:
        strong = img[(img.max(axis=2) - img.min(axis=2)) > 80]
        return len({tuple(c) for c in (strong // 64).astype(int)})

    assert colours(pngs[True]) >= 4 > colours(pngs[False])
