"""The overview camera sees every part (none hidden behind a robot), and parts are drawn in
their kind's palette, not grey. Visibility is measured with MuJoCo's own segmentation
rendering (which geom covers each pixel), independently of the camera's ray tests."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from workcell import Workcell, compile_cell, solids, spatial
from workcell.cell.workcell import MOVABLE_COLOURS, STATIC_COLOURS
from workcell.record.camera import overview_camera
from workcell.record.render import render_cell

W, H = 320, 240


def hiding_cell() -> Workcell:
    """A 30 mm cube just behind the robot's pedestal as seen from the default azimuth
    (60 deg, across the table's longer x side); no colours given anywhere."""
    cell = Workcell("hide")
    solids.box(cell.model, "table", size=(0.8, 0.6, 0.4))
    solids.box(cell.model, "stage", size=(0.1, 0.1, 0.05))
    solids.cube(cell.model, "cube", size=0.03)
    cell.add_static("table", "table", spatial.translation(-0.4, -0.3, 0.0))
    cell.add_static("stage", "stage", spatial.translation(-0.3, -0.2, 0.4))
    c = 0.17 * np.array([math.cos(math.radians(60)), math.sin(math.radians(60))])
    cell.add_movable(
        "part", "cube", spatial.translation(c[0] - 0.015, c[1] - 0.015, 0.4), density=2700.0
    )
    cell.add_movable("other", "cube", spatial.translation(0.25, -0.2, 0.4), density=2700.0)
    cell.add_robot("r", "puma260", gripper=True, base=spatial.translation(0, 0, 0.4))
    return cell


def segmentation(model: mujoco.MjModel, data: mujoco.MjData, cam: mujoco.MjvCamera) -> np.ndarray:
    """Geom id per pixel (-1: none), from MuJoCo's segmentation renderer."""
    with mujoco.Renderer(model, H, W) as r:
        r.update_scene(data, camera=cam)
        r.enable_segmentation_rendering()
        seg = r.render()
    return np.where(seg[..., 1] == mujoco.mjtObj.mjOBJ_GEOM, seg[..., 0], -1)


def body_pixels(model: mujoco.MjModel, seg: np.ndarray, body: str) -> np.ndarray:
    ids = [g for g in range(model.ngeom) if model.body(model.geom_bodyid[g]).name == body]
    return np.isin(seg, ids)


@pytest.fixture(scope="module")
def hidden():
    cell = hiding_cell()
    model = compile_cell(cell).model
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return cell, model, data


def test_the_default_view_would_hide_the_part(hidden):
    _, model, data = hidden
    cam = overview_camera(model, width=W, height=H, azimuth=60.0)
    assert body_pixels(model, segmentation(model, data, cam), "part").sum() == 0


def test_the_overview_camera_turns_until_no_part_is_hidden(hidden):
    _, model, data = hidden
    cam = overview_camera(model, width=W, height=H)
    assert cam.azimuth != 60.0
    seg = segmentation(model, data, cam)
    for part in ("part", "other"):
        assert body_pixels(model, seg, part).sum() >= 20, part
    table = [g for g in range(model.ngeom) if model.geom(g).name.startswith("table.visual")]
    assert np.isin(seg, table).sum() > 0.1 * W * H  # and it still frames the cell


def test_parts_get_their_kinds_palette_colour_by_colour(hidden):
    cell, _, _ = hidden
    assert cell.static_parts["table"].colour == STATIC_COLOURS[0]
    assert cell.static_parts["stage"].colour == STATIC_COLOURS[1]
    assert cell.movable_parts["part"].colour == MOVABLE_COLOURS[0]
    assert cell.movable_parts["other"].colour == MOVABLE_COLOURS[1]
    assert not set(STATIC_COLOURS) & set(MOVABLE_COLOURS)
    assert len(set(STATIC_COLOURS)) == len(STATIC_COLOURS)
    assert len(set(MOVABLE_COLOURS)) == len(MOVABLE_COLOURS)
    # a colour given, or the entity's own, wins over the palette; a saved cell keeps them
    cell2 = Workcell("given", model=cell.model)
    cell2.add_movable("p", "cube", density=1000.0, colour=(0.1, 0.2, 0.3))
    assert cell2.movable_parts["p"].colour[:3] == (0.1, 0.2, 0.3)
    assert Workcell.from_dict(cell.to_dict()).movable_parts["other"].colour == MOVABLE_COLOURS[1]


def test_a_cell_without_colours_is_not_grey_in_the_picture(hidden):
    _, model, data = hidden
    cam = overview_camera(model, width=W, height=H)
    img = render_cell(hiding_cell(), width=W, height=H).astype(float)
    seg = segmentation(model, data, cam)
    for body, rgba in (("part", MOVABLE_COLOURS[0]), ("other", MOVABLE_COLOURS[1])):
        mean = img[body_pixels(model, seg, body)].mean(axis=0)
        hue = np.argmax(rgba[:3])
        assert np.argmax(mean) == hue, (body, mean)  # red shows red, green green
        assert mean.max() - mean.min() > 40, (body, mean)  # saturated, not grey
