"""`workcell run FILE.wcl --save --render`: the run's files, also when the script fails."""

from __future__ import annotations

import numpy as np
from PIL import Image
from rerun.chunk import RrdReader

from workcell.cli import main
from workcell.record.render import render_frame

SCRIPT = """cell example pick-place
simulate path dt 0.02
move end_effector puma at cube offset 0 0 0.1 down config ru
move joints relative puma 0 0 0 0 200 0
"""


def event_texts(path) -> list[str]:
    out = []
    for chunk in RrdReader(path).store().stream().filter(content="/events").to_chunks():
        rb = chunk.to_record_batch()
        for name in rb.schema.names:
            if name.endswith("text"):
                out += [str(v) for v in rb.column(name).to_pylist()]
    return out


def _run_in_process(tmp_path, text: str):
    """The script's simulator as `workcell run` leaves it (the error logged)."""
    from workcell.errors import WorkcellError
    from workcell.program.interpreter import run_script
    from workcell.program.session import Session

    script = tmp_path / "run.wcl"
    script.write_text(text)
    session = Session(base_dir=tmp_path)
    try:
        run_script(script, session, out=lambda _: None)
    except WorkcellError as exc:
        session.sim._log_error(exc)
    return script, session.sim


def test_a_failing_script_still_writes_its_recording_with_the_error(tmp_path, capsys):
    script = tmp_path / "bad.wcl"
    script.write_text(SCRIPT)
    rrd, png = tmp_path / "bad.rrd", tmp_path / "bad.png"
    code = main(["run", str(script), "--save", str(rrd), "--render", str(png)])
    assert code == 2  # the error's type reaches the user, the program stops
    err = capsys.readouterr().err
    assert "JointLimitError" in err
    assert "bad.wcl:4:" in err
    texts = event_texts(rrd)
    assert any("JointLimitError" in t and "joint 5" in t for t in texts)
    assert any("move_end_effector" in t for t in texts)  # what ran before the error
    with Image.open(png) as im:
        assert im.width > 100


def test_a_script_without_a_simulation_cannot_be_recorded(tmp_path, capsys):
    script = tmp_path / "model.wcl"
    script.write_text("create block b1\n")
    assert main(["run", str(script), "--save", str(tmp_path / "x.rrd")]) == 2
    assert "never started a simulation" in capsys.readouterr().err


def test_the_picture_of_a_failing_run_ends_with_the_failing_moment(tmp_path, capsys):
    """--render shows the start, each command's end and, last, the moment the script
    stopped: the state the failing command found, captioned with its error."""
    from workcell.record.sheets import key_frames

    script, sim = _run_in_process(tmp_path, SCRIPT)
    keys = key_frames(sim)
    assert [k.title for k in keys] == [
        "initial state",
        "puma: move_end_effector",
        "error: JointLimitError",
    ]
    assert keys[-1].frame == sim.frames - 1
    assert "joint 5" in keys[-1].detail
    png = tmp_path / "bad.png"
    assert main(["run", str(script), "--render", str(png)]) == 2
    capsys.readouterr()
    with Image.open(png) as im:  # three tiles: two columns, two rows of 240 px pictures
        assert im.width == 2 * 320 + 3 * 4
        assert im.height > 2 * 240


# ------------------------------------------------ a name error stops the script (issue 19)
NAME_ERROR = """cell example pick-place
simulate path dt 0.02
move joints relative puma 20 -10 0 0 0 0
move joints relative pumax 5 0 0 0 0 0
"""


