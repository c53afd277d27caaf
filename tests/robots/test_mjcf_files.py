"""Issue 19, items 2 and 3: MJCF files read the way MuJoCo finds them, inside the root, never
blocking.

Which file MuJoCo 3.17 loads for each name is checked against MuJoCo itself: a tree of
look-alike meshes (a cube of edge k in each place, so the loaded mesh tells which file
was read) is loaded by ``mujoco.MjModel.from_xml_path`` and by our reader, and both must
pick the same file for every case (meshdir, assetdir, texturedir, several compilers, a
compiler in an include or after the assets, includes in subfolders and nested,
strippath, backslashes, absolute folders). Then the attacks: symbolic links out through
``meshdir`` or an include's folder, FIFOs, sockets and devices named as meshes,
textures or includes, a swap between the check and the open."""

from __future__ import annotations

import os
import socket
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh
from blocking import outcome
from robot_files import arm_mjcf, write, write_meshes

from workcell import limits
from workcell.errors import LimitError, ModelError, ProgramError
from workcell.robots import from_mjcf
from workcell.robots.mjcf_files import read_mjcf, spec_from_files

PLACES = {
    "box.stl": 1,
    "m/box.stl": 2,
    "sub/box.stl": 3,
    "sub/m/box.stl": 4,
    "m/sub/box.stl": 5,
    "t/box.stl": 6,
}


def cube_tree(root: Path) -> None:
    for rel, k in PLACES.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        trimesh.creation.box(extents=(k, k, k)).export(root / rel)


def extent(model: mujoco.MjModel) -> float:
    v = model.mesh_vert
    return round(float(v.max() - v.min()), 6)


def ours(path: Path, root: Path | None = None) -> float:
    files = read_mjcf(path, root)
    return extent(spec_from_files(files, "test").compile())


