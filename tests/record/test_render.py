"""Offscreen pictures (workcell.record.render) and the ``render``/``info`` subcommands.

Independent references: pixel positions come from MuJoCo's own camera (the scene's GL
camera after ``mjv_updateScene``, or a named camera's pose and field of view) with a
pinhole model written here; command ends from the thesis program's joint targets; video
lengths from the thesis formula (eq. 4.27); joint limits from DESIGN.md's Puma 260 table.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest
from PIL import Image

from workcell import solids
from workcell.cell import Workcell, compile_cell
from workcell.errors import ModelError, WorkcellError
from workcell.examples import thesis_joints
from workcell.record import cli_render
from workcell.record.render import (
    CellRenderer,
    contact_sheet,
    overview_camera,
    render_cell,
    render_frame,
    save_mp4,
    save_png,
)
from workcell.sim.simulator import Simulator
from workcell.spatial import translation

W, H = 160, 120
ROOT = Path(__file__).resolve().parents[2]


def _two_puma_cell() -> Workcell:
    spec = importlib.util.spec_from_file_location(
        "_cell_helpers", ROOT / "tests" / "cell" / "cell_helpers.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.two_puma_cell()


@pytest.fixture(scope="module")
def ex1() -> Simulator:
    return thesis_joints.run("path", 0.05)


@pytest.fixture(scope="module")
def two() -> Workcell:
    return _two_puma_cell()


def _project(glcam: mujoco.MjvGLCamera, p: np.ndarray, width: int, height: int) -> tuple:
    """Pixel (column, row) of world point p for MuJoCo's GL camera (pinhole, OpenGL frustum)."""
    fwd, up = np.array(glcam.forward), np.array(glcam.up)
    right = np.cross(fwd, up)
    rel = np.asarray(p) - np.array(glcam.pos)
    depth = rel @ fwd
    half_h = glcam.frustum_top / glcam.frustum_near  # tan(fovy / 2)
    half_w = half_h * width / height
    x = (rel @ right) / depth / half_w
    y = (rel @ up) / depth / half_h
    return (1 + x) / 2 * width, (1 - y) / 2 * height


def _robot_geoms(model: mujoco.MjModel, prefix: str) -> np.ndarray:
    return np.array(
        [
            g
            for g in range(model.ngeom)
            if model.geom(g).name.startswith(prefix) and model.geom_group[g] == 2
        ]
    )


def _without_robots(cell: Workcell) -> Workcell:
    other = Workcell.from_dict(cell.to_dict())
    for name in list(other.robots):
        other.remove(name)
    return other


# ---------------------------------------------------------------------- pictures
def test_render_frame_shape_dtype_and_not_blank(ex1):
    img = render_frame(ex1, 0, width=W, height=H)
    assert img.shape == (H, W, 3)
    assert img.dtype == np.uint8
    assert img.std() > 20  # not a flat picture
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 50


def test_robot_visible_where_a_named_camera_projects_it(two):
    """Robot link centres, projected with the named camera's own pose and fovy, are drawn."""
    with_robot = render_cell(two, camera="overview", width=W, height=H)
    without = render_cell(_without_robots(two), camera="overview", width=W, height=H)
    model = compile_cell(two).model
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    cam = model.camera("overview").id
    R, c = data.cam_xmat[cam].reshape(3, 3), data.cam_xpos[cam]
    f = (H / 2) / math.tan(math.radians(model.cam_fovy[cam]) / 2)
    hits = []
    for g in _robot_geoms(model, "puma_1."):
        p = R.T @ (data.geom_xpos[g] - c)  # camera frame: looks along -z, y up
        u, v = W / 2 + f * p[0] / -p[2], H / 2 - f * p[1] / -p[2]
        assert 0 <= u < W
        assert 0 <= v < H
        hits.append(np.abs(with_robot[int(v), int(u)].astype(int) - without[int(v), int(u)]).sum())
    assert np.mean(np.array(hits) > 30) >= 0.8, hits


