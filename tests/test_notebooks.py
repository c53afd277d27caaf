"""The tutorials in notebooks/: committed without outputs, and each runs top to bottom in a
fresh kernel (the venv's Python, ``MUJOCO_GL=egl``) on its small sizes (``SMALL = True``).

The numbers the notebooks print are checked against values computed here by hand: box
volumes and inertias, regular-polygon areas, the Puma 560's tool point from its DH table
(DESIGN.md), eq. 4.27 for the thesis's example 1, and where the parts must end up.
One test per notebook, so ``pytest -n 2`` runs two kernels at a time.
"""

from __future__ import annotations

import base64
import io
import math
import re
import sys
from pathlib import Path

import nbformat
import numpy as np
import pytest
from jupyter_client.kernelspec import KernelSpecManager
from jupyter_client.manager import KernelManager
from nbclient import NotebookClient
from PIL import Image

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = ROOT / "notebooks"
NAMES = (
    "quickstart",
    "build_your_own_cell",
    "modeller",
    "kinematics",
    "thesis_examples",
    "study",
    "conveyor",
)
PICTURES = {
    "quickstart": 4,
    "build_your_own_cell": 2,
    "modeller": 1,
    "kinematics": 3,
    "thesis_examples": 3,
    "study": 2,
    "conveyor": 2,
}
FLOAT = r"(-?\d+(?:\.\d*)?(?:e[-+]?\d+)?)"


def _gon(n: int, r: float) -> float:
    """Area (m^2) of a regular n-gon inscribed in a circle of radius r (m)."""
    return n / 2 * r**2 * math.sin(2 * math.pi / n)


def _number(text: str, label: str) -> float:
    """The first number printed after ``label`` (a literal prefix)."""
    found = re.search(re.escape(label) + r"\s*" + FLOAT, text)
    assert found, f"{label!r} not printed; output:\n{text[-2000:]}"
    return float(found.group(1))


def _vector(text: str, label: str) -> list[float]:
    """The list ``[a, b, ...]`` printed after ``label``."""
    found = re.search(re.escape(label) + r"\s*\[([^\]]*)\]", text)
    assert found, f"{label!r} not printed; output:\n{text[-2000:]}"
    return [float(v) for v in found.group(1).replace(",", " ").split()]


def _run(name: str, cwd: Path) -> tuple[str, list[np.ndarray]]:
    """Execute notebooks/NAME.ipynb in a fresh kernel of this interpreter; its stdout text
    and the PNG pictures it displayed."""
    nb = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
    # no kernel dirs: only ipykernel's own spec, which launches sys.executable (the venv's
    # Python), whatever "python3" kernels the user or the system has installed
    km = KernelManager(kernel_name="python3", kernel_spec_manager=KernelSpecManager(kernel_dirs=[]))
    assert km.kernel_spec.argv[0] == sys.executable
    km.connection_file = str(cwd / "kernel.json")  # not a tmp*.json file in the system's /tmp
    client = NotebookClient(
        nb, km=km, timeout=120, resources={"metadata": {"path": str(cwd)}}, allow_errors=False
    )
    try:
        client.execute()  # raises CellExecutionError with the cell and traceback on failure
    finally:  # nbclient leaves a kernel manager it was given running: stop it, remove its file
        if km.has_kernel:
            km.shutdown_kernel(now=True)
        km.cleanup_resources()
    assert not (cwd / "kernel.json").exists()
    text, images = [], []
    for cell in nb.cells:
        for out in cell.get("outputs", []):
            if out.get("output_type") == "stream" and out.get("name") == "stdout":
                text.append(out["text"])
            elif "image/png" in out.get("data", {}):
                png = base64.b64decode(out["data"]["image/png"])
                images.append(np.asarray(Image.open(io.BytesIO(png)).convert("RGB")))
    return "".join(text), images