MESH = '<asset><mesh name="a" file="{f}"/></asset>'
BODY = '<worldbody><geom type="mesh" mesh="a"/></worldbody>'
CASES = {  # name: (main file, {include file: text}), mesh named "a"
    "meshdir": (f'<compiler meshdir="m"/>{MESH.format(f="box.stl")}{BODY}', {}),
    "no meshdir": (f"{MESH.format(f='sub/box.stl')}{BODY}", {}),
    "include in a subfolder: its mesh from the main file's folder": (
        f'<include file="sub/inc.xml"/>{BODY}',
        {"sub/inc.xml": MESH.format(f="box.stl")},
    ),
    "include in a subfolder with meshdir in the main file": (
        f'<compiler meshdir="m"/><include file="sub/inc.xml"/>{BODY}',
        {"sub/inc.xml": MESH.format(f="box.stl")},
    ),
    "meshdir set in an included file applies to all": (
        f'<include file="sub/inc.xml"/>{MESH.format(f="box.stl")}{BODY}',
        {"sub/inc.xml": '<compiler meshdir="m"/>'},
    ),
    "nested include: relative to the main file's folder": (
        f'<include file="sub/inc.xml"/>{BODY}',
        {"sub/inc.xml": '<include file="t/inc2.xml"/>', "t/inc2.xml": MESH.format(f="box.stl")},
    ),
    "the last compiler wins": (
        f'<compiler meshdir="m"/><compiler meshdir="sub/m"/>{MESH.format(f="box.stl")}{BODY}',
        {},
    ),
    "a compiler after the assets still applies": (
        f'{MESH.format(f="box.stl")}<compiler meshdir="t"/>{BODY}',
        {},
    ),
    "compiler order across an include": (
        f'<compiler meshdir="m"/><include file="sub/inc.xml"/><compiler meshdir="t"/>'
        f"{MESH.format(f='box.stl')}{BODY}",
        {"sub/inc.xml": '<compiler meshdir="sub/m"/>'},
    ),
    "assetdir after meshdir overrides it": (
        f'<compiler meshdir="m"/><compiler assetdir="sub"/>{MESH.format(f="box.stl")}{BODY}',
        {},
    ),
    "meshdir after assetdir overrides it": (
        f'<compiler assetdir="sub"/><compiler meshdir="m"/>{MESH.format(f="box.stl")}{BODY}',
        {},
    ),
    "meshdir beats assetdir on one compiler": (
        f'<compiler assetdir="sub" meshdir="m"/>{MESH.format(f="box.stl")}{BODY}',
        {},
    ),
    "strippath drops the name's folders": (
        f'<compiler strippath="true" meshdir="m"/>{MESH.format(f="sub/box.stl")}{BODY}',
        {},
    ),
    "backslashes separate folders": (
        '<compiler meshdir="m\\..\\sub"/>' + MESH.format(f="m\\box.stl") + BODY,
        {},
    ),
    "dots in names": (
        f'<compiler meshdir="./m//"/><include file="./sub/../sub/inc.xml"/>{BODY}',
        {"sub/inc.xml": MESH.format(f="./sub/box.stl")},
    ),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_file_read_is_the_one_mujoco_reads(tmp_path, case):
    main, includes = CASES[case]
    cube_tree(tmp_path)
    for name, text in includes.items():
        write(tmp_path, name, f"<mujoco>{text}</mujoco>")
    path = write(tmp_path, "model.xml", f"<mujoco>{main}</mujoco>")
    theirs = extent(mujoco.MjModel.from_xml_path(str(path)))
    assert theirs in PLACES.values()
    assert ours(path) == theirs
    if ".." in main + "".join(includes.values()):  # a root takes no '..', even one that stays
        with pytest.raises(ModelError, match=r"refused: .*no absolute names"):
            ours(path, root=tmp_path)
    else:
        assert ours(path, root=tmp_path) == theirs  # and the same inside a root


def test_absolute_folders_work_without_a_root(tmp_path):
    cube_tree(tmp_path)
    text = f'<compiler meshdir="{tmp_path / "sub" / "m"}"/>{MESH.format(f="box.stl")}{BODY}'
    path = write(tmp_path, "abs.xml", f"<mujoco>{text}</mujoco>")
    assert ours(path) == extent(mujoco.MjModel.from_xml_path(str(path))) == 4
    with pytest.raises(ModelError, match=r"meshdir=.*refused: it leads outside the root"):
        ours(path, root=tmp_path)


def test_textures_and_height_fields_are_found_where_mujoco_finds_them(tmp_path):
    from PIL import Image

    for folder, size in (("t", 4), ("sub", 6), ("m", 8)):
        (tmp_path / folder).mkdir()
        Image.fromarray(np.zeros((size, size + 1, 3), np.uint8)).save(tmp_path / folder / "i.png")
    text = (
        '<compiler meshdir="m" texturedir="t"/><compiler assetdir="sub" texturedir="t"/>'
        '<asset><texture name="x" type="2d" file="i.png"/><material name="y" texture="x"/>'
        '<hfield name="h" file="i.png" size="1 1 1 0.1"/></asset>'
        '<worldbody><geom type="box" size="1 1 1" material="y"/>'
        '<geom type="hfield" hfield="h"/></worldbody>'
    )
    path = write(tmp_path, "tex.xml", f"<mujoco>{text}</mujoco>")
    theirs = mujoco.MjModel.from_xml_path(str(path))
    mine = spec_from_files(read_mjcf(path, tmp_path), "t").compile()
    assert (int(theirs.tex_height[0]), int(theirs.hfield_nrow[0])) == (4, 6)
    assert (int(mine.tex_height[0]), int(mine.hfield_nrow[0])) == (4, 6)


def test_mujoco_opens_no_file_itself(tmp_path):
    """Everything is read first and handed over in memory: with the files gone, the
    model still compiles (so nothing can change between the check and MuJoCo's read)."""
    cube_tree(tmp_path)
    write(tmp_path, "sub/inc.xml", f"<mujoco>{MESH.format(f='box.stl')}</mujoco>")
    path = write(
        tmp_path,
        "model.xml",
        f'<mujoco><compiler meshdir="m"/><include file="sub/inc.xml"/>{BODY}</mujoco>',
    )
    files = read_mjcf(path, tmp_path)
    for p in sorted(tmp_path.rglob("*"), reverse=True):
        p.unlink() if p.is_file() else p.rmdir()
    assert extent(spec_from_files(files, "t").compile()) == 2


# ---------------------------------------------------------------------- escapes
def escape_tree(tmp_path: Path, *, target_exists: bool) -> tuple[Path, Path]:
    root, outside = tmp_path / "root", tmp_path / "outside"
    cube_tree(root)
    outside.mkdir()
    if target_exists:
        trimesh.creation.box(extents=(9, 9, 9)).export(outside / "secret.stl")
    (root / "m" / "box.stl").unlink()
    (root / "m" / "box.stl").symlink_to(outside / "secret.stl")  # the attack of the issue
    (root / "sub" / "box.stl").unlink()
    (root / "sub" / "box.stl").symlink_to(outside / "secret.stl")
    (root / "lm").symlink_to(outside)  # a folder leading out
    return root, outside


ATTACKS = {
    "meshdir, mesh a link out": f'<compiler meshdir="m"/>{MESH.format(f="box.stl")}{BODY}',
    "assetdir, mesh a link out": f'<compiler assetdir="m"/>{MESH.format(f="box.stl")}{BODY}',
    "include's mesh a link out": f'<include file="sub/inc.xml"/>{BODY}',
    "meshdir a link to a folder out": (
        f'<compiler meshdir="lm"/>{MESH.format(f="secret.stl")}{BODY}'
    ),
    "include a link to a folder out": f'<include file="lm/inc.xml"/>{BODY}',
    "meshdir with ..": f'<compiler meshdir="m/../../outside"/>{MESH.format(f="secret.stl")}{BODY}',
    "backslash ..": '<compiler meshdir="m\\..\\..\\outside"/>' + MESH.format(f="secret.stl") + BODY,
    "absolute mesh": MESH.format(f="{outside}/secret.stl") + BODY,
    "absolute texture": (
        '<asset><texture name="x" type="2d" file="{outside}/secret.png"/></asset>'
    ),
}


@pytest.mark.parametrize("attack", sorted(ATTACKS))
def test_no_mjcf_name_leads_outside_the_root_and_the_refusal_tells_nothing(tmp_path, attack):
    messages = set()
    for exists in (True, False):
        here = tmp_path / str(exists)
        root, outside = escape_tree(here, target_exists=exists)
        write(root, "sub/inc.xml", f"<mujoco>{MESH.format(f='sub/box.stl')}</mujoco>")
        text = ATTACKS[attack].replace("{outside}", str(outside))
        path = write(root, "model.xml", f"<mujoco>{text}</mujoco>")
        if exists and "link out" in attack:  # MuJoCo itself would load the outside file
            assert extent(mujoco.MjModel.from_xml_path(str(path))) == 9
        with pytest.raises(ModelError, match="refused: it leads outside the root folder") as info:
            from_mjcf(path, root=root)
        messages.add(str(info.value).replace(str(here), "HERE"))
    assert len(messages) == 1, messages  # the same words whether the outside file exists


def test_the_server_refuses_an_mjcf_mesh_through_a_linked_meshdir(tmp_path):
    from workcell.client import Client
    from workcell.program.server import Server

    root, _ = escape_tree(tmp_path, target_exists=True)
    write_meshes(root)
    write(root, "arm.xml", arm_mjcf().replace("<compiler", '<compiler meshdir="m"', 1))
    (root / "m" / "meshes").symlink_to(root / "meshes")
    (root / "m" / "meshes" / "arm.stl").unlink()
    (root / "m" / "meshes" / "arm.stl").symlink_to(tmp_path / "outside" / "secret.stl")
    srv = Server(root=root)
    srv.serve_in_thread()
    try:
        with Client(port=srv.port) as c:
            c.call("new_cell", name="c")
            with pytest.raises(ModelError, match="refused: it leads outside the root folder"):
                c.call("import_robot", name="r", format="mjcf", path="arm.xml")
    finally:
        srv.stop()


# ---------------------------------------------------------------------- special files
SPECIAL = {
    "mesh": f"{MESH.format(f='special.stl')}{BODY}",
    "include": f'<include file="special.stl"/>{BODY}',
    "texture": '<asset><texture name="x" type="2d" file="special.stl"/></asset>',
    "cube face": '<asset><texture name="x" type="cube" fileup="special.stl"/></asset>',
    "hfield": '<asset><hfield name="h" file="special.stl" size="1 1 1 1"/></asset>',
}


@pytest.mark.parametrize("kind", ["fifo", "socket", "device"])
@pytest.mark.parametrize("where", sorted(SPECIAL))
def test_special_files_named_in_mjcf_are_refused_without_blocking(tmp_path, where, kind):
    special = tmp_path / "special.stl"
    sock = None
    if kind == "fifo":
        os.mkfifo(special)
    elif kind == "socket":
        sock = socket.socket(socket.AF_UNIX)
        sock.bind(str(special))
    else:
        special.symlink_to("/dev/zero")
    path = write(tmp_path, "model.xml", f"<mujoco>{SPECIAL[where]}</mujoco>")
    try:
        for root in (None, tmp_path):
            exc = outcome(lambda root=root: from_mjcf(path, root=root))
            assert isinstance(exc, ModelError), exc
            outside = root is not None and kind == "device"  # a link to /dev/zero
            assert ("leads outside the root" if outside else "not a regular file") in str(exc)
    finally:
        if sock is not None:
            sock.close()


def test_a_fifo_swapped_in_after_the_check_is_refused_not_waited_on(tmp_path, monkeypatch):
    """The race: the name is checked (a regular file), then a FIFO takes its place before
    the open. The open does not block and the file opened is checked again."""
    from workcell import files

    os.mkfifo(tmp_path / "swapped.stl")
    real_stat = os.stat

    def looks_regular(p, *a, **k):  # what stat said just before the swap
        st = real_stat(p, *a, **k)
        return real_stat(__file__) if str(p).endswith("swapped.stl") else st

    monkeypatch.setattr(files.os, "stat", looks_regular)
    exc = outcome(lambda: files.read_bytes(tmp_path / "swapped.stl", error=ModelError))
    assert isinstance(exc, ModelError), exc
    assert "it is a FIFO" in str(exc)


def test_a_link_swapped_in_after_the_check_is_refused_after_the_open(tmp_path, monkeypatch):
    from workcell import files

    root, outside = tmp_path / "root", tmp_path / "outside"
    root.mkdir()
    outside.mkdir()
    (outside / "secret.stl").write_text("solid secret")
    (root / "box.stl").symlink_to(outside / "secret.stl")
    monkeypatch.setattr(files, "leaves_root", lambda *a: None)  # the check saw a plain file
    with pytest.raises(ModelError, match="leads outside the root folder") as info:
        files.read_bytes(root / "box.stl", error=ModelError, root=root)
    assert "secret" not in str(info.value).replace("box.stl", "")


# ---------------------------------------------------------------------- bounds
def test_meshes_over_the_facet_limit_are_refused_before_mujoco_parses_them(tmp_path):
    cube_tree(tmp_path)
    path = write(
        tmp_path,
        "m.xml",
        f'<mujoco><compiler meshdir="m"/>{MESH.format(f="box.stl")}{BODY}</mujoco>',
    )
    with limits.using(max_facets=11), pytest.raises(LimitError, match="12 facets"):
        read_mjcf(path)
    with limits.using(max_file_bytes=800), pytest.raises(LimitError, match="files it names"):
        read_mjcf(path)  # the XML and its 684-byte mesh together


def test_files_mujoco_would_read_but_a_robot_does_not_need_are_refused(tmp_path):
    path = write(tmp_path, "s.xml", '<mujoco><asset><skin file="a.skn"/></asset></mujoco>')
    with pytest.raises(ModelError, match=r"<skin file='a\.skn'>: is not read"):
        read_mjcf(path)
    loop = write(tmp_path, "loop.xml", '<mujoco><include file="loop.xml"/></mujoco>')
    with pytest.raises(ModelError, match="includes a file that includes it"):
        read_mjcf(loop)


def test_program_errors_from_session_paths_stay_program_errors(tmp_path):
    from workcell.program import Session

    with pytest.raises(ProgramError, match="refused"):
        Session(root=tmp_path).path("../x.xml")
