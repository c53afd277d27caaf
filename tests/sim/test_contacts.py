"""Which overlaps :meth:`ContactMonitor.penetrations` reports (workcell.sim.contacts).

Reference: MuJoCo's own ``mj_geomDistance`` (the signed distance of two convex collision
pieces by GJK/EPA, independent of the geom margins the simulator's contact model sets),
through :meth:`ContactMonitor.clearance`, which takes the minimum over the pieces of two
things. A pair must be reported exactly when that distance is below ``-tolerance``, with
the depth ``-distance``. Poses are found by bisection on the reference distance along a
line, so the cases sit on both sides of the tolerance and at touching (distance 0).

The defect this guards against: with geom margins of ``-tolerance / 2`` (the previous
contact model; MuJoCo requires ``margin + gap >= 0``), MuJoCo's convex collider reported
a mesh pair overlapping by d < tolerance with ``dist = -(d + tolerance)``, so a part
resting on a support (d ~ 0) became a collision whenever the bounding-box tests let the
pair through: single-geom bodies, and shapes whose boxes do not fit the contact face (a
cylinder lying on a table, a cube on that cylinder).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from workcell import Workcell, solids
from workcell.cell import compile_cell
from workcell.cell.compile import CompiledCell
from workcell.sim import Simulator
from workcell.sim.contacts import DEFAULT_TOLERANCE, ContactMonitor, contact_model
from workcell.spatial import compose, rot_x, rot_z, translation

TOL = DEFAULT_TOLERANCE  # m
BAND = 2e-6  # m: MuJoCo's GJK/EPA tolerance (opt.ccd_tolerance 1e-6), twice; cases
# whose reference distance is this close to -TOL may go either way
WALL = 0.01  # m: the bin's walls (the same bin as test_collision_geometry: one CoACD run)

# ---------------------------------------------------------------------------- helpers


def quat(v: tuple[float, float, float, float]) -> np.ndarray:
    """A unit quaternion (wxyz) from four numbers (not all ~0)."""
    q = np.asarray(v, dtype=float)
    return q / np.linalg.norm(q)


def unit(v: tuple[float, float, float]) -> np.ndarray:
    u = np.asarray(v, dtype=float)
    return u / np.linalg.norm(u)


def mujoco_quat(T: np.ndarray) -> np.ndarray:
    """The unit quaternion (wxyz) of a 4x4 transform's rotation."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(T[:3, :3]).ravel())
    return q


nonzero4 = st.tuples(*[st.floats(-1, 1)] * 4).filter(lambda v: np.linalg.norm(v) > 0.1)
nonzero3 = st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1)
# the mover's orientation: upright, yawed, lying with a facet or an edge down, or any
orientations = st.one_of(
    st.sampled_from([(1.0, 0.0, 0.0, 0.0), (0.99, 0.0, 0.0, 0.14), (0.71, 0.71, 0.0, 0.0)]),
    st.builds(
        lambda a, b: tuple(mujoco_quat(compose(rot_z(a), rot_x(math.pi / 2), rot_z(b)))),
        st.floats(-math.pi, math.pi),
        st.floats(-math.pi, math.pi),
    ),
    nonzero4,
)
# where it comes from: straight down (resting), a few degrees off, or anywhere
directions = st.one_of(
    st.just((0.0, 0.0, 1.0)),
    st.tuples(st.floats(-0.1, 0.1), st.floats(-0.1, 0.1), st.just(1.0)),
    nonzero3,
)
# the signed distance aimed at (m): around the tolerance, touching, just either side
targets = st.one_of(
    st.floats(-3 * TOL, 2 * TOL),
    st.sampled_from([0.0, -0.5 * TOL, -0.99 * TOL, -1.01 * TOL, 1e-6, -1e-6]),
)