def test_overview_camera_frames_every_robot_without_clipping(two):
    model = compile_cell(two).model
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    cam = overview_camera(model, width=W, height=H)
    with CellRenderer(model, W, H) as r:
        img = r.render(data, cam)
        glcam = r.scene.camera[0]
    bare_model = compile_cell(_without_robots(two)).model
    bare_data = mujoco.MjData(bare_model)
    mujoco.mj_forward(bare_model, bare_data)
    with CellRenderer(bare_model, W, H) as r:
        bare = r.render(bare_data, cam)
    signs = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T
    for prefix in ("puma_1.", "puma_2."):
        boxes, centres = [], []
        for g in _robot_geoms(model, prefix):
            mid, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
            R, x = data.geom_xmat[g].reshape(3, 3), data.geom_xpos[g]
            boxes.append(np.array([_project(glcam, R @ (mid + s * half) + x, W, H) for s in signs]))
            centres.append(_project(glcam, x, W, H))
        uv = np.concatenate(boxes)
        assert uv.min() >= 0  # nothing clipped
        assert uv[:, 0].max() <= W
        assert uv[:, 1].max() <= H
        assert np.ptp(uv[:, 1]) > 0.3 * H  # not a speck
        # the centres of the links that cover some pixels show the robot, not the floor
        big = [c for b, c in zip(boxes, centres, strict=True) if np.ptp(b, axis=0).min() >= 6]
        assert len(big) >= 5
        differ = [
            np.abs(img[int(v), int(u)].astype(int) - bare[int(v), int(u)]).sum() > 30
            for u, v in big
        ]
        assert np.mean(differ) >= 0.9, differ


def test_render_cell_is_the_first_frame_and_frames_differ(two):
    sim = Simulator(two, dt=0.1)
    sim.move_joints_relative("puma_1", np.radians([40, 0, 0, 0, 0, 0]))
    first = render_frame(sim, 0, camera="overview", width=W, height=H)
    assert np.array_equal(first, render_cell(two, camera="overview", width=W, height=H))
    last = render_frame(sim, -1, camera="overview", width=W, height=H)
    assert (np.abs(first.astype(int) - last).sum(axis=2) > 30).sum() > 100


def test_unknown_camera_and_frame_are_refused(ex1):
    with pytest.raises(ModelError, match=r"no camera 'nope'.*cameras: none"):
        render_frame(ex1, camera="nope", width=W, height=H)
    with pytest.raises(ModelError, match="out of range"):
        render_frame(ex1, ex1.frames, width=W, height=H)


# ---------------------------------------------------------------------- contact sheet
def _tile_blocks(sheet: np.ndarray) -> list[tuple[int, int, int, int]]:
    """(x0, x1, y0, y1) of the rendered tiles: runs of non-white columns and of rows that
    are non-white across a whole column run (captions are mostly white)."""

    def runs(mask: np.ndarray) -> list[tuple[int, int]]:
        edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(int), 0]))
        return list(zip(edges[::2], edges[1::2], strict=True))

    nonwhite = (sheet < 250).any(axis=2)
    blocks = []
    for x0, x1 in runs(nonwhite.any(axis=0)):
        for y0, y1 in runs(nonwhite[:, x0:x1].mean(axis=1) > 0.9):
            blocks.append((x0, x1, y0, y1))
    return blocks


def test_contact_sheet_has_one_tile_per_command_end(ex1, tmp_path):
    out = tmp_path / "sheet.png"
    keys = contact_sheet(ex1, out, tile_width=W, tile_height=H, columns=3)
    sheet = np.asarray(Image.open(out).convert("RGB"))
    blocks = _tile_blocks(sheet)
    # thesis program: 3 moves (set_speed moves nothing), plus the initial state
    assert len(keys) == len(blocks) == 4
    assert all(x1 - x0 == W and y1 - y0 == H for x0, x1, y0, y1 in blocks)
    # the command ends are the frames where the joints reach the program's targets
    start = np.radians(thesis_joints.START_DEG)
    targets = [
        start + np.radians(thesis_joints.RELATIVE_DEG),
        np.radians(thesis_joints.ABSOLUTE_DEG),
        start,
    ]
    _, Q = ex1.trajectory(thesis_joints.ROBOT)
    ends = [0] + [int(np.flatnonzero(np.all(np.abs(Q - t) < 1e-12, axis=1))[-1]) for t in targets]
    assert [k.frame for k in keys] == ends
    blocks.sort(key=lambda b: (b[2], b[0]))  # row by row
    for (x0, x1, y0, y1), frame in zip(blocks, ends, strict=True):
        tile = sheet[y0:y1, x0:x1].astype(int)
        assert np.abs(tile - render_frame(ex1, frame, width=W, height=H)).mean() < 1.0
        caption = sheet[y1 : y1 + 20, x0:x1]
        assert (caption < 100).any()  # text was drawn under the tile
    assert "move_joints_relative" in keys[1].title


