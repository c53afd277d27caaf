"""The live view in a real browser (Chromium driving viser's page): it draws the cell
where MuJoCo's own renderer does, jogging by input and by gizmo, a run's frames,
collisions in red, Teach and Run, and the token."""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np
import pytest
from viewpage import open_view, panel_left, quiet_scene, screenshot

from workcell.examples import thesis_handoff, thesis_pick_place
from workcell.sim import Simulator
from workcell.view import Viewer
from workcell.view.cameras import View, apply_view
from workcell.view.headless import WATCH_FRAMES

pytestmark = pytest.mark.browser

MJ_W, MJ_H = 640, 400  # MuJoCo's offscreen buffer holds 640 x 480: half the page's size
GREY = 30  # chroma (max - min of 0..255 RGB) under which a pixel is "grey": the robots'
# links and bases are grey (MuJoCo colours of chroma <= 0.06 x 255); tables (wood),
# fingers (orange) and the green background are far above it under any shading


def mujoco_labels(sim: Simulator, view: View) -> np.ndarray:
    """MuJoCo's segmentation picture (geom id per pixel, -1: nothing) for ``view``."""
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    fwd = view.look_at - view.eye
    dist = float(np.linalg.norm(fwd))
    cam.lookat[:] = view.look_at
    cam.distance = dist
    cam.azimuth = math.degrees(math.atan2(fwd[1], fwd[0]))
    cam.elevation = math.degrees(math.asin(fwd[2] / dist))
    assert sim.model.vis.global_.fovy == pytest.approx(math.degrees(view.fov))
    with mujoco.Renderer(sim.model, MJ_H, MJ_W) as r:
        r.enable_segmentation_rendering()
        r.update_scene(sim.data, cam)
        seg = r.render()
    ids, kinds = seg[..., 0], seg[..., 1]
    return np.where(kinds == int(mujoco.mjtObj.mjOBJ_GEOM), ids, -1)


