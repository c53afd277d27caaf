"""The public surface: names in __all__ resolve, README code runs, the demo CLI works."""

from __future__ import annotations

import importlib
import json
import re
from pathlib import Path

import pytest

import workcell
from workcell.cli import main

ROOT = Path(__file__).resolve().parents[1]
MODULES = [
    "workcell",
    "workcell.errors",
    "workcell.spatial",
    "workcell.files",
    "workcell.solids",
    "workcell.modeller.surface",
    "workcell.modeller.model",
    "workcell.modeller.meshprops",
    "workcell.modeller.world",
    "workcell.modeller.storage",
    "workcell.modeller.solids",
    "workcell.modeller.sweeps",
    "workcell.modeller.csg",
    "workcell.modeller.patches",
    "workcell.modeller.show",
    "workcell.robots",
    "workcell.robots.robot",
    "workcell.robots.puma",
    "workcell.robots.geometry",
    "workcell.robots.gripper",
    "workcell.robots.ik_closed",
    "workcell.robots.ik_numeric",
    "workcell.robots.ik_common",
    "workcell.robots.ik_mink",
    "workcell.robots.ik_newton",
    "workcell.robots.mjcf",
    "workcell.robots.chain",
    "workcell.robots.axes",
    "workcell.robots.opw",
    "workcell.robots.opw_solve",
    "workcell.robots.ur",
    "workcell.robots.ur_solve",
    "workcell.robots.ik_wrap",
    "workcell.robots.library",
    "workcell.robots.models",
    "workcell.robots.arm_geometry",
    "workcell.robots.cli",
    "workcell.meshgeoms",
    "workcell.decompose",
    "workcell.cell",
    "workcell.cell.workcell",
    "workcell.cell.compile",
    "workcell.sim",
    "workcell.sim.timeline",
    "workcell.sim.simulator",
    "workcell.sim.cartesian",
    "workcell.sim.contacts",
    "workcell.sim.grasp",
    "workcell.sim.gripping",
    "workcell.sim.profiles",
    "workcell.sim.tasks",
    "workcell.sim.planning",
    "workcell.sim.concurrent",
    "workcell.checks",
    "workcell.sim.physics",
    "workcell.sim.physics_result",
    "workcell.sim.physics_support",
    "workcell.program",
    "workcell.program.args",
    "workcell.program.base",
    "workcell.program.cellcommands",
    "workcell.program.cli",
    "workcell.program.commands",
    "workcell.program.completion",
    "workcell.program.format",
    "workcell.program.grammar_model",
    "workcell.program.grammar_sim",
    "workcell.program.interpreter",
    "workcell.program.keytree",
    "workcell.program.language",
    "workcell.program.lexer",
    "workcell.program.params",
    "workcell.program.protocol",
    "workcell.program.server",
    "workcell.program.session",
    "workcell.program.shell",
    "workcell.program.simcommands",
    "workcell.program.solidcommands",
    "workcell.program.targets",
    "workcell.client",
    "workcell.record",
    "workcell.record.render",
    "workcell.record.gl",
    "workcell.record.sheets",
    "workcell.record.rerun_log",
    "workcell.record.rr_scene",
    "workcell.record.rr_images",
    "workcell.record.cli_render",
    "workcell.examples.thesis_joints",
    "workcell.examples.thesis_pick_place",
    "workcell.examples.thesis_handoff",
    "workcell.study",
    "workcell.study.spec",
    "workcell.study.candidates",
    "workcell.study.program",
    "workcell.study.variants",
    "workcell.study.metrics",
    "workcell.study.evaluation",
    "workcell.study.prepare",
    "workcell.study.pool",
    "workcell.study.backends",
    "workcell.study.results",
    "workcell.study.plots",
    "workcell.study.runner",
    "workcell.study.cli",
]


@pytest.mark.parametrize("name", MODULES)
def test_every_public_name_resolves(name):
    mod = importlib.import_module(name)
    assert mod.__all__, name
    for attr in mod.__all__:
        assert hasattr(mod, attr), f"{name}.{attr}"


def test_errors_form_one_family():
    for attr in workcell.errors.__all__:
        assert issubclass(getattr(workcell.errors, attr), workcell.WorkcellError)
    assert issubclass(workcell.UnreachableError, workcell.KinematicsError)


def test_readme_python_example_runs(tmp_path, monkeypatch, capsys):
    text = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert blocks
    monkeypatch.chdir(tmp_path)
    for code in blocks:
        exec(compile(code, "README.md", "exec"), {})
    out = capsys.readouterr().out.split()
    # the README promises these printed values (thesis cube and parallelepiped)
    assert out[:3] == ["1.0", "6", "9.0"]
    assert "cube" in out  # the simulator example grasps the cube
    assert (tmp_path / "parts.json").exists()


def test_readme_starts_with_the_two_commands():
    lines = (ROOT / "README.md").read_text().splitlines()
    block = lines[lines.index("```sh") + 1 : lines.index("```sh") + 3]
    assert block[0].startswith("make demo")
    assert block[1].startswith("make test")
    assert "make test" in (ROOT / ".ci" / "run").read_text()
    demo = (ROOT / "Makefile").read_text().split("\ndemo:")[1].split("\n\n")[0]
    assert "workcell demo handoff" in demo
    assert "--save handoff.rrd" in demo
    assert "--render handoff.png" in demo


def test_demo_solids_json(tmp_path, capsys):
    out_file = tmp_path / "m.json"
    assert main(["demo", "solids", "--json", "--save", str(out_file)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["round_trip_exact"] is True
    rows = {r["name"]: r for r in data["solids"]}
    assert rows["cube1"]["volume"] == pytest.approx(1.0, abs=1e-12)
    assert rows["para_block"]["volume"] == pytest.approx(9.0, abs=1e-12)
    assert rows["para_object"]["volume"] == pytest.approx(9.0, abs=1e-12)
    for r in data["solids"]:
        assert r["valid"], r["name"]
        if r["exact_volume"] is not None:
            assert r["volume"] == pytest.approx(r["exact_volume"], rel=1e-12), r["name"]
    assert out_file.exists()


def test_readme_shell_transcript_is_what_the_shell_prints():
    import subprocess
    import sys

    text = (ROOT / "README.md").read_text()
    start = text.index("```\nworkcell> ") + len("```\n")
    block = text[start : text.index("```", start)]
    lines = [ln[len("workcell> ") :] for ln in block.splitlines() if ln.startswith("workcell> ")]
    run = subprocess.run(
        [sys.executable, "-m", "workcell.cli", "shell", "--echo"],
        input="\n".join(lines) + "\n",
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=120,
    )
    assert run.stdout.strip() == block.strip()