# ---------------------------------------------------------------------- video
def test_mp4_has_one_frame_per_sample_of_simulated_time(ex1, tmp_path):
    import av

    fps = 5
    out = tmp_path / "run.mp4"
    n = save_mp4(ex1, out, fps=fps, width=W, height=H)
    expected = math.ceil(thesis_joints.expected_sim_time() * fps) + 1  # 9.89 s -> 51
    with av.open(str(out)) as c:
        frames = [f.to_ndarray(format="rgb24") for f in c.decode(video=0)]
        rate = c.streams.video[0].average_rate
    assert n == len(frames) == expected == 51
    assert rate == fps
    assert frames[0].shape == (H, W, 3)
    first, last = render_frame(ex1, 0, width=W, height=H), render_frame(ex1, -1, width=W, height=H)
    assert np.abs(frames[0].astype(int) - first).mean() < 6  # lossy, but the same picture
    assert np.abs(frames[-1].astype(int) - last).mean() < 6
    middle = frames[len(frames) // 2].astype(int)
    assert np.abs(middle - first).mean() > 2 * np.abs(frames[-1].astype(int) - last).mean()
    assert [p.name for p in tmp_path.iterdir()] == ["run.mp4"]  # no temp file left


# ---------------------------------------------------------------------- files
def test_png_is_written_atomically(tmp_path, monkeypatch):
    import workcell.files as files

    out = tmp_path / "pic.png"
    out.write_bytes(b"old")
    img = np.zeros((4, 6, 3), np.uint8)
    img[1, 2] = (255, 0, 0)
    seen = []
    real = os.replace

    def replace(src, dst):  # the target still holds the old bytes until the rename
        seen.append((Path(src).parent, Path(dst).read_bytes()))
        real(src, dst)

    monkeypatch.setattr(files.os, "replace", replace)
    save_png(img, out)
    assert seen == [(tmp_path, b"old")]
    assert np.array_equal(np.asarray(Image.open(out)), img)
    assert [p.name for p in tmp_path.iterdir()] == ["pic.png"]
    with pytest.raises(WorkcellError, match="uint8"):
        save_png(img.astype(float), out)
    assert np.array_equal(np.asarray(Image.open(out)), img)


# ---------------------------------------------------------------------- backends
_PROBE = """
import os, sys
from workcell.errors import WorkcellError
from workcell.examples.thesis_joints import build
from workcell.record.render import gl_backend, render_cell
if len(sys.argv) > 1:
    os.environ["MUJOCO_GL"] = sys.argv[1]  # set after import mujoco
try:
    img = render_cell(build(), width=32, height=24)
    print("OK", gl_backend(), int(img.std() > 5))
except WorkcellError as exc:
    print("ERR", type(exc).__name__, exc)
"""


def _probe(env_changes: dict, *args: str) -> subprocess.Popen:
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    env.update(env_changes)
    return subprocess.Popen(
        [sys.executable, "-c", _PROBE, *args], env=env, cwd=ROOT, stdout=subprocess.PIPE, text=True
    )


def test_backend_errors_are_clear():
    """Each case in a fresh interpreter: the backend is chosen once per process."""
    procs = {
        "none works": _probe({"PYOPENGL_PLATFORM": "bogus"}),  # egl and osmesa both refuse
        "egl asked, broken": _probe({"MUJOCO_GL": "egl", "MUJOCO_EGL_DEVICE_ID": "99"}),
        "egl set after import": _probe({}, "egl"),
    }
    out = {k: p.communicate(timeout=120)[0].strip().splitlines()[-1] for k, p in procs.items()}
    msg = out["none works"]
    assert msg.startswith("ERR"), msg
    assert "tried egl, osmesa" in msg
    assert msg.count("PYOPENGL_PLATFORM") >= 2  # each attempt's own reason
    msg = out["egl asked, broken"]
    assert msg.startswith("ERR"), msg
    assert "MUJOCO_GL egl" in msg
    assert "MUJOCO_EGL_DEVICE_ID" in msg
    assert "osmesa:" not in msg  # no fallback from an explicit choice
    assert out["egl set after import"] == "OK egl 1"


def test_invalid_mujoco_gl_is_refused(ex1, monkeypatch):
    import workcell.record.render as render

    monkeypatch.setattr(render, "_backend", None)  # as before the first context
    monkeypatch.setenv("MUJOCO_GL", "bogus")
    with pytest.raises(WorkcellError, match=r"'bogus' is not a rendering backend; valid: egl"):
        render_frame(ex1, width=W, height=H)
    monkeypatch.setenv("MUJOCO_GL", "off")
    with pytest.raises(WorkcellError, match="disabled"):
        render_frame(ex1, width=W, height=H)


# ---------------------------------------------------------------------- CLI
@pytest.fixture(scope="module")
def cli() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="workcell")
    cli_render.register(parser.add_subparsers(dest="command", required=True))
    return parser


