"""Browser fixtures for the live view's tests: one Chromium per test session (Debian's
``/usr/bin/chromium``, installed by ``make test`` when missing; never a downloaded
browser), a fresh page per test. Tests marked ``browser`` skip, saying why, only when
the browser is not there."""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest
from viewpage import HEIGHT, WIDTH

from workcell.view.headless import CHROMIUM, CHROMIUM_ARGS


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
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield b
        b.close()


@pytest.fixture
def page(browser):
    context = browser.new_context(viewport={"width": WIDTH, "height": HEIGHT})
    pg = context.new_page()
    yield pg
    context.close()
