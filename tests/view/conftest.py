"""Browser fixtures for the live view's tests: one Chromium per test session (Debian's
``/usr/bin/chromium``, installed by ``make test`` when missing; never a downloaded
browser), a fresh page per test. Tests marked ``browser`` skip, saying why, only when
the browser is not there."""

from __future__ import annotations

import os
import time
from collections.abc import Iterator

import numpy as np
import pytest

CHROMIUM = os.environ.get("WORKCELL_CHROMIUM", "/usr/bin/chromium")
ARGS = ["--no-sandbox", "--use-gl=angle", "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"]  # fmt: skip
WIDTH, HEIGHT = 1280, 800


def pytest_collection_modifyitems(config, items):
    if os.path.exists(CHROMIUM):
        return
    skip = pytest.mark.skip(
        reason=f"no browser at {CHROMIUM}: 'make test' installs Debian's chromium "
        "(apt-get install -y chromium); it could not here"
    )
    for item in items:
        if "browser" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def browser() -> Iterator[object]:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


@pytest.fixture
def page(browser):
    context = browser.new_context(viewport={"width": WIDTH, "height": HEIGHT})
    pg = context.new_page()
    yield pg
    context.close()


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