def same_picture(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal to one intensity level (the renderer's rounding of a frame read back from
    the timeline's storage)."""
    return bool(np.abs(a.astype(int) - b.astype(int)).max() <= 1)


def tile(png, k: int, columns: int, size=(320, 240)) -> np.ndarray:
    """Tile ``k``'s picture (no caption) of a contact sheet with the default layout."""
    w, h = size
    gap, cap = 4, 2 * max(9, h // 18) + 10
    x, y = gap + (k % columns) * (w + gap), gap + (k // columns) * (h + cap + gap)
    with Image.open(png) as im:
        return np.asarray(im.convert("RGB"))[y : y + h, x : x + w]


def test_a_script_stopped_by_a_multiline_error_draws_the_moment_of_the_error(tmp_path, capsys):
    # the user's steps: a typo in a robot's name after a move, `workcell run --render`;
    # the error quotes the line with a caret under it (three lines), which crashed the
    # caption ("can't measure length of multiline text")
    script, sim = _run_in_process(tmp_path, NAME_ERROR)
    error = sim.events[-1]
    assert error.kind == "error"
    assert "\n" in error.detail  # the multiline message
    png = tmp_path / "run.png"
    assert main(["run", str(script), "--render", str(png)]) == 2
    err = capsys.readouterr().err
    assert "unknown robot 'pumax'; valid here: puma" in err
    # three tiles (start, the move, the error), the error's is the last frame: the same
    # pixels as the frame drawn on its own with the same view
    with Image.open(png) as im:
        assert im.size == (2 * 320 + 3 * 4, 2 * (240 + 2 * 13 + 10) + 3 * 4)
    assert same_picture(tile(png, 2, 2), render_frame(sim, -1, width=320, height=240))
    assert same_picture(tile(png, 0, 2), render_frame(sim, 0, width=320, height=240))
    assert not same_picture(tile(png, 2, 2), tile(png, 0, 2))  # the robot moved


def test_the_render_camera_is_a_cell_camera_or_a_preset_view(tmp_path, capsys):
    script, sim = _run_in_process(tmp_path, SCRIPT)
    png = tmp_path / "top.png"
    assert main(["run", str(script), "--render", str(png), "--camera", "top"]) == 2
    # the top view: straight down, framing every pose of the run
    assert same_picture(tile(png, 0, 2), render_frame(sim, 0, camera="top", width=320, height=240))
    top = render_frame(sim, 0, camera="top", width=320, height=240)
    front = render_frame(sim, 0, camera="front", width=320, height=240)
    assert not same_picture(top, front)
    # a camera of the cell by its name: MuJoCo's own fixed camera
    side = tmp_path / "side.png"
    assert main(["run", str(script), "--render", str(side), "--camera", "side"]) == 2
    from workcell.record.sheets import key_frames

    moved = key_frames(sim)[1].frame
    assert same_picture(
        tile(side, 1, 2), render_frame(sim, moved, camera="side", width=320, height=240)
    )
    capsys.readouterr()
    bad = tmp_path / "bad.png"
    assert main(["run", str(script), "--render", str(bad), "--camera", "nope"]) == 2
    assert (
        "no camera 'nope' in the cell and no such view; cameras: overview, side; views: "
        "overview, front, back, left, right, top" in capsys.readouterr().err
    )
    assert not bad.exists()
    assert main(["run", str(script), "--camera", "top"]) == 2  # nothing to draw
    assert "give --render too" in capsys.readouterr().err


def test_the_preset_views_look_from_where_they_say():
    # the cell's geometry seen from the top spans x and y; from the front, x and z
    from workcell.examples import thesis_pick_place
    from workcell.record.camera import VIEWS, named_view
    from workcell.sim import Simulator

    sim = Simulator(thesis_pick_place.build())
    for name, direction in {
        "front": (0, 1, 0), "back": (0, -1, 0), "left": (1, 0, 0), "right": (-1, 0, 0),
        "top": (0, 0, -1),
    }.items():  # fmt: skip
        cam = named_view(sim.model, name)
        az, el = np.radians(cam.azimuth), np.radians(cam.elevation)
        forward = [np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)]
        assert np.dot(forward, direction) > 0.93, name  # within 21 deg
        assert VIEWS[name]
    assert named_view(sim.model, "side") == "side"  # the cell's own camera wins


# ------------------------------------------------ collisions (issue 19)
COLLIDING = """cell example obstacle
simulate path dt 0.02
move end_effector puma at cube offset 0 0 0.02 down config ru
move end_effector puma at 0.28 0.2 0.56 down config ru
"""


def test_a_run_that_collides_says_so_and_exits_3(tmp_path, capsys):
    # the user's steps: a joint-space move sweeps the arm through the obstacle cell's wall
    script, sim = _run_in_process(tmp_path, COLLIDING)
    hits = [e for e in sim.events if e.kind == "collision"]
    assert len(hits) == sim.summary()["collisions"] >= 2
    assert any("wall" in e.detail for e in hits)
    first = hits[0]
    line = (
        f"workcell: {len(hits)} collision(s); the first at t = {first.t:.6g} s "
        f"(frame {first.frame}): {first.detail}"
    )
    assert main(["run", str(script)]) == 3
    err = capsys.readouterr().err
    assert err.startswith(line)
    assert "--allow-collisions" in err
    assert main(["run", str(script), "--allow-collisions"]) == 0
    assert capsys.readouterr().err == line + "\n"  # still said
    # a clean run: 0, nothing on stderr
    clean = tmp_path / "clean.wcl"
    clean.write_text(COLLIDING.splitlines()[0] + "\nsimulate path dt 0.02\n")
    assert main(["run", str(clean)]) == 0
    assert capsys.readouterr().err == ""
    # an error after the collisions: the error's status (2), the collisions said too
    failing = tmp_path / "failing.wcl"
    failing.write_text(COLLIDING + "move joints relative puma 0 0 0 0 400 0\n")
    assert main(["run", str(failing)]) == 2
    err = capsys.readouterr().err
    assert line in err
    assert "JointLimitError" in err


def test_a_script_that_stops_before_simulating_says_nothing_was_drawn(tmp_path, capsys):
    # a typo on line 2 stops the script before its `simulate` line: no picture to draw
    script = tmp_path / "typo.wcl"
    script.write_text("cell example pick-place\nmove joints absolutely puma 5 0 0 0 0 0\n")
    png = tmp_path / "typo.png"
    assert main(["run", str(script), "--render", str(png)]) == 2
    err = capsys.readouterr().err
    assert "nothing recorded or drawn: the script stopped before it started a simulation" in err
    assert "CommandSyntaxError" in err
    assert not png.exists()