def test_page_draws_the_cell_where_mujoco_does(page):
    """The page's grey (robot) pixels lie where MuJoCo's render of the same camera has the
    robots' grey geoms (its segmentation picture), and vice versa, within 1 px of the
    picture halved to MuJoCo's size: 99 % of either within 1 px of the other."""
    sim = Simulator(thesis_handoff.build())
    with Viewer(sim, speed=None) as v:
        open_view(page, v)
        quiet_scene(v)
        v.server.scene.set_background_image(np.full((8, 8, 3), (0, 200, 0), np.uint8))
        page.wait_for_timeout(2500)  # the background and hidden nodes reach the picture
        shot = screenshot(page)
        right = panel_left(page)
        view = v._views["overview"]
    from PIL import Image

    small = Image.fromarray(shot.astype(np.uint8)).resize((MJ_W, MJ_H), Image.BILINEAR)
    half = np.asarray(small).astype(int)
    chroma = half.max(axis=2) - half.min(axis=2)
    page_grey = chroma < GREY
    labels = mujoco_labels(sim, view)
    m = sim.model
    rgba = np.array([m.geom_rgba[g] for g in range(m.ngeom)])
    grey_geom = (rgba[:, :3].max(axis=1) - rgba[:, :3].min(axis=1)) < GREY / 255
    robot_geom = np.array([sim.contacts.robot_of(sim.contacts.labels[g]) is not None
                           for g in range(m.ngeom)])  # fmt: skip
    mj_robot = np.where(labels >= 0, robot_geom[labels.clip(0)] & grey_geom[labels.clip(0)], False)
    other_grey = np.where(
        labels >= 0, ~robot_geom[labels.clip(0)] & grey_geom[labels.clip(0)], False
    )
    # compare left of the control panel and below the software-WebGL notice
    region = np.zeros_like(page_grey)
    region[:, : right // 2 - 12] = True
    region[:80, :165] = False
    region &= ~_dilate(other_grey, 3)  # the grey sphere: not a robot's colour, left out
    assert mj_robot[region].sum() > 2000  # the robots are well in view
    # within 1 px of the halved picture (2 px of the page): edges differ by antialiasing
    # and the halving; measured 0.9995 / 0.9971 at 0 px and 1.0 / 1.0 at 1 px
    recall = (mj_robot & _dilate(page_grey, 1) & region).sum() / (mj_robot & region).sum()
    precision = (page_grey & _dilate(mj_robot, 1) & region).sum() / (page_grey & region).sum()
    assert recall > 0.99, recall
    assert precision > 0.99, precision


def _dilate(mask: np.ndarray, r: int) -> np.ndarray:
    out = mask.copy()
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            out |= np.roll(np.roll(mask, dy, axis=0), dx, axis=1)
    return out


def _pick_place_view(page, speed=None):
    sim = Simulator(thesis_pick_place.build())
    v = Viewer(sim, speed=speed)
    open_view(page, v)
    return sim, v


def _until(cond, timeout=15.0, page=None):
    t0 = time.perf_counter()
    while not cond():
        if time.perf_counter() - t0 > timeout:
            return False
        (page.wait_for_timeout(50) if page is not None else time.sleep(0.05))
    return True


def test_typing_a_joint_value_moves_the_simulator_and_the_page(page):
    sim, v = _pick_place_view(page)
    with v:
        right = panel_left(page)
        before = screenshot(page)[:, :right].astype(int)
        q0 = sim.joints("puma")
        box = page.get_by_label("puma j1", exact=True)
        box.fill("40")
        box.press("Enter")
        assert _until(lambda: abs(sim.joints("puma")[0] - math.radians(40)) < 1e-12, page=page)
        np.testing.assert_allclose(sim.joints("puma")[1:], q0[1:], atol=0)
        assert sim.events[-1].kind == "jog"
        page.wait_for_timeout(1000)
        after = screenshot(page)[:, :right].astype(int)
        changed = (np.abs(after - before).sum(axis=2) > 60).sum()
        assert changed > 2000, changed  # the arm turned 40 deg about its base on the page
        box.fill("170")  # outside -160 ... 160: refused, nothing moves
        box.press("Enter")
        page.wait_for_timeout(1500)
        assert sim.joints("puma")[0] == pytest.approx(math.radians(40), abs=1e-12)


def _project(view: View, p: np.ndarray, w: int, h: int) -> tuple[float, float]:
    f = view.look_at - view.eye
    f = f / np.linalg.norm(f)
    r = np.cross(f, view.up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    d = p - view.eye
    k = (h / 2) / math.tan(view.fov / 2)
    return w / 2 + k * (d @ r) / (d @ f), h / 2 - k * (d @ u) / (d @ f)


def test_dragging_the_gizmo_moves_the_tool_by_ik(page):
    """After a drag of the tool gizmo's x arrow, the robot's joints put the tool (their
    FK, from the robot's own chain) at the gizmo's pose to 1e-6 m."""
    sim, v = _pick_place_view(page)
    with v:
        T0 = sim.tool_pose("puma")
        tool = T0[:3, 3]
        view = View(tool + np.array([0.25, -0.55, 0.25]), tool + np.array([0.12, 0.0, 0.0]),
                    np.array([0.0, 0.0, 1.0]), math.radians(45))  # fmt: skip
        apply_view(v.server, view, None)
        page.wait_for_timeout(1500)
        w, h = page.viewport_size["width"], page.viewport_size["height"]
        x_axis = T0[:3, 0]
        start = _project(view, tool + 0.12 * x_axis, w, h)
        end = _project(view, tool + 0.06 * x_axis, w, h)  # in: the arm is stretched
        assert start[0] < panel_left(page)
        page.mouse.move(*start)
        page.mouse.down()
        for s in np.linspace(0, 1, 8)[1:]:
            page.mouse.move(start[0] + s * (end[0] - start[0]), start[1] + s * (end[1] - start[1]))
            page.wait_for_timeout(60)
        page.mouse.up()
        assert _until(lambda: sim.events and sim.events[-1].kind == "jog", page=page)
        page.wait_for_timeout(1000)  # the drag's last IK
        g = v.jog.gizmos["puma"]
        from workcell.spatial import pose_from_pos_quat

        G = pose_from_pos_quat(g.position, g.wxyz)
        placement = sim.cell.robots["puma"]
        T = placement.base @ placement.robot.fk(sim.joints("puma"))
        np.testing.assert_allclose(T[:3, 3], G[:3, 3], atol=1e-6)
        np.testing.assert_allclose(T[:3, :3], G[:3, :3], atol=1e-6)
        assert np.linalg.norm(T[:3, 3] - tool) > 0.01  # it moved (along its x axis)
        assert abs((T[:3, 3] - tool) @ T0[:3, 1]) < 1e-3


def test_a_run_shows_its_frames_as_they_are_made(page):
    """At speed 1 a 2 s move is shown frame after frame on the page (many distinct
    frames, in order, with their simulated times) and takes about 2 s of wall time. (A
    small page: software WebGL paints a 1280 x 800 page about twice a second on this
    machine, a 400 x 300 one about ten times.)"""
    page.set_viewport_size({"width": 400, "height": 300})
    sim, v = _pick_place_view(page, speed=1.0)
    with v:
        page.evaluate(WATCH_FRAMES)
        q = sim.joints("puma") + np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.6])  # rad
        t0 = time.perf_counter()
        sim.move_joints_absolute("puma", q)  # 0.6 rad at 0.3 rad/s: 2 s
        wall = time.perf_counter() - t0
        last = sim.frames - 1
        shown = lambda: page.evaluate("() => window.__seen")[-1][1]  # noqa: E731
        assert _until(lambda: shown() == last, timeout=30, page=page), (shown(), last)
        seen = page.evaluate("() => window.__seen")
    assert sim.sim_time == pytest.approx(2.0, abs=1e-9)
    assert 1.9 < wall < 5.0, wall  # paced: never faster than real time (slower under load)
    frames = [f for _, f, _ in seen]
    assert frames == sorted(frames)
    assert len(frames) >= 4, frames  # the start, the end and frames between (a loaded
    # machine paints a software-rendered page a few times a second)
    times = sim.timeline.sim_times()
    for t, f, _ in seen:
        assert t == pytest.approx(times[f], abs=1e-3)