# ---------------------------------------------------------------------- per notebook
def check_quickstart(out: str) -> None:
    a, r, n = 0.04, 0.008, 24  # the bored cube: side, bore radius, bore sides
    assert _number(out, "bored cube volume:") == pytest.approx(a**3 - _gon(n, r) * a, rel=1e-12)
    assert "grasped: part" in out
    assert "released: part" in out
    # placed centred on the 100 mm stage at (0.25, 0.25), top 0.4 + 0.08 m: its centroid
    # half the 40 mm cube above, its frame (a corner) half the cube below and beside that
    assert _vector(out, "part centroid at (m):") == pytest.approx([0.25, 0.25, 0.50], abs=1e-9)
    assert _vector(out, "part frame (a corner) at (m):") == pytest.approx(
        [0.23, 0.23, 0.48], abs=1e-9
    )


def check_build_your_own_cell(out: str) -> None:
    sheet, side, height = 0.006, 0.15, 0.06  # the bin's walls, side, height (m)
    boxes = side * side * sheet + 4 * sheet * side * height  # its five boxes, summed
    assert _number(out, "bin volume:") == pytest.approx(boxes, rel=1e-12)
    assert _number(out, "part mass:") == pytest.approx(0.04**3 * 2700 * 1e3, rel=1e-12)  # g
    assert "grasped: part" in out
    assert "released: part" in out
    assert _number(out, "collisions:") == 0
    # dropped at the bin's centre (corner 0.17, 0.15 + half its side), 20 mm above its
    # floor (table top 0.4 m + the 6 mm sheet)
    drop = [0.17 + side / 2, 0.15 + side / 2, 0.4 + sheet + 0.02]
    assert _vector(out, "part centroid at (m):") == pytest.approx(drop, abs=1e-9)
    cycle = _number(out, "cycle time:")
    assert _number(out, "eq. 4.27 over the joint path:") == pytest.approx(cycle, abs=1e-4)
    assert _number(out, "script cycle time:") == pytest.approx(cycle, abs=1e-4)  # the .wcl
    assert 15 < cycle < 30
    assert len(re.findall(r"^\d+ key frames -> ", out, re.M)) == 1


def check_modeller(out: str) -> None:
    assert _number(out, "cube volume:") == pytest.approx(1.0, abs=1e-12)
    assert _number(out, "area") == pytest.approx(6.0, abs=1e-12)  # the cube's six faces
    assert _vector(out, "cube centroid (m):") == pytest.approx([0.5, 0.5, 0.5], abs=1e-12)
    assert "square1 is pointed to 6 times" in out
    a, b, c = 2.0, 3.0, 1.5
    v = a * b * c
    assert _number(out, "parallelepiped volume:") == pytest.approx(v, abs=1e-12)
    assert _vector(out, "parallelepiped centroid (m):") == pytest.approx([1, 1.5, 0.75])
    inertia = [v * (b**2 + c**2) / 12, v * (a**2 + c**2) / 12, v * (a**2 + b**2) / 12]
    assert _vector(out, "parallelepiped inertia diagonal:") == pytest.approx(inertia, rel=1e-12)
    assert _number(out, "plate area:") == pytest.approx(0.1 * 0.06 - 2 * _gon(16, 0.01), rel=1e-12)
    fixture = 0.2 * 0.1 * 0.02 + 2 * _gon(24, 0.01) * 0.08
    assert _number(out, "fixture volume:") == pytest.approx(fixture, rel=1e-12)
    assert _number(out, "bench volume:") == pytest.approx(2 * fixture, rel=1e-12)
    assert "ModelError: cannot remove block 'post'" in out
    for n in (8, 32, 128):
        assert _number(out, f"cylinder n={n:3}:") == pytest.approx(_gon(n, 0.05) * 0.1, rel=1e-12)
    plate = 0.1 * 0.06 - 2 * _gon(16, 0.01)
    assert _number(out, "extruded plate:") == pytest.approx(plate * 0.01, rel=1e-12)
    washer = (_gon(24, 0.04) - _gon(24, 0.02)) * 0.015
    assert _number(out, "washer:") == pytest.approx(washer, rel=1e-12)
    a1, a2, h = 0.04**2, 0.02**2, 0.06  # frustum of a square pyramid
    frustum = h / 3 * (a1 + a2 + math.sqrt(a1 * a2))
    assert _number(out, "frustum:") == pytest.approx(frustum, rel=1e-12)
    cube = 0.04**3
    assert _number(out, "u:") == pytest.approx(1.5 * cube, rel=1e-9)  # overlap: half a cube
    assert _number(out, "i:") == pytest.approx(0.5 * cube, rel=1e-9)
    assert _number(out, "d:") == pytest.approx(0.5 * cube, rel=1e-9)
    drilled = (0.2 * 0.1 - _gon(32, 0.02)) * 0.01
    assert _number(out, "drilled:") == pytest.approx(drilled, rel=1e-9)
    assert out.count("valid solid: watertight") == 2
    assert "same entities: True" in out
    assert "same volumes: True" in out


