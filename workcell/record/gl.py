"""The OpenGL backend for offscreen rendering: which one, and a context on it.

MuJoCo renders through an OpenGL context made by one of three backends: ``egl``
(headless, GPU or Mesa), ``osmesa`` (software) or ``glfw`` (a window system). The
backend is ``MUJOCO_GL`` when set; otherwise EGL is tried, then OSMesa; when none works a
:class:`~workcell.errors.RenderError` says what each attempt gave. It is picked when a
context is created, not when ``mujoco`` is imported: :func:`open_context` makes contexts
itself (``mujoco.Renderer`` binds the backend at ``import mujoco``, so setting
``MUJOCO_GL`` afterwards has no effect on it).

This module keeps no state: the caller passes the backend that worked before (``known``)
so that a process keeps one backend once it has one (:mod:`workcell.record.render` does).
"""

from __future__ import annotations

import contextlib
import os
import sys
from typing import Any

import mujoco

from workcell.errors import RenderError

__all__ = ["BACKENDS", "candidates", "free_context", "open_context"]

BACKENDS = ("egl", "osmesa", "glfw")
_OFF = ("disable", "disabled", "off", "false", "0")
_AUTO = ("", "enable", "enabled", "on", "true", "1")


def candidates(known: str | None = None) -> list[str]:
    """The backends to try, in order: ``[known]`` when one already works, else from ``MUJOCO_GL``.

    Unset (or "on"): EGL, then OSMesa. A backend name: only that one. RenderError when
    ``MUJOCO_GL`` disables rendering or names no backend (the message lists the valid ones).
    """
    if known is not None:
        return [known]
    asked = os.environ.get("MUJOCO_GL", "").strip().lower()
    if asked in _OFF:
        raise RenderError(f"rendering is disabled by MUJOCO_GL={asked!r}; unset it or use egl")
    if asked in _AUTO:
        return ["egl", "osmesa"]
    if asked in (*BACKENDS, "glx"):
        return [asked]
    raise RenderError(
        f"MUJOCO_GL={asked!r} is not a rendering backend; valid: {', '.join(BACKENDS)}"
    )


def _forget_pyopengl(platform_before: str | None) -> None:
    """Unload PyOpenGL (its platform is fixed at import) so another backend can load it."""
    for name in [n for n in sys.modules if n == "OpenGL" or n.startswith("OpenGL.")]:
        del sys.modules[name]
    for name in ("mujoco.egl", "mujoco.egl.egl_ext", "mujoco.osmesa"):
        sys.modules.pop(name, None)
    if platform_before is None:
        os.environ.pop("PYOPENGL_PLATFORM", None)
    else:
        os.environ["PYOPENGL_PLATFORM"] = platform_before


def _context_class(name: str) -> Any:
    if name == "egl":
        from mujoco.egl import GLContext
    elif name == "osmesa":
        from mujoco.osmesa import GLContext
    else:
        from mujoco.glfw import GLContext
    return GLContext


def open_context(
    model: mujoco.MjModel, width: int, height: int, known: str | None = None
) -> tuple[Any, mujoco.MjrContext, str]:
    """A current GL context of ``width`` x ``height`` pixels and an offscreen MjrContext.

    Tries the backends of :func:`candidates` (``known``: the one that worked before in this
    process, the only one tried then) and returns ``(gl_context, mjr_context, backend)``.
    Free them with ``mjr_context.free()`` and :func:`free_context`. RenderError listing
    each attempt's failure when none works.
    """
    names = candidates(known)
    failures = []
    for name in names:
        loaded = "OpenGL" in sys.modules
        platform = os.environ.get("PYOPENGL_PLATFORM")
        gl = None
        try:
            gl = _context_class(name)(width, height)
            gl.make_current()
            mjr = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
        except Exception as exc:  # ImportError, RuntimeError, mujoco.FatalError, GLError ...
            failures.append(f"{name}: {type(exc).__name__}: {str(exc).strip().rstrip('.')}")
            if gl is not None:
                free_context(gl)
            if not loaded and known is None:
                _forget_pyopengl(platform)
            continue
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, mjr)
        return gl, mjr, name
    how = "MUJOCO_GL" if len(names) == 1 else "no MUJOCO_GL set; tried"
    raise RenderError(
        f"no OpenGL backend works for offscreen rendering ({how} {', '.join(names)}): "
        + "; ".join(failures)
        + ". On Linux install libegl1 and libegl-mesa0 (egl) or libosmesa6 (osmesa), leave "
        "PYOPENGL_PLATFORM unset, and set MUJOCO_GL=egl or MUJOCO_GL=osmesa"
    )


def free_context(gl: Any) -> None:
    """Free a GL context from :func:`open_context`; errors of a half-made one are ignored."""
    with contextlib.suppress(Exception):
        gl.free()