def test_a_collision_turns_the_part_red(page):
    from workcell.sim.grasp import tool_down
    from workcell.view.contacts import contacts

    sim = Simulator(thesis_handoff.build())
    with Viewer(sim, speed=None) as v:
        open_view(page, v)
        c = np.array(sim.part_positions()["sphere"])
        view = View(c + np.array([0.0, -0.45, 0.12]), c, np.array([0.0, 0.0, 1.0]),
                    math.radians(45))  # fmt: skip
        apply_view(v.server, view, None)
        for g in v.jog.gizmos.values():  # red x arrows of the gizmos and axes: away
            g.visible = False
        v.server.scene.add_frame("/axes", show_axes=False, visible=False)
        page.wait_for_timeout(1500)
        w, h = page.viewport_size["width"], page.viewport_size["height"]
        x, y = (round(a) for a in _project(view, c, w, h))
        red = lambda img: (img[..., 0] > 120) & (img[..., 0] > 3 * img[..., 1:].max(axis=-1))  # noqa: E731
        assert red(screenshot(page)[y - 4 : y + 5, x - 4 : x + 5]).mean() < 0.1
        assert v.jog.move_tool("puma_1", tool_down(c - [0.0, 0.0, 0.03]))  # palm into it
        assert "sphere" in {n for k in contacts(sim.contacts, sim.data) for n in (k.a, k.b)}
        page.wait_for_timeout(1500)
        patch = screenshot(page)[y - 4 : y + 5, x - 4 : x + 5]
        assert red(patch).mean() > 0.5
        assert "sphere" in v.scene.red
        assert "contact: " in page.inner_text("body")


