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
    "workcell.confine",
    "workcell.tempfiles",
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
    "workcell.robots.ik_family",
    "workcell.robots.ik_refine",
    "workcell.robots.ik_numeric",
    "workcell.robots.ik_common",
    "workcell.robots.ik_mink",
    "workcell.robots.ik_newton",
    "workcell.robots.mjcf",
    "workcell.robots.mjcf_geoms",
    "workcell.robots.mjcf_xml",
    "workcell.robots.mjcf_files",
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
    "workcell.examples.plan_problems",
    "workcell.cli_common",
    "workcell.moved",
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
    "workcell.sim.planned",
    "workcell.sim.resting",
    "workcell.sim.choosing",
    "workcell.sim.task_commands",
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
    "workcell.program.progcli",
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
    "workcell.robotprog.krl_data",
    "workcell.robotprog.reading",
    "workcell.robotprog.rapid_exprs",
    "workcell.robotprog.fanuc_file",
    "workcell.robotprog.rapid_run",
    "workcell.robotprog.fanuc_run",
    "workcell.robotprog.urscript_run",
    "workcell.robotprog.cli",
    "workcell.client",
    "workcell.client_link",
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
    "workcell.record.obstacle_demo",
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
    "workcell.cell.devices",
    "workcell.cell.device_types",
    "workcell.cell.device_json",
    "workcell.cell.compile_devices",
    "workcell.sim.devices",
    "workcell.sim.sensors",
    "workcell.sim.signals",
    "workcell.sim.throughput",
    "workcell.sim.physics_devices",
    "workcell.logic",
    "workcell.logic.scheduler",
    "workcell.logic.clock",
    "workcell.logic.block",
    "workcell.logic.programs",
    "workcell.program.logiccommands",
    "workcell.program.grammar_logic",
    "workcell.program.wcl_programs",
    "workcell.record.gantt",
    "workcell.record.devices",
    "workcell.record.rr_devices",
    "workcell.record.conveyor_demo",
    "workcell.record.demo_files",
    "workcell.examples.conveyor",
]


@pytest.mark.filterwarnings("ignore:.* moved to .*:DeprecationWarning")
@pytest.mark.parametrize("name", MODULES)
def test_every_public_name_resolves(name):
    mod = importlib.import_module(name)
    assert mod.__all__, name
    for attr in mod.__all__:
        assert hasattr(mod, attr), f"{name}.{attr}"


def test_moved_names_resolve_at_their_old_place_with_a_warning():
    # each module whose names moved up the layers sets a workcell.moved look-up; the
    # old spelling gives the very object at its new place, and a DeprecationWarning
    found = {}
    for name in (".".join(m.parts).removesuffix(".__init__") for m in _module_paths()):
        mod = importlib.import_module(name)
        for value in vars(mod).values():
            if callable(value) and hasattr(value, "moved"):
                found[name] = value.moved
    assert found == {
        "workcell.plan": {"random_problem": "workcell.examples.plan_problems"},
        "workcell.plan.motion": {"PlanningCommands": "workcell.sim.planned"},
        "workcell.plan.resting": {"RestingCommands": "workcell.sim.resting"},
        "workcell.plan.choices": {"ChoiceHelpers": "workcell.sim.choosing"},
        "workcell.plan.tasks": {"TaskCommands": "workcell.sim.task_commands"},
        "workcell.plan.scenes": dict.fromkeys(
            ("ROBOT", "Problem", "penetrations", "random_problem"),
            "workcell.examples.plan_problems",
        ),
        "workcell.examples.obstacle": dict.fromkeys(
            ("demo", "picture"), "workcell.record.obstacle_demo"
        ),
    }
    for old, names in found.items():
        for attr, new in names.items():
            with pytest.warns(DeprecationWarning, match=f"{old}.{attr} moved to {new}.{attr}"):
                value = getattr(importlib.import_module(old), attr)
            assert value is getattr(importlib.import_module(new), attr)
    from workcell.sim import Simulator

    for mixin in ("PlanningCommands", "RestingCommands", "TaskCommands", "ChoiceHelpers"):
        assert any(c.__name__ == mixin for c in Simulator.__mro__)
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        importlib.import_module("workcell.plan.motion").nothing  # noqa: B018


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
    # imported (the layers: test_imports_run_one_way_down_the_documented_layers). One
    # interpreter imports each module afresh.
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


# ---------------------------------------------------------------- layers and layout
def _module_paths() -> list[Path]:
    """Every module of the package, as paths relative to the repository, no suffix."""
    return sorted(p.relative_to(ROOT).with_suffix("") for p in (ROOT / "workcell").rglob("*.py"))


def _node(module: str) -> str | None:
    """The layer-drawing name of ``module``: its folder ("sim/") or, for a module of the
    package's top folder, its file ("cli.py"); None for the package itself (its facade)."""
    parts = module.split(".")
    if len(parts) == 1:
        return None
    if (ROOT / "workcell" / parts[1]).is_dir():
        return parts[1] + "/"
    return parts[1] + ".py"


