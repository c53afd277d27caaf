"""Helpers of the live view's browser tests (a module name of its own: ``conftest`` is
taken by the suite's root)."""

from __future__ import annotations

import time

import numpy as np

WIDTH, HEIGHT = 1280, 800


def open_view(page, viewer, timeout: float = 30.0) -> None:
    """Open the viewer's page and wait until it is connected and has drawn."""
    page.goto(viewer.url)
    t0 = time.perf_counter()
    while viewer.clients == 0:
        if time.perf_counter() - t0 > timeout:
            raise TimeoutError("the page did not connect")
        page.wait_for_timeout(100)
    page.wait_for_timeout(1500)


def quiet_scene(viewer) -> None:
    """Hide what MuJoCo's picture has not: floor, grid, axes, gizmos, paths, markers."""
    sc = viewer.server.scene
    for h in [*viewer.jog.gizmos.values(), *viewer.scene.paths.values()]:
        h.visible = False
    for name in ("/floor", "/axes", "/contacts"):
        sc.add_frame(name, show_axes=False, visible=False)


def screenshot(page) -> np.ndarray:
    """The page as an RGB array (HEIGHT, WIDTH, 3) of ints (no uint8 wrap-around)."""
    import io

    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("RGB")).astype(int)


def panel_left(page) -> int:
    """x (px) where the control panel begins: compare pictures left of it."""
    box = page.get_by_text("workcell", exact=True).first.bounding_box()
    return int(box["x"]) - 40 if box else WIDTH