def _input(page, label: str):
    """The input in the row of a label of the page."""
    return page.locator("label", has_text=label).first.locator("xpath=ancestor::div[2]//input")


def _type_joint(page, sim, label: str, k: int, deg: float) -> None:
    box = page.get_by_label(label, exact=True)
    box.fill(f"{deg}")
    box.press("Enter")
    assert _until(lambda: abs(sim.joints("puma")[k] - math.radians(deg)) < 1e-12, page=page)


def test_teach_then_run_reproduces_the_taught_poses(page, tmp_path):
    """Two poses taught on the page (a joint line, then a linear line), the robot jogged
    away, Run: the program's moves end at the taught joints (1e-9 rad) and the taught
    tool pose (1e-6 m); Save writes the program inside the root and nowhere else."""
    sim = Simulator(thesis_pick_place.build())
    with Viewer(sim, speed=None, root=tmp_path) as v:
        open_view(page, v)
        page.get_by_text("Program", exact=True).click()
        _type_joint(page, sim, "puma j1", 0, 30.0)
        _type_joint(page, sim, "puma j2", 1, 20.0)
        q1, T1 = sim.joints("puma"), sim.tool_pose("puma")
        page.get_by_role("button", name="Teach").click()
        assert _until(lambda: "move joints absolute puma" in v.program.text.value, page=page)
        _type_joint(page, sim, "puma j2", 1, 35.0)
        _type_joint(page, sim, "puma j3", 2, -100.0)
        T2 = sim.tool_pose("puma")
        page.get_by_label("teach as", exact=True).click()
        page.get_by_role("option", name="linear").click()
        assert _until(lambda: v.program.kind.value == "linear", page=page)
        page.get_by_role("button", name="Teach").click()
        assert _until(lambda: "move linear puma matrix" in v.program.text.value, page=page)
        _type_joint(page, sim, "puma j1", 0, -40.0)
        n_events = len(sim.events)
        page.get_by_role("button", name="Run").click()
        assert _until(lambda: v.program.state.content.startswith("done"), timeout=60, page=page)
        moves = [e for e in sim.events[n_events:] if e.kind == "move"]
        assert len(moves) == 2
        qa = sim.timeline.frame(moves[0].frame)[2][sim._qadr["puma"]]
        np.testing.assert_allclose(qa, q1, atol=1e-9)
        np.testing.assert_allclose(sim.tool_pose("puma")[:3, 3], T2[:3, 3], atol=1e-6)
        np.testing.assert_allclose(sim.tool_pose("puma")[:3, :3], T2[:3, :3], atol=1e-6)
        np.testing.assert_allclose(v.program.targets["p1"], T1, atol=1e-12)
        _input(page, "file").fill("../outside.wcl")
        page.get_by_role("button", name="Save").click()
        page.wait_for_timeout(1000)
        assert not (tmp_path.parent / "outside.wcl").exists()
        _input(page, "file").fill("cell/taught.wcl")
        (tmp_path / "cell").mkdir()
        page.get_by_role("button", name="Save").click()
        assert _until(lambda: (tmp_path / "cell" / "taught.wcl").exists(), page=page)
        assert (tmp_path / "cell" / "taught.wcl").read_text() == v.program.text.value


def test_the_page_needs_its_token(page):
    sim = Simulator(thesis_pick_place.build())
    with Viewer(sim, speed=None) as v:
        base = v.url.rsplit("/", 1)[0]
        response = page.goto(base + "/")
        assert response.status == 403
        assert "token" in page.inner_text("body")
        response = page.goto(base + "/" + "x" * len(v.guard.token))
        assert response.status == 403
        page.wait_for_timeout(500)
        assert v.clients == 0
