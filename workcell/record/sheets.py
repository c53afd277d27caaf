"""Key frames, contact sheets and MP4 videos of a simulator run.

A run's *key frames* are frame 0 and the end of each command (its events); a contact
sheet is a PNG grid of them, each tile captioned with its simulated time and command; an
MP4 shows the run in simulated time. Tiles and video frames are drawn by
:class:`~workcell.record.render.CellRenderer` with one camera for the whole run (a cell
camera by name, or :func:`~workcell.record.render.overview_camera` over the run). Sizes
are in pixels, times in seconds of simulated time. These names are also importable from
:mod:`workcell.record.render`.
"""

from __future__ import annotations

import itertools
import math
import os
import sys
from collections.abc import Iterator, Sequence
from fractions import Fraction
from typing import TYPE_CHECKING, Any, NamedTuple

import mujoco
import numpy as np
from numpy.typing import NDArray

from workcell import limits
from workcell.errors import RenderError
from workcell.files import atomic_path, check_writable
from workcell.record.render import CellRenderer, _camera_for, _frames_qpos, save_png

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = [
    "KEY_EVENT_KINDS",
    "KeyFrame",
    "contact_sheet",
    "key_frames",
    "rendered_frames",
    "save_mp4",
    "video_frames",
]

KEY_EVENT_KINDS = (
    "move", "grasp", "release", "wait", "open", "close", "line", "path", "collision", "error"
)  # fmt: skip


# ---------------------------------------------------------------------- contact sheet
class KeyFrame(NamedTuple):
    """A tile of a contact sheet: timeline ``frame``, its simulated time ``t`` (s), a
    ``title`` (robot and command: the first word of the event's detail, else its kind)
    and the rest of the event's ``detail``."""

    frame: int
    t: float
    title: str
    detail: str


def key_frames(sim: Simulator, kinds: Sequence[str] = KEY_EVENT_KINDS) -> list[KeyFrame]:
    """Frame 0 and the end of each command (events of ``kinds``), in order: by default
    also each collision (its first overlapping frame) and the error a run stopped on (the
    state the failing command found).

    An event maps to its ``frame`` (the last frame when it was recorded), exact in every
    mode, or, for events without one, to the last frame whose simulated time is at most
    the event's (1e-9 s).
    """
    times = sim.timeline.sim_times()
    out = [KeyFrame(0, float(times[0]), "initial state", "")]
    for e in sim.events:
        if e.kind not in kinds:
            continue
        i = getattr(e, "frame", -1)
        if i < 0:
            i = max(int(np.searchsorted(times, e.t + 1e-9, side="right")) - 1, 0)
        command, _, rest = e.detail.partition(" ")
        if e.kind == "error":  # "JointLimitError: message"
            kind, _, rest = e.detail.partition(": ")
            command = f"error: {kind}"
        elif e.kind == "collision" or not command.isidentifier():
            command, rest = e.kind, e.detail
        title = f"{e.robot}: {command}" if e.robot else command
        out.append(KeyFrame(i, float(times[i]), title, rest))
    return out


def _font(size: int) -> Any:
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: a fixed bitmap font
        return ImageFont.load_default()


def _fit(draw: Any, text: str, font: Any, width: float) -> str:
    """``text``'s first line, cut to ``width`` pixels with an ellipsis (a caption is one
    line: an error's message may go on with the line it quotes and a caret)."""
    lines = text.splitlines()
    text = lines[0] if lines else ""
    if draw.textlength(text, font=font) <= width:
        return text
    while text and draw.textlength(text + "…", font=font) > width:
        text = text[:-1]
    return text + "…"


