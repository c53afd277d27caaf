"""An MJCF file and every file it names, read by us the way MuJoCo 3.17 finds them.

MuJoCo opens the files a model names by itself, with no way to say which folder they
must stay in or to refuse a FIFO. So :func:`read_mjcf` finds each file as MuJoCo 3.17
would, reads it through :func:`workcell.files.read_bytes` (regular files only, never
blocking, bounded, confined to ``root``), and :func:`spec_from_files` hands everything to
MuJoCo in memory: the XML with each file name replaced by a unique asset name, the files
as MuJoCo's assets and includes. MuJoCo then opens no file at all, so nothing can change
between our check and its read, and whatever it loads is what was checked.

How MuJoCo 3.17 finds files (each rule checked by experiment, with ``strace`` and by
loading trees of look-alike files; ``tests/robots/test_mjcf_files.py`` keeps them):

- ``<include file>``: relative to the folder of the *main* model file, also when the
  include stands in an included file in another folder;
- ``<compiler>`` settings apply to the whole model wherever they stand (in an included
  file, after the assets); read in document order (includes expanded in place), the
  last value wins; ``assetdir`` sets both ``meshdir`` and ``texturedir``, and a
  ``meshdir``/``texturedir`` on the same or a later ``<compiler>`` overrides it;
- ``<mesh file>`` and ``<hfield file>``: in ``meshdir``; ``<texture file>`` and its six
  cube faces (``fileright`` ... ``fileback``): in ``texturedir``; each folder relative
  to the main model file's folder unless absolute;
- ``strippath="true"`` drops the folders of mesh, height-field and texture names;
- ``\\`` separates folders as ``/`` does; a name starting with ``/`` or ``\\``, or holding
  ``:/`` or ``:\\``, is absolute; ``.`` and ``..`` are reduced on the text (not through
  symbolic links), then the file system resolves the rest.

An asset without a name keeps the one MuJoCo gives it (its file's name without folder
and extension: geoms use it) when its file name is replaced. A mesh or texture file
found nowhere is, with ``missing``, listed there and left unread for
:mod:`workcell.robots.mjcf_missing` (a name leading outside ``root`` is refused all the
same); ``wanted=False`` reads none (only the kinematics are wanted).

With ``root``: names and folders may not be absolute or hold ``~`` or ``..``; every
file must resolve inside ``root`` (symbolic links followed) and have one hard link;
refusals never tell whether a file outside the root exists. Skins, flex components and
sub-models from files (``<skin file>``, ``<flexcomp file>``, ``<model file>``) are not
read (a robot's geometry is its geoms). The model file and every file it names count
together against ``max_file_bytes``, and each mesh file's triangles against
``max_facets`` before MuJoCo parses it.
"""

from __future__ import annotations

import os
import posixpath
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import mujoco

from workcell import limits
from workcell.confine import leaves_root
from workcell.errors import ModelError
from workcell.files import read_bytes
from workcell.robots.meshfile import count_facets, parse_xml
from workcell.robots.standin import Missing

__all__ = ["MjcfFiles", "read_mjcf", "spec_from_files"]

_CUBE = ("fileright", "fileleft", "fileup", "filedown", "filefront", "fileback")
_DIRS = ("assetdir", "meshdir", "texturedir")
_FOLDER = {"mesh": "meshdir", "hfield": "meshdir", "texture": "texturedir"}
_NOT_READ = ("skin", "flexcomp", "model")
_STAND_IN = {  # files that may be missing, and what stands in (robots.mjcf_missing)
    "mesh": "a capsule between its body's joints stands in",
    "texture": "a plain grey texture stands in",
}
_MAX_INCLUDES = 1000  # include elements in one model (each file's bytes count too)
_SAFE = re.compile(r"[^A-Za-z0-9._-]")


@dataclass
class MjcfFiles:
    """A model ready for MuJoCo: ``xml`` (the main file, file names replaced by asset
    names), ``includes`` and ``assets`` (asset name -> bytes), ``data`` (the main file's
    bytes as read) and ``names`` (asset name -> the file it came from, for messages)."""

    xml: str
    includes: dict[str, bytes] = field(default_factory=dict)
    assets: dict[str, bytes] = field(default_factory=dict)
    data: bytes = b""
    names: dict[str, str] = field(default_factory=dict)
    absent: set[str] = field(default_factory=set)  # asset names of files not read

    def explain(self, message: str) -> str:
        """``message`` (MuJoCo's) with asset names put back as the files they came from."""
        for key, name in sorted(self.names.items(), key=lambda kv: -len(kv[0])):
            message = message.replace(key, name)
        return message


@dataclass
class _Doc:
    path: str
    root: ET.Element
    lines: dict[ET.Element, int]