def check_kinematics(out: str) -> None:
    # DESIGN.md's Puma 560 table: d1 = 0.67183, a2 = 0.4318, a3 = 0.0203, d3 = 0.15005,
    # d4 = 0.4318; at q = 0 the tool point is (a2 + a3, -d3, d1 + d4)
    expected = [0.4318 + 0.0203, -0.15005, 0.67183 + 0.4318]
    assert _vector(out, "tool position at q = 0 (m):") == pytest.approx(expected, abs=1e-12)
    assert _number(out, "largest difference:") < 1e-9  # fk vs MuJoCo's tool site
    assert "8 solutions of the tool pose" in out
    configs = re.findall(r"^([lr][ud][nf])\s+True\s", out, re.M)
    assert sorted(configs) == sorted(a + b + c for a in "lr" for b in "ud" for c in "nf")
    assert _number(out, "largest |fk(q) - T| of the 8 solutions:") < 1e-9
    successes = re.findall(r"^ik\(.*?\): success=(\w+), position error " + FLOAT, out, re.M)
    assert len(successes) == 3
    for ok, err in successes:
        assert ok == "True"
        assert float(err) < 1e-6
    assert "unreachable: success=False; reason: unreachable" in out
    # the library: every robot has a closed-form family; a UR5e pose has 8 solutions
    assert re.findall(r"^ur5e\s+6 axes, family ur", out, re.M)
    assert re.findall(r"^kuka_kr6_r700\s+6 axes, family opw", out, re.M)
    assert "UR5e: 8 solutions of the tool pose" in out
    ur = re.findall(r"^ur5e ([lr][ud][nf])\s+True\s", out, re.M)
    assert sorted(ur) == sorted(a + b + c for a in "lr" for b in "ud" for c in "nf")
    assert _number(out, "largest |fk(q) - T| of the UR5e solutions:") < 1e-9
    # a KUKA KR 16 read from its ROS-Industrial URDF (rtb-data): an OPW arm, 4 solutions
    assert re.findall(r"^KR 16 from kr16_2\.urdf in .* 6 axes, family opw", out, re.M)
    kr = re.findall(r"^kr16 ([lr][ud][nf])\s+True\s", out, re.M)
    assert sorted(kr) == ["rdf", "rdn", "ruf", "run"]
    assert _number(out, "largest |fk(q) - T| of the KR 16 solutions:") < 1e-9


def check_thesis_examples(out: str) -> None:
    eq_4_27 = math.radians(70 + 40 + 60) / 0.3  # s: the largest joint motions at 0.3 rad/s
    assert _number(out, "simulated time:") == pytest.approx(eq_4_27, abs=1e-9)
    for mode in ("path", "joint-by-joint", "playback"):
        assert _number(out, f"{mode:15} simulated") == pytest.approx(eq_4_27, abs=1e-4)
    assert "grasp 'cube'" in out
    assert "grasp 'sphere'" in out
    assert "now carried by 'puma_2'" in out
    assert out.count(" 0 collisions") == 2
    # cube (40 mm) centred on stage 1 at (0.24, 0.22), top 0.5 m: its centroid 20 mm above
    assert _vector(out, "final cube centroid (m):") == pytest.approx([0.24, 0.22, 0.52], abs=1e-6)
    # sphere (25 mm radius) on table 2 (top 0.4 m) at (0.62, 0.15)
    assert _vector(out, "final sphere centre (m):") == pytest.approx([0.62, 0.15, 0.425], abs=1e-6)
    assert len(re.findall(r"^\d+ key frames -> ", out, re.M)) == 3


