"""`workcell demo handoff --save --render`: the main job's recording and picture."""

from __future__ import annotations

import json

import numpy as np
from PIL import Image
from rerun.chunk import RrdReader

from workcell.cli import main
from workcell.examples import thesis_handoff as ho
from workcell.record.rerun_log import body_entity


def test_demo_handoff_writes_a_recording_and_a_picture(tmp_path, capsys):
    rrd, png = tmp_path / "handoff.rrd", tmp_path / "handoff.png"
    args = ["demo", "handoff", "--dt", "0.02", "--json", "--save", str(rrd), "--render", str(png)]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rrd"] == str(rrd)
    assert out["png"] == str(png)
    assert rrd.stat().st_size == out["rrd_bytes"] > 0
    # the sphere's logged path ends where the simulator put it: on table 2
    entity = body_entity(ho.SPHERE)
    last = None
    for chunk in RrdReader(rrd).store().stream().filter(content=entity).to_chunks():
        rb = chunk.to_record_batch()
        names = [n for n in rb.schema.names if n.endswith("translation")]
        if chunk.entity_path == entity and names and "frame" in rb.schema.names:
            frames = rb.column("frame").to_numpy()
            values = np.array(rb.column(names[0]).to_pylist())
            i = int(np.argmax(frames))
            if last is None or frames[i] > last[0]:
                last = (frames[i], values[i])
    assert last is not None
    assert last[0] == out["frames"] - 1
    assert np.allclose(last[1], ho.PLACE, atol=1e-6)
    # one tile per key moment: the start, two grasps, two releases, in one row
    assert out["png_frames"][0] == 0
    assert len(out["png_frames"]) == 5
    with Image.open(png) as im:
        assert 5 * 400 <= im.width < 5 * 400 + 100  # five tiles and their margins
        assert im.height > 300
        assert np.asarray(im.convert("L")).std() > 10  # not a blank picture


def test_pictures_inside_the_recording(tmp_path):
    import io

    from workcell.examples import thesis_joints
    from workcell.record import record
    from workcell.record.rr_images import image_entity
    from workcell.record.sheets import video_frames

    sim = thesis_joints.run("path", 0.05)
    path = tmp_path / "pictures.rrd"
    record(sim, path, images_fps=2.0, image_size=(160, 120))
    entity = image_entity(None)
    frames, blobs = [], []
    for chunk in RrdReader(path).store().stream().filter(content=entity).to_chunks():
        rb = chunk.to_record_batch()
        if chunk.entity_path != entity or "frame" not in rb.schema.names:
            continue
        frames += rb.column("frame").to_pylist()
        col = next(n for n in rb.schema.names if n.endswith("blob"))
        blobs += rb.column(col).to_pylist()
    # one picture per distinct frame of a 2 fps video of the run (9.89 s: 21 samples)
    expected = np.unique(video_frames(sim, 2.0))
    assert sorted(frames) == expected.tolist()
    assert len(expected) == 21
    first = blobs[0][0] if isinstance(blobs[0], list) else blobs[0]
    with Image.open(io.BytesIO(bytes(first))) as im:
        assert im.size == (160, 120)
        assert im.format == "JPEG"
