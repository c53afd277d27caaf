"""`workcell run FILE.wcl --save --render`: the run's files, also when the script fails."""

from __future__ import annotations

from PIL import Image
from rerun.chunk import RrdReader

from workcell.cli import main

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
    from workcell.errors import WorkcellError
    from workcell.program.interpreter import run_script
    from workcell.program.session import Session
    from workcell.record.sheets import key_frames

    script = tmp_path / "bad.wcl"
    script.write_text(SCRIPT)
    session = Session(base_dir=tmp_path)
    try:
        run_script(script, session, out=lambda _: None)
    except WorkcellError as exc:
        session.sim._log_error(exc)  # as `workcell run` does
    keys = key_frames(session.sim)
    assert [k.title for k in keys] == [
        "initial state",
        "puma: move_end_effector",
        "error: JointLimitError",
    ]
    assert keys[-1].frame == session.sim.frames - 1
    assert "joint 5" in keys[-1].detail
    png = tmp_path / "bad.png"
    assert main(["run", str(script), "--render", str(png)]) == 2
    capsys.readouterr()
    with Image.open(png) as im:  # three tiles: two columns, two rows of 240 px pictures
        assert im.width == 2 * 320 + 3 * 4
        assert im.height > 2 * 240