def check_study(out: str) -> None:
    """The placement study's numbers against independent runs of example 2: the thesis's
    placement, and the best one on a cell moved by editing its saved form."""
    from workcell.cell import Workcell
    from workcell.examples import thesis_pick_place
    from workcell.sim import Simulator

    assert "8 of 9 candidates feasible" in out  # SMALL: 3 x 3, one placement out of reach
    assert _number(out, "cycle time at the thesis's placement (0, 0):") == (
        thesis_pick_place.run().sim_time
    )
    x, y = _number(out, "best placement: x ="), _number(out, "m, y =")
    data = thesis_pick_place.build().to_dict()
    data["robots"][0]["base"][0][3], data["robots"][0]["base"][1][3] = x, y
    sim = Simulator(Workcell.from_dict(data))
    thesis_pick_place.program(sim)
    assert _number(out, "m, cycle time") == sim.sim_time
    assert "second run: 0 evaluated, 9 already done" in out


def check_conveyor(out: str) -> None:
    """A beam at 1.3 m from the box's front on a 0.25 m/s belt breaks after 5.2 s (the first
    frame at or after it, 10 ms apart); the demo's throughput is its boxes over its time."""
    t = _number(out, "beam broken at t =")
    assert 1.3 / 0.25 - 1e-9 <= t <= 1.3 / 0.25 + 0.01 + 1e-9
    assert _vector(out, "'box_1': ") == pytest.approx([1.45, 0.0, 0.55], abs=1e-3)  # at the beam
    assert _number(out, "boxes stacked:") == 8
    T = _number(out, "time:")
    assert _number(out, "boxes per hour:") == pytest.approx(8 * 3600 / T, abs=0.01)
    shares = [_number(out, f"{k} ") for k in ("ur5e: moving", "waiting", "idle")]
    assert sum(shares) == pytest.approx(100, abs=0.15)
    assert "'a' waits for signal 'b_done' = true" in out
    assert "'b' waits for signal 'a_done' = true" in out


CHECKS = {
    "conveyor": check_conveyor,
    "quickstart": check_quickstart,
    "build_your_own_cell": check_build_your_own_cell,
    "modeller": check_modeller,
    "kinematics": check_kinematics,
    "thesis_examples": check_thesis_examples,
    "study": check_study,
}


# ---------------------------------------------------------------------- tests
def test_every_notebook_is_tested():
    assert sorted(p.stem for p in NOTEBOOKS.glob("*.ipynb")) == sorted(NAMES)
    assert sorted(CHECKS) == sorted(NAMES)


@pytest.mark.parametrize("path", sorted(NOTEBOOKS.glob("*.ipynb")), ids=lambda p: p.stem)
def test_notebook_is_committed_without_outputs(path):
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    assert nb.metadata.kernelspec.name == "python3"
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code
    for k, cell in enumerate(code):
        assert cell.outputs == [], f"{path.name}: code cell {k} has outputs; strip them"
        assert cell.execution_count is None, f"{path.name}: code cell {k} has an execution count"
    assert "SMALL = True" in code[0].source  # the test suite runs the small sizes


@pytest.mark.parametrize("name", NAMES)
def test_notebook_runs(name, tmp_path, monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "egl")  # the kernel inherits this environment
    monkeypatch.setenv("IPYTHONDIR", str(tmp_path / "ipython"))  # no shared history database
    monkeypatch.setenv("TMPDIR", str(tmp_path))  # the notebooks' output folders (mkdtemp)
    monkeypatch.setenv("PYDEVD_DISABLE_FILE_VALIDATION", "1")  # quiet debugpy in the kernel
    out, images = _run(name, tmp_path)
    CHECKS[name](out)
    assert len(images) == PICTURES[name]
    for img in images:  # a drawn scene, not a blank frame
        assert img.shape[0] >= 120
        assert img.shape[1] >= 160
        assert img.reshape(-1, 3).std(axis=0).max() > 10
