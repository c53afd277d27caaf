"""Rendered pictures inside a rerun recording (optional: ``record(..., images_fps=...)``).

The run is sampled every ``1 / fps`` simulated seconds (the frames an MP4 would show,
:func:`~workcell.record.sheets.video_frames`), each sample rendered offscreen from one
camera and logged as a JPEG (``EncodedImage``) under ``/camera/{name}`` on the frame,
simulated-time and wall-time timelines, so the viewer shows the picture beside the 3-D
view at the cursor.
"""

from __future__ import annotations

import io
from typing import TYPE_CHECKING

import numpy as np
import rerun as rr

from workcell.record.rr_scene import entity_part, index_columns
from workcell.record.sheets import rendered_frames, video_frames

if TYPE_CHECKING:
    from workcell.sim.simulator import Simulator

__all__ = ["CAMERAS", "image_entity", "log_images"]

CAMERAS = "/camera"


def image_entity(camera: str | None) -> str:
    """Entity path of the pictures from ``camera`` (None: the overview camera)."""
    return f"{CAMERAS}/{entity_part(camera or 'overview')}"


def _jpeg(image: np.ndarray, quality: int) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(image).save(buf, format="JPEG", quality=quality)
    return buf.getvalue()


def log_images(
    rec: rr.RecordingStream,
    sim: Simulator,
    *,
    fps: float,
    camera: str | None = None,
    width: int = 640,
    height: int = 480,
    quality: int = 85,
) -> int:
    """Render the run every ``1 / fps`` simulated seconds and log the pictures (module
    doc); returns how many were logged (repeated frames are logged once)."""
    frames = np.unique(video_frames(sim, fps))
    pictures = rendered_frames(sim, frames, camera=camera, width=width, height=height)
    blobs = [_jpeg(img, quality) for _, img in pictures]
    times, walls = sim.timeline.sim_times()[frames], sim.timeline.wall_times()[frames]
    rec.send_columns(
        image_entity(camera),
        indexes=index_columns(frames, times, walls),
        columns=rr.EncodedImage.columns(blob=blobs, media_type=["image/jpeg"] * len(blobs)),
    )
    return len(blobs)
