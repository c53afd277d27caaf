"""Issue 19, items 3 and 4: a FIFO, socket or device wherever a file name reaches an open,
and mesh files too big to parse.

Each reader is handed a FIFO (opening it for reading would wait for a writer forever),
a socket and a device; each must refuse it at once with its own WorkcellError, from a
thread that finishes. A mesh file over ``max_facets`` is refused from its counted
triangles before any reader parses it."""

from __future__ import annotations

import os
import socket
from pathlib import Path

import pytest
import trimesh
from blocking import outcome

from workcell import Model, Workcell, limits
from workcell.errors import LimitError, ModelError, StudyError, WorkcellError
from workcell.program.interpreter import run_script
from workcell.robots import from_urdf
from workcell.robots.meshfile import count_facets, load_mesh


def special(folder: Path, name: str, kind: str) -> tuple[Path, socket.socket | None]:
    p = folder / name
    if kind == "fifo":
        os.mkfifo(p)
        return p, None
    if kind == "socket":
        s = socket.socket(socket.AF_UNIX)
        s.bind(str(p))
        return p, s
    p.symlink_to("/dev/zero")
    return p, None


def _urdf(folder: Path, mesh: str) -> Path:
    p = folder / "r.urdf"
    p.write_text(
        f"""<robot name="r"><link name="a"><visual><geometry><mesh filename="{mesh}"/>
        </geometry></visual></link><link name="b"/><joint name="j" type="revolute">
        <parent link="a"/><child link="b"/><limit lower="-1" upper="1"/></joint></robot>"""
    )
    return p


def _study_program(path: Path) -> None:
    from workcell.study.program import ScriptProgram

    ScriptProgram.read(path)


READERS = {  # name of the special file, reader, error class
    "model": ("m.json", Model.load, ModelError),
    "cell": ("c.json", Workcell.load, ModelError),
    "script": ("s.wcl", run_script, WorkcellError),
    "mesh": ("m.stl", load_mesh, ModelError),
    # strict: a mesh found nowhere is an error (else a warning and a stand-in)
    "urdf mesh": ("m.stl", lambda p: from_urdf(_urdf(p.parent, p.name), strict=True), ModelError),
    "urdf": ("r.urdf", from_urdf, ModelError),
    "study program": ("p.wcl", _study_program, StudyError),
}


@pytest.mark.parametrize("kind", ["fifo", "socket", "device"])
@pytest.mark.parametrize("reader", sorted(READERS))
def test_special_files_are_refused_at_once_everywhere(tmp_path, reader, kind):
    name, read, error = READERS[reader]
    path, sock = special(tmp_path, name, kind)
    try:
        exc = outcome(lambda: read(path))
    finally:
        if sock is not None:
            sock.close()
    assert isinstance(exc, error), repr(exc)
    # a URDF mesh place that is no regular file is passed over (the next place is tried)
    # and the error lists it as such
    assert "not a regular file" in str(exc)
    if reader == "urdf mesh":
        assert "not found; tried" in str(exc)


def test_a_study_output_folder_with_a_fifo_for_its_study_file_is_refused(tmp_path):
    from workcell.study import Study, run

    out = tmp_path / "out"
    out.mkdir()
    os.mkfifo(out / "study.json")
    study = Study(cell="pick-place", vary={"puma.base.x": "0:0.01:2"})
    exc = outcome(lambda: run(study, out, backend="serial"), seconds=60)
    assert isinstance(exc, StudyError), repr(exc)
    assert "not a regular file" in str(exc)


# ---------------------------------------------------------------------- mesh sizes
def binary_stl(path: Path, n: int) -> Path:
    """A binary STL whose header says ``n`` triangles (all zero), ``84 + 50 n`` bytes."""
    with open(path, "wb") as f:
        f.write(b"\0" * 80 + n.to_bytes(4, "little"))
        f.truncate(84 + 50 * n)
    return path


def test_count_facets_agrees_with_the_readers(tmp_path):
    mesh = trimesh.creation.icosphere(subdivisions=3)  # 1280 triangles
    for ext in ("stl", "obj", "ply"):
        data = mesh.export(file_type=ext)
        data = data.encode() if isinstance(data, str) else data
        assert count_facets(data, ext) == 1280 == len(trimesh.load(
            __import__("io").BytesIO(data), file_type=ext).faces), ext  # fmt: skip
    ascii_stl = trimesh.exchange.stl.export_stl_ascii(mesh).encode()
    assert count_facets(ascii_stl, ".STL") == 1280
    quads = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf 1 2 3\n"
    assert count_facets(quads, "obj") == 3  # a quad is two triangles


def test_a_mesh_over_the_facet_limit_is_refused_before_it_is_parsed(tmp_path, monkeypatch):
    """Issue 19, item 4: a 250 MB STL took 48 s and 3.5 GB before the LimitError. Now
    the count in its header refuses it; the parser is never called."""
    big = binary_stl(tmp_path / "big.stl", 600_000)  # 30 MB
    monkeypatch.setattr(trimesh, "load", lambda *a, **k: pytest.fail("parsed"))
    with pytest.raises(LimitError, match="600,000 facets is over the limit max_facets"):
        load_mesh(big)
    with limits.using(max_facets=10), pytest.raises(LimitError, match="max_facets"):
        load_mesh(binary_stl(tmp_path / "small.stl", 11))