def _run(cli, argv: list[str]) -> int:
    args = cli.parse_args(argv)
    return args.func(args)


def test_cli_render_writes_the_png(cli, two, tmp_path, capsys):
    cell_file, out = tmp_path / "cell.json", tmp_path / "cell.png"
    two.save(cell_file)
    argv = ["render", str(cell_file), "--out", str(out), "--camera", "top"]
    assert _run(cli, [*argv, "--width", str(W), "--height", str(H)]) == 0
    assert str(out) in capsys.readouterr().out
    img = np.asarray(Image.open(out))
    assert img.shape == (H, W, 3)
    assert np.array_equal(img, render_cell(two, camera="top", width=W, height=H))


def test_cli_info_lists_limits_parts_cameras_and_reach(cli, tmp_path, capsys):
    cell = Workcell("reach")
    cell.add_robot("arm", "puma260", gripper=True)
    q_down = np.radians([0, 0, -90, 0, -90, 0])  # tool z axis straight down (checked below)
    T = cell.robots["arm"].tool_pose(q_down)
    assert np.allclose(T[:3, 2], [0, 0, -1], atol=1e-9)
    solids.cube(cell.model, "c", size=0.03)
    offset = cell.model.properties("c").centroid
    cell.add_movable("near", "c", translation(*(T[:3, 3] - offset)), density=1000.0)
    cell.add_movable("far", "c", translation(2.0, 0.0, 0.2), density=1000.0)
    cell.add_camera("cam", (1, -1, 1), (0, 0, 0.2), fovy=40)
    cell.save(tmp_path / "reach.json")
    assert _run(cli, ["info", str(tmp_path / "reach.json"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    (robot,) = info["robots"]
    limits = [(j["lower"], j["upper"]) for j in robot["joints"]]
    assert limits == [(-160, 160), (-76, 256), (-214, 34), (-194, 384), (-122, 122), (-267, 267)]
    assert [p["name"] for p in info["movable_parts"]] == ["near", "far"]
    assert info["movable_parts"][0]["mass_kg"] == pytest.approx(0.03**3 * 1000)
    assert [c["name"] for c in info["cameras"]] == ["cam"]
    reach = {r["part"]: r for r in info["reachability"]}
    assert reach["near"]["reachable"]
    assert reach["near"]["target"] == pytest.approx(T[:3, 3])
    assert not reach["far"]["reachable"]
    assert "out of reach" in reach["far"]["reason"]
    assert _run(cli, ["info", str(tmp_path / "reach.json")]) == 0
    text = capsys.readouterr().out
    assert "near" in text
    assert "NOT reachable" in text
    assert "-76.00" in text


def test_picture_functions_are_annotated_with_what_they_return(ex1, two):
    """help() and type checkers show what comes back: an ndarray of uint8, not an 'Image'."""
    import typing

    from workcell.record import render

    pictures = (
        (render_frame, render_frame(ex1, 0, width=64, height=48)),
        (render_cell, render_cell(two, width=64, height=48)),
    )
    for fn, value in pictures:
        text = fn.__annotations__["return"]  # what help() shows
        assert text.startswith("NDArray["), (fn.__name__, text)
        hint = eval(text, vars(render))
        assert typing.get_origin(hint) is np.ndarray, (fn.__name__, hint)
        assert isinstance(value, np.ndarray)
        assert value.dtype == np.uint8
        assert value.shape == (48, 64, 3)
