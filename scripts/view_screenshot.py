"""The README's picture of the live view: the pick-and-place cell after its program, in
Chromium (Debian's, software WebGL), taken by the project's own page.

Usage: python scripts/view_screenshot.py [--out docs/live_view.png] [--width 1280]
(the picture is halved: 640 px wide by default).
"""

from __future__ import annotations

import argparse
import io
import time

from PIL import Image
from playwright.sync_api import sync_playwright

from workcell.examples import thesis_pick_place
from workcell.sim import Simulator
from workcell.view import Viewer
from workcell.view.headless import CHROMIUM, CHROMIUM_ARGS


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="docs/live_view.png")
    ap.add_argument("--width", type=int, default=1280)
    a = ap.parse_args()
    w, h = a.width, a.width * 5 // 8
    sim = Simulator(thesis_pick_place.build())
    with Viewer(sim, speed=None) as v, sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": w, "height": h})
        page.goto(v.url)
        while v.clients == 0:
            page.wait_for_timeout(100)
        thesis_pick_place.program(sim)
        v.program.teach("puma")
        time.sleep(1.0)
        page.get_by_text("Cycle time", exact=True).click()
        for close in page.locator(".mantine-CloseButton-root").all():  # the notices
            close.click(timeout=2000)
        page.wait_for_timeout(4000)
        shot = Image.open(io.BytesIO(page.screenshot())).convert("RGB")
        browser.close()
    shot = shot.resize((w // 2, h // 2), Image.LANCZOS)
    shot.quantize(colors=128, method=Image.Quantize.MEDIANCUT).save(a.out, optimize=True)
    print(f"picture written to {a.out}")


if __name__ == "__main__":
    main()
