"""assets/: the example cells are the files their builders write today, and assets/README.md
lists exactly what is there."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from workcell.cell.workcell import Workcell
from workcell.examples import CELLS, example

ASSETS = Path(__file__).resolve().parents[1] / "assets"


def asset_of(name: str) -> Path:
    """The file of example cell ``name``: its builder module's name, .json."""
    return ASSETS / f"{CELLS[name].rsplit('.', 1)[1]}.json"


@pytest.mark.parametrize("name", sorted(CELLS))
def test_each_example_cell_file_is_what_its_builder_makes(name):
    path = asset_of(name)
    assert path.is_file(), f"missing {path}: workcell export-cell {name} --out {path}"
    built = example(name).build()
    assert json.loads(path.read_text()) == built.to_dict(), (
        f"{path.name} is out of date: workcell export-cell {name} --out assets/{path.name}"
    )
    assert Workcell.load(path) == built


def test_export_cell_writes_the_file(tmp_path):
    from workcell.cli import main

    out = tmp_path / "cell.json"
    assert main(["export-cell", "pick-place", "--out", str(out)]) == 0
    assert out.read_text() == asset_of("pick-place").read_text()
    again = tmp_path / "again.json"
    assert main(["export-cell", str(out), "--out", str(again)]) == 0  # a file re-saved
    assert again.read_text() == out.read_text()


def test_the_assets_readme_lists_exactly_the_files():
    text = (ASSETS / "README.md").read_text()
    listed = set(re.findall(r"^\| `([^`]+)` \|", text, re.M))
    present = {p.name for p in ASSETS.iterdir() if p.name != "README.md"}
    assert listed == present