def contact_sheet(
    sim: Simulator,
    path: str | os.PathLike,
    *,
    camera: str | None = None,
    tile_width: int = 320,
    tile_height: int = 240,
    columns: int | None = None,
    kinds: Sequence[str] = KEY_EVENT_KINDS,
) -> list[KeyFrame]:
    """Write a PNG grid of :func:`key_frames`, each tile captioned with its time and command.

    Tiles are ``tile_width`` x ``tile_height`` renders (one camera for all, see
    :func:`render_frame`) above a two-line caption; ``columns`` defaults to
    ceil(sqrt(n)). Returns the key frames in tile order (row by row).
    """
    from PIL import Image as PILImage
    from PIL import ImageDraw

    check_writable(path, error=RenderError)  # before the rendering
    keys = key_frames(sim, kinds)
    n = len(keys)
    cols = columns if columns else math.ceil(math.sqrt(n))
    if not (isinstance(cols, int) and cols >= 1):
        raise RenderError(f"columns must be an integer >= 1, got {columns!r}")
    rows = math.ceil(n / cols)
    fsize = max(9, tile_height // 18)
    cap_h, gap = 2 * fsize + 10, 4
    size = (cols * tile_width + (cols + 1) * gap, rows * (tile_height + cap_h) + (rows + 1) * gap)
    what = f"a contact sheet of {n:,} tiles of {tile_width} x {tile_height}"
    limits.check("max_images", n, what)  # before anything is rendered
    limits.check("max_pixels", size[0] * size[1], what)
    sheet = PILImage.new("RGB", size, "white")
    draw, font = ImageDraw.Draw(sheet), _font(fsize)
    cam = _camera_for(sim, camera, tile_width, tile_height)
    data = mujoco.MjData(sim.model)
    order = sorted(range(n), key=lambda k: keys[k].frame)
    qs = dict(zip(order, _frames_qpos(sim, [keys[k].frame for k in order]), strict=True))
    with CellRenderer(sim.model, tile_width, tile_height) as r:
        for k, key in enumerate(keys):
            data.qpos[:] = qs[k]
            mujoco.mj_forward(sim.model, data)
            x = gap + (k % cols) * (tile_width + gap)
            y = gap + (k // cols) * (tile_height + cap_h + gap)
            sheet.paste(PILImage.fromarray(r.render(data, cam)), (x, y))
            line1 = _fit(draw, f"{k}.  t = {key.t:.2f} s   {key.title}", font, tile_width - 6)
            line2 = _fit(draw, key.detail, font, tile_width - 6)
            draw.text((x + 3, y + tile_height + 3), line1, fill=(20, 20, 20), font=font)
            draw.text((x + 3, y + tile_height + 5 + fsize), line2, fill=(90, 90, 90), font=font)
    buf = np.asarray(sheet)
    save_png(buf, path)
    return keys


# ---------------------------------------------------------------------- video
def video_frames(sim: Simulator, fps: float) -> NDArray[np.intp]:
    """Timeline frame shown at each video frame: samples every 1/fps s of simulated time
    from 0 to the end (the last sample is the final frame), ceil(T fps) + 1 of them."""
    times = sim.timeline.sim_times()
    T = float(times[-1] - times[0])
    n = math.ceil(T * fps - 1e-9) + 1
    limits.check("max_images", n, f"{n:,} pictures: {T:.4g} s at {fps:g} per second")
    ts = np.minimum(times[0] + np.arange(n) / fps, times[-1])
    return np.maximum(np.searchsorted(times, ts + 1e-9, side="right") - 1, 0)


def save_mp4(
    sim: Simulator,
    path: str | os.PathLike,
    *,
    fps: float = 30.0,
    camera: str | None = None,
    width: int = 640,
    height: int = 480,
    crf: int = 20,
    progress: bool | None = None,
) -> int:
    """Write an H.264 MP4 of the run in simulated time (``fps`` samples per simulated s).

    ``width`` and ``height`` must be even (yuv420p). ``progress``: a tqdm bar on stderr
    (default: when stderr is a terminal). Written atomically. Returns the number of
    video frames, ``ceil(T * fps) + 1`` for a run of T simulated seconds.
    """
    import av
    from tqdm import tqdm

    if not (fps > 0 and math.isfinite(fps)):
        raise RenderError(f"fps must be a finite number > 0, got {fps!r}")
    if width % 2 or height % 2:
        raise RenderError(f"MP4 width and height must be even, got {width} x {height}")
    p = check_writable(path, error=RenderError)  # before the rendering
    idx = video_frames(sim, fps)
    show = sys.stderr.isatty() if progress is None else progress
    with (
        atomic_path(p, suffix=p.suffix, error=RenderError) as tmp,
        av.open(tmp, mode="w", format="mp4") as out,
    ):
        stream = out.add_stream("libx264", rate=Fraction(fps).limit_denominator(1000))
        stream.width, stream.height, stream.pix_fmt = width, height, "yuv420p"
        stream.options = {"crf": str(crf), "preset": "veryfast"}
        pictures = rendered_frames(sim, idx, camera=camera, width=width, height=height)
        for _, img in tqdm(pictures, total=len(idx), disable=not show, unit="frame", desc="mp4"):
            for packet in stream.encode(av.VideoFrame.from_ndarray(img, format="rgb24")):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)
    return len(idx)


def rendered_frames(
    sim: Simulator,
    frames: Sequence[int] | NDArray[np.intp],
    *,
    camera: str | None = None,
    width: int = 640,
    height: int = 480,
) -> Iterator[tuple[int, NDArray[np.uint8]]]:
    """(frame, picture (H, W, 3) uint8) for each timeline frame of a non-decreasing list,
    from one camera (default: the overview fitted over the whole run); a repeated frame
    is rendered once."""
    idx = [int(i) for i in frames]
    if any(b < a for a, b in itertools.pairwise(idx)):
        raise RenderError("rendered_frames: frames must not decrease")
    cam = _camera_for(sim, camera, width, height)
    data = mujoco.MjData(sim.model)
    with CellRenderer(sim.model, width, height) as r:
        qs = _frames_qpos(sim, sorted(set(idx)))  # one pass over the timeline
        img, last = None, -1
        for i in idx:
            if i != last:
                data.qpos[:] = next(qs)
                mujoco.mj_forward(sim.model, data)
                img, last = r.render(data, cam), i
            yield i, img
