"""The public surface: names in __all__ resolve, the demo CLI works (README and docs code:
tests/test_doc_blocks.py)."""

from __future__ import annotations

import importlib
import json
from pathlib import Path

import pytest

import workcell
from workcell.cli import main

ROOT = Path(__file__).resolve().parents[1]
MODULES = [
    "workcell",
    "workcell.errors",
    "workcell.spatial",
    "workcell.spatial_checks",
    "workcell.files",
    "workcell.solids",
    "workcell.modeller.surface",
    "workcell.modeller.model",
    "workcell.modeller.meshprops",
    "workcell.modeller.world",
    "workcell.modeller.hashgroup",
    "workcell.modeller.storage",
    "workcell.modeller.solids",
    "workcell.modeller.sweeps",
    "workcell.modeller.csg",
    "workcell.modeller.patches",
    "workcell.modeller.show",
    "workcell.modeller.contours",
    "workcell.modeller.entities",
    "workcell.modeller.model_base",
    "workcell.modeller.model_edit",
    "workcell.modeller.model_attach",
    "workcell.modeller.selfintersect",
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
    "workcell.robots.mjcf_geoms",
    "workcell.robots.mjcf_xml",
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
    "workcell.plan",
    "workcell.plan.scene",
    "workcell.plan.rrt",
    "workcell.plan.motion",
    "workcell.plan.grasps",
    "workcell.plan.choices",
    "workcell.plan.tasks",
    "workcell.plan.support",
    "workcell.plan.resting",
    "workcell.plan.scenes",
    "workcell.examples.obstacle",
    "workcell.decompose",
    "workcell.cell",
    "workcell.cell.workcell",
    "workcell.cell.items",
    "workcell.cell.cell_json",
    "workcell.cell.compile",
    "workcell.sim",
    "workcell.sim.timeline",
    "workcell.sim.simulator",
    "workcell.sim.frames",
    "workcell.sim.readback",
    "workcell.sim.cartesian",
    "workcell.sim.contacts",
    "workcell.sim.grasp",
    "workcell.sim.gripping",
    "workcell.sim.profiles",
    "workcell.sim.tasks",
    "workcell.sim.planning",
    "workcell.sim.paths",
    "workcell.sim.pieces",
    "workcell.sim.concurrent",
    "workcell.checks",
    "workcell.sim.physics",
    "workcell.sim.physics_events",
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
    "workcell.program.grammar_cell",
    "workcell.program.grammar_motion",
    "workcell.program.grammar_tasks",
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
    "workcell.program.runcommands",
    "workcell.program.motioncommands",
    "workcell.program.taskcommands",
    "workcell.program.readcommands",
    "workcell.program.solidcommands",
    "workcell.program.targets",
    "workcell.program.progcommands",
    "workcell.robotprog",
    "workcell.robotprog.instructions",
    "workcell.robotprog.rotations",
    "workcell.robotprog.configs",
    "workcell.robotprog.writing",
    "workcell.robotprog.urscript",
    "workcell.robotprog.krl",
    "workcell.robotprog.rapid",
    "workcell.robotprog.fanuc",
    "workcell.robotprog.source",
    "workcell.robotprog.exprs",
    "workcell.robotprog.runtime",
    "workcell.robotprog.kuka_values",
    "workcell.robotprog.read_krl",
    "workcell.robotprog.read_rapid",
    "workcell.robotprog.read_urscript",
    "workcell.robotprog.read_fanuc",
    "workcell.robotprog.krl_run",
    "workcell.robotprog.krl_exprs",
    "workcell.robotprog.rapid_run",
    "workcell.robotprog.fanuc_run",
    "workcell.robotprog.urscript_run",
    "workcell.robotprog.cli",
    "workcell.client",
    "workcell.record",
    "workcell.record.render",
    "workcell.record.gl",
    "workcell.record.camera",
    "workcell.record.sheets",
    "workcell.record.rerun_log",
    "workcell.record.rr_scene",
    "workcell.record.rr_frames",
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


@pytest.mark.slow
def test_every_module_imports_first_in_a_fresh_interpreter_and_the_package_is_light():
    # `import workcell` loads its names on first use (the command line starts fast and
    # its Ctrl-C handling covers the heavy imports), so each module may be the first one
    # imported: no import cycle may depend on the order (the simulator and its planning
    # mixins import each other's modules). One interpreter imports each module afresh.
    names = sorted(
        ".".join(p.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
        for p in (ROOT / "workcell").rglob("*.py")
    )
    code = (
        "import importlib, sys\n"
        "import workcell\n"
        "assert 'mujoco' not in sys.modules and 'trimesh' not in sys.modules\n"
        "base = set(sys.modules)\n"
        f"for name in {names!r}:\n"
        "    for m in set(sys.modules) - base:\n"
        "        if m.startswith('workcell'):\n"
        "            del sys.modules[m]\n"
        "    importlib.import_module(name)\n"
    )
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