def _is_module(name: str) -> bool:
    path = ROOT / Path(*name.split("."))
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def import_graph() -> dict[tuple[str, str], list[str]]:
    """(from, to) -> where: every import of a workcell module by another, at any depth of
    the code (in functions, under TYPE_CHECKING), and every string naming a workcell
    module (look-up tables such as ``SUBCOMMAND_MODULES``), except the tables of names
    that moved (:mod:`workcell.moved`), grouped by layer-drawing name (:func:`_node`)."""
    import ast

    edges: dict[tuple[str, str], list[str]] = {}
    for rel in _module_paths():
        name = ".".join(rel.parts).removesuffix(".__init__")
        tree = ast.parse((ROOT / rel).with_suffix(".py").read_text())
        exempt = {
            id(c)
            for call in ast.walk(tree)
            if isinstance(call, ast.Call) and getattr(call.func, "id", "") == "moved"
            for c in ast.walk(call)
        }
        for node in ast.walk(tree):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                assert node.level == 0, f"{name}: relative import"
                base = node.module or ""
                for a in node.names:
                    sub = f"{base}.{a.name}"
                    if _is_module(sub):
                        targets.append(sub)
                    elif not (base == "workcell" and a.name == "__version__"):
                        targets.append(base)
            elif (
                isinstance(node, ast.Constant)
                and isinstance(node.value, str)
                and node.value.startswith("workcell.")
                and id(node) not in exempt
                and _is_module(node.value)
            ):
                targets = [node.value]
            for target in targets:
                if not target.startswith("workcell"):
                    continue
                a, b = _node(name), _node(target)
                assert b is not None or a is None, f"{name} imports the package facade: {target}"
                if a is not None and b is not None and a != b:
                    line = getattr(node, "lineno", "?")
                    edges.setdefault((a, b), []).append(f"{name}:{line} -> {target}")
    return edges


def documented_layers() -> list[list[str]]:
    """The layers of docs/architecture.md's drawing ("Layers"), top first: the folder
    and module names at the start of each line."""
    import re

    text = (ROOT / "docs" / "architecture.md").read_text()
    block = text.split("\n## Layers\n", 1)[1].split("```text\n", 1)[1].split("```", 1)[0]
    layers = []
    for line in block.splitlines():
        names = []
        for word in line.split():
            if not re.fullmatch(r"\w+/|\w+\.py", word):
                break
            names.append(word)
        assert names, f"a line of the layer drawing names no folder or module: {line!r}"
        layers.append(names)
    return layers


def test_imports_run_one_way_down_the_documented_layers():
    layers = documented_layers()
    level = {n: i for i, names in enumerate(layers) for n in names}
    nodes = {_node(".".join(p.parts).removesuffix(".__init__")) for p in _module_paths()}
    nodes.discard(None)
    missing = sorted(n for n in nodes if n not in level)
    assert not missing, f"not in docs/architecture.md's layer drawing: {missing}"
    stale = sorted(n for n in level if n not in nodes)
    assert not stale, f"in the layer drawing but not in the package: {stale}"
    edges = import_graph()
    up = {k: v for k, v in edges.items() if level[k[1]] < level[k[0]]}
    assert not up, "imports pointing up the layers: " + "; ".join(
        f"{a} -> {b} ({where[0]})" for (a, b), where in sorted(up.items())
    )
    # and no two folders (or modules of one layer) import each other, through any path
    reach = {n: {b for (a, b) in edges if a == n} for n in nodes}
    changed = True
    while changed:
        changed = False
        for n in nodes:
            more = set().union(*(reach[m] for m in reach[n])) - reach[n]
            if more:
                reach[n] |= more
                changed = True
    cycles = sorted(n for n in nodes if n in reach[n])
    assert not cycles, f"import cycles across folders through: {cycles}"


def test_the_import_check_sees_every_kind_of_arrow(tmp_path):
    # the graph above must see imports in functions, under TYPE_CHECKING and by name
    edges = import_graph()
    assert "workcell.record.render:" in " ".join(edges[("record/", "sim/")])  # TYPE_CHECKING
    assert ("cli.py", "study/") in edges  # a string in SUBCOMMAND_MODULES
    assert any("program.cli" in w for w in edges[("program/", "cli_common.py")])  # in a function
    assert ("plan/", "examples/") not in edges  # a moved-names table is not an arrow


def test_the_readme_layout_names_every_folder_and_top_module():
    import re

    text = (ROOT / "README.md").read_text()
    block = text.split("\n## Layout\n", 1)[1].split("```text\n", 1)[1].split("```", 1)[0]
    heads = set(re.findall(r"^ {0,2}(\w+/|\w+\.py)\s", block, re.M))
    missing = []
    for rel in _module_paths():
        if len(rel.parts) > 2:
            if f"{rel.parts[1]}/" not in heads:
                missing.append(f"{rel.parts[1]}/")
        elif rel.name != "__init__" and not re.search(rf"\b{rel.name}\b", block):
            missing.append(f"{rel.name}.py")
    assert not missing, f"not in README.md's Layout: {sorted(set(missing))}"