class Mover:
    """A free body moved so that its collision geom's centre is at ``centre + t * u``."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, body: str) -> None:
        b = model.body(body).id
        self.model, self.data = model, data
        self.adr = int(model.jnt_qposadr[model.body_jntadr[b]])
        geoms = range(model.body_geomadr[b], model.body_geomadr[b] + model.body_geomnum[b])
        g = next(g for g in geoms if model.geom_contype[g] or model.geom_conaffinity[g])
        self.offset = model.geom_pos[g].copy()  # the geom's centre in the body (m)

    def put(self, q: np.ndarray, centre: np.ndarray) -> None:
        shift = np.zeros(3)
        mujoco.mju_rotVecQuat(shift, self.offset, q)
        self.data.qpos[self.adr : self.adr + 3] = centre - shift
        self.data.qpos[self.adr + 3 : self.adr + 7] = q
        mujoco.mj_kinematics(self.model, self.data)


def place_at_distance(
    monitor: ContactMonitor,
    mover: Mover,
    a: str,
    b: str,
    q: np.ndarray,
    centre: np.ndarray,
    u: np.ndarray,
    target: float,
    reach: float,
) -> float:
    """Put ``b`` (oriented ``q``) on the line ``centre + t u`` (t in [0, reach] m) where
    the reference distance to ``a`` crosses ``target`` (m, bisection); that distance."""

    def dist(t: float) -> float:
        mover.put(q, centre + t * u)
        return monitor.clearance(mover.data, a, b)[0]

    # not t = 0: MuJoCo (3.17) finds no contact, and mj_geomDistance 0, for two convex
    # pieces whose centres coincide exactly, however deep the overlap
    lo, hi = 1e-6, reach
    assert dist(lo) < min(target, 0.0)  # overlapping
    assert dist(hi) > target  # apart
    for _ in range(48):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if dist(mid) < target else (lo, mid)
    return dist(hi)


def check(monitor: ContactMonitor, data: mujoco.MjData, a: str, b: str) -> float:
    """Compare penetrations() in ``data`` with the reference; the reference distance."""
    mujoco.mj_collision(monitor.model, data)
    pens = {(x, y): depth for x, y, depth in monitor.penetrations(data)}
    true = monitor.clearance(data, a, b)[0]
    key = (a, b) if a < b else (b, a)
    assert set(pens) <= {key}  # nothing else is near
    if abs(true + monitor.tolerance) > BAND:
        assert (key in pens) == (true < -monitor.tolerance), (true, pens)
    if key in pens:
        assert pens[key] == pytest.approx(-true, abs=BAND)
    return true


# ------------------------------------------------------- things of a compiled cell

SLOTS = {  # a static thing and where it stands (m), 2 m apart
    "block_1": (0.0, 0.0),
    "drum_1": (2.0, 0.0),
    "bin_1": (4.0, 0.0),
}
MOVABLE = ("cube_1", "roller_1")
PAIRS = [
    ("block_1", "cube_1"),
    ("block_1", "roller_1"),
    ("drum_1", "cube_1"),
    ("drum_1", "roller_1"),
    ("bin_1", "cube_1"),
    ("bin_1", "roller_1"),
    ("ground", "cube_1"),
    ("ground", "roller_1"),
    ("cube_1", "roller_1"),
    ("roller_1", "cube_1"),
]


def things_cell() -> Workcell:
    """Static parts (a box, a 24-sided drum, a CoACD-decomposed bin) on stands 1 m up
    (away from the ground), and two movable parts (a cube, a 24-sided roller)."""
    cell = Workcell("contacts")
    m = cell.model
    solids.box(m, "block", size=(0.2, 0.15, 0.1))
    solids.cylinder(m, "drum", radius=0.06, height=0.06, n=24)
    solids.box(m, "outer", size=(0.2, 0.15, 0.1))
    solids.box(m, "inner", size=(0.2 - 2 * WALL, 0.15 - 2 * WALL, 0.1))
    solids.difference(m, "bin", "outer", "inner", transforms=[None, translation(WALL, WALL, WALL)])
    solids.cube(m, "cube", size=0.04)
    solids.cylinder(m, "roller", radius=0.03, height=0.08, n=24)
    for name, (x, y) in SLOTS.items():
        cell.add_static(name, name.split("_")[0], translation(x, y, 1.0))
    for k, name in enumerate(MOVABLE):
        cell.add_movable(
            name, name.split("_")[0], translation(10.0 + 2 * k, 0.0, 1.0), density=1000.0
        )
    return cell


@pytest.fixture(scope="module")
def things():
    sim = Simulator(things_cell())
    assert collisions(sim) == []
    return sim


@pytest.mark.slow
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    pair=st.sampled_from(PAIRS),
    orientation=orientations,
    other=nonzero4,
    direction=directions,
    target=targets,
    piece=st.integers(0, 100),
)
def test_penetrations_are_the_overlaps_deeper_than_the_tolerance(
    things, pair, orientation, other, direction, target, piece
):
    a, b = pair
    m, monitor = things.model, things.contacts
    d = mujoco.MjData(m)
    d.qpos[:] = things.data.qpos
    mujoco.mj_kinematics(m, d)
    mover = Mover(m, d, b)
    u = unit(direction)
    if a in MOVABLE:  # the other movable part, turned any way, in its own slot
        Mover(m, d, a).put(quat(other), np.array([8.0, 0.0, 1.0]))
        centre = np.array([8.0, 0.0, 1.0])
    elif a == "ground":
        centre = np.array([6.0, 0.0, 0.0])
        u = unit((u[0], u[1], abs(u[2]) + 0.3))  # from above
    else:  # the centre of one of its convex pieces (inside it)
        geoms = monitor.geoms_of(a)
        centre = d.geom_xpos[geoms[piece % len(geoms)]].copy()
    true = place_at_distance(monitor, mover, a, b, quat(orientation), centre, u, target, 0.5)
    assert true == pytest.approx(target, abs=1e-5)
    check(monitor, d, a, b)


# ------------------------------------------------------------ single-geom bodies


def single_geom_bodies(kind_a: str, kind_b: str) -> tuple[ContactMonitor, mujoco.MjData]:
    """Two free bodies with one collision geom each and nothing else (MuJoCo then skips
    its bounding-box tests: only a bounding-sphere test before the narrow phase)."""
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    shapes = {
        "box": {"type": mujoco.mjtGeom.mjGEOM_BOX, "size": [0.1, 0.075, 0.05]},
        "boxmesh": {"type": mujoco.mjtGeom.mjGEOM_MESH, "meshname": "boxmesh"},
        "cylmesh": {"type": mujoco.mjtGeom.mjGEOM_MESH, "meshname": "cylmesh"},
    }
    box = spec.add_mesh(name="boxmesh")
    box.uservert = [
        c for x in (-0.1, 0.1) for y in (-0.075, 0.075) for z in (-0.05, 0.05) for c in (x, y, z)
    ]
    cyl = spec.add_mesh(name="cylmesh")
    ang = np.arange(24) * 2 * math.pi / 24
    cyl.uservert = (
        np.concatenate(
            [
                np.column_stack([0.03 * np.cos(ang), 0.03 * np.sin(ang), np.full(24, z)])
                for z in (-0.04, 0.04)
            ]
        )
        .ravel()
        .tolist()
    )
    for name, kind, x in (("A", kind_a, 0.0), ("B", kind_b, 2.0)):
        body = spec.worldbody.add_body(name=name, pos=[x, 0.0, 1.0])
        body.add_freejoint()
        body.add_geom(name=f"{name}.col0", **shapes[kind])
    model = spec.compile()
    assert list(model.body_geomnum[1:]) == [1, 1]
    m = contact_model(model)
    monitor = ContactMonitor(CompiledCell(spec=spec, model=model), TOL, m)
    data = mujoco.MjData(m)
    mujoco.mj_kinematics(m, data)
    return monitor, data


KINDS = [
    ("boxmesh", "boxmesh"),
    ("boxmesh", "cylmesh"),
    ("cylmesh", "cylmesh"),
    ("box", "box"),
    ("box", "cylmesh"),
]


@pytest.fixture(scope="module")
def single():
    return {kinds: single_geom_bodies(*kinds) for kinds in KINDS}


@settings(max_examples=100, deadline=None)
@given(
    kinds=st.sampled_from(KINDS),
    orientation=orientations,
    other=nonzero4,
    direction=directions,
    target=targets,
)
def test_single_geom_bodies_are_reported_by_their_true_depth(
    single, kinds, orientation, other, direction, target
):
    monitor, d = single[kinds]
    centre = np.array([0.0, 0.0, 1.0])
    Mover(monitor.model, d, "A").put(quat(other), centre)
    mover = Mover(monitor.model, d, "B")
    place_at_distance(
        monitor, mover, "A", "B", quat(orientation), centre, unit(direction), target, 0.5
    )
    check(monitor, d, "A", "B")


# --------------------------------------------------- resting parts in a real run

TABLE_TOP = 0.4  # m


def lowest_at(cell: Workcell, block: str, R: np.ndarray, z: float, xy: tuple[float, float]):
    """Pose of ``block`` turned by ``R`` with its lowest vertex at height ``z`` (m) and its
    frame over ``xy``; and the height of its highest vertex (m)."""
    v = cell.model.world_mesh(("block", block)).vertices @ R[:3, :3].T
    T = np.array(R, dtype=float)
    T[:3, 3] = [xy[0], xy[1], z - v[:, 2].min()]
    return T, z - v[:, 2].min() + v[:, 2].max()


def resting_cell(sink: float) -> Workcell:
    """A Puma 260 on a table; a 24-sided roller lying on the table with an edge down
    (turned 0.13 rad about its axis), a cube on the roller's top; both parts sunk by
    ``sink`` (m) into what carries them (0: resting exactly)."""
    cell = Workcell("resting")
    m = cell.model
    solids.box(m, "table", size=(1.0, 0.8, TABLE_TOP))
    solids.cylinder(m, "roller", radius=0.03, height=0.08, n=24)
    solids.cube(m, "cube", size=0.04)
    cell.add_static("table_1", "table", translation(-0.3, -0.4, 0.0))
    R = compose(rot_z(0.4), rot_x(math.pi / 2), rot_z(0.13))
    T, top = lowest_at(cell, "roller", R, TABLE_TOP - sink, (0.3, 0.25))
    cell.add_movable("roller_1", "roller", T, density=1000.0)
    centre = T[:3, :3] @ cell.model.world_mesh(("block", "roller")).vertices.mean(axis=0)
    Rc = rot_z(0.3)
    Tc, _ = lowest_at(cell, "cube", Rc, top - sink, (0.0, 0.0))
    Tc[:2, 3] = (T[:3, 3] + centre)[:2] - (Rc[:3, :3] @ [0.02, 0.02, 0.0])[:2]
    cell.add_movable("cube_1", "cube", Tc, density=1000.0)
    cell.add_robot("puma", "puma260", gripper=True, base=translation(0.0, 0.0, TABLE_TOP))
    return cell


def collisions(sim: Simulator) -> list[str]:
    return [e.detail for e in sim.events if e.kind == "collision"]


@pytest.mark.parametrize("sink", [0.0, 0.5 * TOL])
def test_parts_resting_on_a_table_and_on_a_part_make_no_collision(sink):
    sim = Simulator(resting_cell(sink))
    sim.move_joints_relative("puma", np.radians([20.0, -10.0, 10.0, 0.0, 30.0, 0.0]))
    assert sim.frames > 100
    assert collisions(sim) == []
    for a, b in (("roller_1", "table_1"), ("cube_1", "roller_1")):
        assert sim.clearance(a, b) == pytest.approx(-sink, abs=1e-7)


def test_parts_sunk_deeper_than_the_tolerance_collide():
    sim = Simulator(resting_cell(2 * TOL))
    sim.move_joints_relative("puma", np.radians([20.0, -10.0, 10.0, 0.0, 30.0, 0.0]))
    assert sorted(collisions(sim)) == [
        "cube_1 with roller_1: depth 0.2 mm",
        "roller_1 with table_1: depth 0.2 mm",
    ]
    assert all(e.t == 0.0 for e in sim.events if e.kind == "collision")


def test_the_contact_model_keeps_the_geometry():
    """Margins and gaps 0 (MuJoCo needs margin + gap >= 0), one contact per pair of pieces;
    the compiled model untouched."""
    cc = compile_cell(resting_cell(0.0))
    cc.model.geom_margin[:] = 0.01  # e.g. an imported robot's margins
    m = contact_model(cc.model)
    assert np.all(m.geom_margin == 0.0)
    assert np.all(m.geom_gap == 0.0)
    assert np.all(cc.model.geom_margin == 0.01)
    assert m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_MULTICCD
    assert not cc.model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_MULTICCD
