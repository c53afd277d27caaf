"""Issue 14, item 2: a server's file names stay inside its root folder.

Every command that takes a file name is found from the vocabulary itself, and each is
tried with the names an attacker would use (absolute paths, '..', '~', symbolic links
leading out, hidden files); none may read or write outside the root, errors must not
echo what a file holds or tell whether a file outside the root exists, and reads are
bounded."""

from __future__ import annotations

import dataclasses
import json
import os

import pytest

from workcell import LimitError, Model, limits
from workcell.client import Client
from workcell.errors import ModelError, ProgramError, WorkcellError
from workcell.program import COMMANDS, Session
from workcell.program.args import label
from workcell.program.interpreter import run_script
from workcell.program.server import Server

# a valid value for every other argument of the file commands
OTHER_ARGS = {"ref": "c", "name": "r", "format": "urdf", "robot": "r"}


def file_commands() -> dict[str, list[str]]:
    """Command -> its file-name arguments (declared with the file_name converter)."""
    out = {}
    for name, cls in COMMANDS.items():
        fields = [
            f.name
            for f in dataclasses.fields(cls)
            if label(f.metadata["convert"]).startswith("file")
        ]
        if fields:
            out[name] = fields
    return out


def test_every_file_argument_is_declared_as_a_file_name():
    """A new command that takes a path as a plain string would escape the root check:
    every argument that looks like a file must use the file_name converter."""
    found = file_commands()
    assert {"save", "load", "save_cell", "load_cell", "world_mesh"} <= set(found)
    for name, cls in COMMANDS.items():
        for f in dataclasses.fields(cls):
            looks_like_file = any(w in f.name for w in ("path", "file", "out", "dir", "folder"))
            looks_like_file &= f.name != "profile"  # set_profile's motion profile is no file
            if looks_like_file:
                assert f.name in found.get(name, []), (name, f.name)
            assert label(f.metadata["convert"]) != "string", (name, f.name)  # no raw text


@pytest.fixture
def tree(tmp_path):
    """root/ (the server's) with a sub folder and links leading out; outside/ beside it."""
    root, outside = tmp_path / "root", tmp_path / "outside"
    (root / "sub").mkdir(parents=True)
    outside.mkdir()
    secret = {"format": "SECRET-FORMAT", "version": "SECRET-VERSION", "token": "SECRET"}
    (outside / "secret.json").write_text(json.dumps(secret))
    (root / "link").symlink_to(outside)  # a folder link leading out
    (root / "lfile.json").symlink_to(outside / "secret.json")  # a file link leading out
    (root / "inside.json").symlink_to(root / "sub" / "target.json")  # a link that stays in
    os.link(outside / "secret.json", root / "hard.json")  # a hard link: the same file
    return root, outside


@pytest.fixture
def client(tree):
    srv = Server(port=0, root=tree[0])
    srv.serve_in_thread()
    with Client(port=srv.port, timeout=30) as c:
        c.create_cube(name="c", size=1.0)
        yield c
    srv.stop()


def escaping_names(root, outside) -> list[str]:
    home = os.path.expanduser("~")
    return [
        str(outside / "x.json"),  # absolute
        "/etc/passwd",
        "../outside/x.json",
        "sub/../../outside/x.json",
        "~/x.json",
        f"~{os.path.basename(home)}/x.json",
        "link/x.json",  # through a symbolic link to a folder outside
        "lfile.json",  # a symbolic link to a file outside
        "hard.json",  # a hard link to a file outside
        ".hidden.json",
        "sub/.config/x.json",
        "a\x00b.json",
    ]


@pytest.mark.parametrize("command", sorted(file_commands()))
def test_no_file_command_reaches_outside_the_root(client, tree, command):
    root, outside = tree
    before = sorted(p.name for p in outside.iterdir())
    for name in escaping_names(root, outside):
        args = {k: v for k, v in OTHER_ARGS.items() if k in _fields(command)}
        args[file_commands()[command][0]] = name
        with pytest.raises(ProgramError, match=r"refused|must be a file name") as info:
            client.call(command, **args)
        assert "SECRET" not in str(info.value)
    assert sorted(p.name for p in outside.iterdir()) == before  # nothing written out there
    assert not os.path.exists(os.path.expanduser("~/x.json"))