def _is_abs(name: str) -> bool:
    return name.startswith(("/", "\\")) or ":/" in name or ":\\" in name


def _join(*parts: str) -> str:
    """MuJoCo's combination of folders and a name: the last absolute part starts anew;
    '\\' is a separator; '.' and '..' reduced on the text."""
    out = ""
    for part in parts:
        if not part:
            continue
        part = part.replace("\\", "/")
        out = part if _is_abs(part) or not out else f"{out.rstrip('/')}/{part}"
    return posixpath.normpath(out) if out else out


def _strip(name: str) -> str:
    return re.split(r"[/\\]", name)[-1]


class _Reader:
    """Reads one model's files (module doc); ``fail`` makes the messages."""

    def __init__(
        self, path: Path, root: Path | None, missing: Missing | None = None, wanted: bool = True
    ) -> None:
        self.path, self.root = path, root
        self.missing, self.wanted = missing, wanted
        self.base = str(path.parent)
        self.total = 0
        self.includes = 0
        self.out = MjcfFiles("")
        self.keys: dict[str, str] = {}  # resolved file -> asset name
        self.docs: dict[str, _Doc] = {}  # include file -> its document
        self.child: dict[int, _Doc] = {}  # id of an include element -> the document

    def fail(self, doc: _Doc, el: ET.Element, attr: str, why: str) -> ModelError:
        line = doc.lines.get(el, "?")
        return ModelError(
            f"MJCF file '{doc.path}': line {line}: <{el.tag} {attr}={el.get(attr)!r}>: {why}"
        )

    def check_name(self, doc: _Doc, el: ET.Element, attr: str, value: str) -> None:
        """With a root: no absolute name, '~' or '..' (module doc)."""
        if self.root is None:
            return
        parts = re.split(r"[/\\]", value)
        if _is_abs(value) or value.startswith("~") or ".." in parts:
            raise self.fail(
                doc, el, attr, "refused: it leads outside the root folder; files must lie "
                "beside the model, inside the root (no absolute names, '~' or '..')"
            )  # fmt: skip

    def read(self, doc: _Doc, el: ET.Element, attr: str, full: str, what: str) -> bytes:
        """The bytes of ``full`` (the file ``el``'s ``attr`` names), checked and bounded."""
        try:
            data = read_bytes(full, what=what, error=ModelError, root=self.root)
        except ModelError as exc:
            why = str(exc)
            if self.root is not None and ("root folder" in why or "hard links" in why):
                why = "refused: " + why.split("': ", 1)[-1]  # the same whether it exists
            raise self.fail(doc, el, attr, why) from None
        self.total += len(data)
        limits.check(
            "max_file_bytes", self.total, f"MJCF file '{self.path}' and the files it names"
        )
        return data

    def key(self, full: str, prefix: str) -> str:
        if full not in self.keys:
            name = _SAFE.sub("_", _strip(full))[-80:] or "file"
            self.keys[full] = f"wc{prefix}{len(self.keys)}_{name}"
            self.out.names[self.keys[full]] = full
        return self.keys[full]

    # -------------------------------------------------------------- includes
    def load(self, path: str, data: bytes, stack: tuple[str, ...]) -> _Doc:
        """The document at ``path``; every file it includes read and parsed (once each),
        its include elements pointed at their asset names."""
        top, lines = parse_xml(data, f"MJCF file '{path}'")
        doc = _Doc(path, top, lines)
        for el in top.iter("include"):
            value = el.get("file")
            if value is None:
                continue
            self.includes += 1
            if self.includes > _MAX_INCLUDES:
                raise self.fail(doc, el, "file", f"refused: more than {_MAX_INCLUDES} includes")
            self.check_name(doc, el, "file", value)
            full = _join(self.base, value)
            if full in stack:
                raise self.fail(doc, el, "file", "includes a file that includes it")
            if full not in self.docs:
                sub = self.read(doc, el, "file", full, "MJCF include file")
                self.key(full, "i")
                self.docs[full] = self.load(full, sub, (*stack, full))
            self.child[id(el)] = self.docs[full]
            el.set("file", self.keys[full])
        return doc

    def walk(self, doc: _Doc) -> Iterator[tuple[_Doc, ET.Element]]:
        """Every element in document order, included files expanded in place."""
        for el in doc.root.iter():
            yield doc, el
            if id(el) in self.child:
                yield from self.walk(self.child[id(el)])

    def run(self) -> MjcfFiles:
        data = read_bytes(self.path, what="MJCF file", error=ModelError, root=self.root)
        self.total = len(data)
        main = str(self.path)
        top = self.load(main, data, (main,))
        settings: dict[str, Any] = {"meshdir": "", "texturedir": "", "strippath": False}
        for doc, el in list(self.walk(top)):  # document order: the last value wins
            if el.tag != "compiler":
                continue
            if el.get("assetdir") is not None:
                settings["meshdir"] = settings["texturedir"] = el.get("assetdir", "")
            for attr in ("meshdir", "texturedir"):
                if el.get(attr) is not None:
                    settings[attr] = el.get(attr, "")
            if el.get("strippath") is not None:
                settings["strippath"] = el.get("strippath") == "true"
            for attr in _DIRS:
                if el.get(attr) is not None:
                    self.check_name(doc, el, attr, el.get(attr, ""))
        for attr in _DIRS:  # every name below is made whole: no folder is left to apply
            for doc in (top, *self.docs.values()):
                for el in doc.root.iter("compiler"):
                    el.attrib.pop(attr, None)
        for doc in (top, *self.docs.values()):
            self.replace_names(doc, settings)
        for full, doc in self.docs.items():
            self.out.includes[self.keys[full]] = ET.tostring(doc.root, encoding="utf-8")
        self.out.xml = ET.tostring(top.root, encoding="unicode")
        self.out.data = data
        return self.out

    # -------------------------------------------------------------- asset files
    def replace_names(self, doc: _Doc, settings: dict[str, Any]) -> None:
        for el in doc.root.iter():
            if el.tag == "include":
                continue
            attrs = [a for a in el.attrib if a == "file" or a in _CUBE]
            if not attrs:
                continue
            if el.tag in _NOT_READ or el.tag not in _FOLDER:
                raise self.fail(
                    doc, el, attrs[0], "is not read: a robot's geometry comes from its geoms "
                    "(meshes, height fields and textures are read from files); remove it"
                )  # fmt: skip
            folder = settings[_FOLDER[el.tag]]
            if el.get("name") is None and el.get("file") is not None:
                # MuJoCo names an unnamed asset by its file (no folder, no extension):
                # keep that name, which geoms use, when the file name is replaced
                el.set("name", posixpath.splitext(_strip(el.get("file", "")))[0])
            for attr in attrs:
                value = el.get(attr, "")
                self.check_name(doc, el, attr, value)
                name = _strip(value) if settings["strippath"] else value
                full = _join(self.base, folder, name)
                if full not in self.keys and self.absent(doc, el, value, full):
                    self.out.absent.add(self.key(full, "m"))
                elif full not in self.keys:
                    what = f"{el.tag} file"
                    data = self.read(doc, el, attr, full, what)
                    if el.tag == "mesh":
                        n = count_facets(data, Path(full).suffix)
                        limits.check("max_facets", n, f"MJCF file '{doc.path}': mesh file '{full}'")
                    self.out.assets[self.key(full, "f")] = data
                el.set(attr, self.keys[full])

    def absent(self, doc: _Doc, el: ET.Element, value: str, full: str) -> bool:
        """Whether mesh or texture file ``full`` is left unread: not wanted (only the
        kinematics are), or found nowhere and so listed in ``missing``
        (:mod:`workcell.robots.mjcf_missing` stands in for it)."""
        if el.tag not in _STAND_IN:
            return False
        if not self.wanted:
            return True
        if self.missing is None or os.path.lexists(full):
            return False
        if self.root is not None and leaves_root(full, self.root) is not None:
            return False  # refused by read(), the same whether it exists outside
        where = f"<{el.tag}> (line {doc.lines.get(el, '?')} of '{doc.path}')"
        self.missing.add(value, where, [full], _STAND_IN[el.tag])
        return True


def read_mjcf(
    path: str | os.PathLike,
    root: str | os.PathLike | None = None,
    *,
    missing: Missing | None = None,
    wanted: bool = True,
) -> MjcfFiles:
    """The MJCF file ``path`` and every file it names (module doc), ready for
    :func:`spec_from_files`. ModelError for a file refused or unreadable (naming the
    element and its line), LimitError over the work limits. With ``missing``, a mesh or
    texture file found nowhere is listed there instead (its asset name in
    ``MjcfFiles.absent``); ``wanted`` False reads no mesh or texture file at all."""
    p = Path(os.path.abspath(path))
    return _Reader(p, None if root is None else Path(root), missing, wanted).run()


def spec_from_files(files: MjcfFiles, what: str) -> mujoco.MjSpec:
    """MuJoCo's parse of ``files`` (opening no file); ModelError naming ``what``."""
    try:
        return mujoco.MjSpec.from_string(files.xml, include=files.includes, assets=files.assets)
    except ValueError as exc:
        raise ModelError(f"{what}: MuJoCo cannot read it: {files.explain(str(exc))}") from None
