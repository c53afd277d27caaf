"""A helper for tests of things that must not block: run a call in a thread that must end."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any


def outcome(fn: Callable[[], Any], seconds: float = 10.0) -> BaseException | None:
    """What ``fn`` raised (None when it returned), from a daemon thread that must finish
    within ``seconds`` (the test fails with "blocked" otherwise)."""
    out: list[BaseException | None] = [None]

    def run() -> None:
        try:
            fn()
        except BaseException as exc:  # handed back to the test
            out[0] = exc

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(seconds)
    assert not t.is_alive(), "blocked"
    return out[0]
