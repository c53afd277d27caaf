"""Driving the live view from a headless browser: the browser tests,
``scripts/bench_view.py`` and ``scripts/view_screenshot.py`` share these.

The browser is Debian's chromium (``make test`` installs it; ``WORKCELL_CHROMIUM`` names
another), drawing WebGL in software (SwiftShader). :data:`WATCH_FRAMES` is a page script
that records, every 5 ms, each new frame the page's status line shows, as
``window.__seen`` = [[t (s), frame, performance.now() (ms)], ...]; ``clearInterval
(window.__watch)`` stops it.
"""

from __future__ import annotations

import os

__all__ = ["CHROMIUM", "CHROMIUM_ARGS", "WATCH_FRAMES"]

CHROMIUM = os.environ.get("WORKCELL_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = ["--no-sandbox", "--use-gl=angle", "--use-angle=swiftshader",
                 "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"]  # fmt: skip
WATCH_FRAMES = """() => {
  window.__seen = [];
  const read = () => {
    const m = document.body.innerText.match(/t = ([0-9.]+) s · frame (\\d+)/);
    const last = window.__seen[window.__seen.length - 1];
    if (m && (!last || last[1] !== +m[2])) window.__seen.push([+m[1], +m[2], performance.now()]);
  };
  window.__watch = setInterval(read, 5);
}"""