def _fields(command: str) -> set[str]:
    return {f.name for f in dataclasses.fields(COMMANDS[command])}


def test_refusals_do_not_tell_whether_a_file_outside_exists(client):
    messages = set()
    for name in ("../outside/secret.json", "../outside/nothing.json", "link/secret.json",
                 "link/nothing.json"):  # fmt: skip
        with pytest.raises(ProgramError) as info:
            client.call("load", path=name)
        messages.add(str(info.value).replace(name, "NAME").replace("secret", "nothing"))
    assert len(messages) == 2  # one message for '..', one for the link: never about the file


def test_files_inside_the_root_work_and_links_that_stay_inside_too(client, tree):
    root, _ = tree
    assert client.call("save", path="sub/m.json") == str(root / "sub" / "m.json")
    assert client.call("load", path="sub/m.json") == {
        "surface": ["c.square"],
        "block": ["c"],
        "object": [],
        "scene": [],
    }
    client.call("save", path="inside.json")  # written through the link, to sub/target.json
    assert (root / "sub" / "target.json").is_file()
    assert (root / "inside.json").is_symlink()
    out = client.call("world_mesh", ref="c", path="sub/c.stl")
    assert out["path"] == str(root / "sub" / "c.stl")
    client.call("new_cell", name="cell")
    client.call("save_cell", path="cell.json")
    assert client.call("load_cell", path="./cell.json") == "cell"


def test_load_errors_do_not_echo_the_file(client, tree):
    root, _ = tree
    (root / "notes.json").write_text(json.dumps({"format": "SECRET-1", "version": "SECRET-2"}))
    (root / "model.json").write_text(
        json.dumps({"format": "workcell-model", "version": "SECRET-3"})
    )
    (root / "key.pem").write_text("-----BEGIN SECRET KEY-----\nSECRET-4\n")
    for command, name in [
        ("load", "notes.json"),
        ("load_cell", "notes.json"),
        ("load", "model.json"),
        ("load_cell", "model.json"),
        ("load", "key.pem"),
        ("load_cell", "key.pem"),
    ]:
        with pytest.raises(ModelError) as info:
            client.call(command, path=name)
        assert "SECRET" not in str(info.value), (command, name, str(info.value))


def test_a_local_session_without_a_root_still_takes_any_path(tmp_path):
    """Shells and scripts are the user's own: no root, absolute paths and ~ work."""
    s = Session(base_dir=tmp_path)
    assert s.path(str(tmp_path / "a.json")) == tmp_path / "a.json"
    assert s.path("b.json") == tmp_path / "b.json"
    assert s.path("~/c.json") == Session().path(os.path.expanduser("~/c.json"))


# ------------------------------------------------------------------ bounded loads
def test_devices_are_refused_and_big_files_refused_before_reading(tmp_path):
    """Issue 19, item 3: a device is not a file to read (opening one may wait or act)."""
    with limits.using(max_file_bytes=1 << 20):
        for load in (Model.load, lambda p: __import__("workcell").Workcell.load(p)):
            with pytest.raises(ModelError, match="it is a character device"):
                load("/dev/zero")
        big = tmp_path / "big.json"
        big.write_bytes(b" " * (2 << 20))
        with pytest.raises(LimitError, match="2,097,152 bytes is over the limit max_file_bytes"):
            Model.load(big)  # a regular file: refused from its size, before reading


def test_special_files_are_refused_without_hanging(tmp_path):
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)  # opening it for reading would wait for a writer forever
    with pytest.raises(ModelError, match="it is a FIFO"):
        Model.load(fifo)
    with pytest.raises(ModelError, match="it is a folder"):
        Model.load(tmp_path)
    with pytest.raises(WorkcellError, match="it is a FIFO"):
        run_script(fifo)
