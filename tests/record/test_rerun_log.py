"""The rerun recorder: files read back with rerun.chunk.RrdReader and checked against
MuJoCo kinematics computed here, on the timeline's own qpos."""

from __future__ import annotations

import copy
import math
import socket
from collections import defaultdict
from pathlib import Path

import mujoco
import numpy as np
import pyarrow as pa
import pytest
import rerun as rr
from rerun.chunk import RrdReader

from workcell import solids
from workcell.cell import Workcell
from workcell.examples import thesis_joints
from workcell.record import RecordError, record, rerun_log
from workcell.record.camera import visual_points
from workcell.sim import Event, Simulator, Timeline
from workcell.spatial import rot_z, translation

START = np.radians([0.0, 0.0, -90.0, 0.0, 90.0, 0.0])
TIMELINES = ("frame", "sim_time", "wall_time")


@pytest.fixture(autouse=True)
def strict() -> object:
    rr.set_strict_mode(True)
    yield
    rr.set_strict_mode(False)


def gripper_cell() -> Workcell:
    """A Puma 260 with a gripper, one without, a movable cube and a camera."""
    cell = Workcell("rec_cell")
    solids.cube(cell.model, "cube_block", size=0.04)
    cell.add_movable("cube", "cube_block", translation(0.35, 0.1, 0.0), density=2700.0)
    cell.add_robot("arm", "puma260", gripper=True, q=START)
    cell.add_robot("plain", "puma260", base=translation(1.0, 0.0, 0.0) @ rot_z(np.pi), q=START)
    cell.add_camera("overview", (0.6, -1.8, 1.4), (0.6, 0.0, 0.5), fovy=50)
    return cell


def run_cell() -> Simulator:
    """Both robots move, then the cube flies and turns (frames appended to the timeline, as
    a carried part's would be); grasp, collision, release and error events added by hand
    as they happen, and one event without a frame (-1) at the end."""
    sim = Simulator(gripper_cell(), "path", dt=0.02)
    tl = sim.timeline
    sim.move_joints_relative("arm", np.radians([20, -10, 15, 30, -20, 40]))
    tl.add_event(sim.sim_time, "arm", "grasp", "grasped cube")
    sim.move_joints_relative("plain", np.radians([-30, 10, -10, 0, 25, 0]))
    m = sim.model
    adr = m.jnt_qposadr[m.joint("cube.free").id]
    k = np.arange(1, 41)
    Q = np.repeat(sim.data.qpos[None], len(k), axis=0)
    Q[:, adr : adr + 3] += np.outer(k / 40, [0.1, -0.2, 0.5])
    half = 0.05 * k  # turning about (1, 2, 2)/3
    Q[:, adr + 3 : adr + 7] = np.column_stack(
        [np.cos(half), *(np.sin(half)[None] * np.array([[1 / 3], [2 / 3], [2 / 3]]))]
    )
    t, w = sim.sim_time + 0.02 * k, sim.wall_time + 0.001 * k
    for lo, hi, robot, kind, detail in (
        (0, 15, None, "collision", "cube touches arm.link6"),
        (15, 25, "arm", "release", "released cube"),
        (25, 40, "plain", "error", "joint 2 out of range"),
    ):
        tl.extend(t[lo:hi], w[lo:hi], Q[lo:hi])
        # the error: found during the last step, so before its frame's time
        tl.add_event(t[hi - 1] - 0.01 * (kind == "error"), robot, kind, detail)
    # an event that does not know its frame (e.g. made by hand): placed by its time
    tl._events.append(Event(float(t[9]) + 1e-6, None, "note", "no frame"))
    return sim


@pytest.fixture(scope="module")
def joints_rec(tmp_path_factory: pytest.TempPathFactory) -> tuple[Simulator, Path]:
    sim = thesis_joints.run("path", 0.01)
    path = tmp_path_factory.mktemp("rec") / "joints.rrd"
    rr.set_strict_mode(True)
    record(sim, path, fps=None)  # every frame
    return sim, path


@pytest.fixture(scope="module")
def cell_rec(tmp_path_factory: pytest.TempPathFactory) -> tuple[Simulator, Path]:
    sim = run_cell()
    path = tmp_path_factory.mktemp("rec") / "cell.rrd"
    rr.set_strict_mode(True)
    record(sim, path, chunk_frames=64, fps=None)  # several batches, every frame
    return sim, path


# ---------------------------------------------------------------------- reading back
def _values(col: pa.Array, n: int) -> np.ndarray:
    """A component column flattened to numbers, one row per logged row."""
    while pa.types.is_list(col.type) or pa.types.is_fixed_size_list(col.type):
        col = col.flatten()
    return col.to_numpy(zero_copy_only=False).reshape(n, -1)


def read(path: Path, entity: str, component: str, index: str = "frame") -> tuple:
    """(index values (k,), component values (k, m)) of an entity's temporal rows, by index."""
    idx, val = [], []
    stream = RrdReader(path).store().stream().filter(content=entity, is_static=False)
    for chunk in stream.to_chunks():
        if chunk.entity_path != entity:
            continue
        rb = chunk.to_record_batch()
        t = rb.column(index)
        idx.append(t.cast(pa.int64()).to_numpy() if pa.types.is_duration(t.type) else t.to_numpy())
        val.append(_values(rb.column(component), rb.num_rows))
    assert idx, f"no temporal {component} on {entity}"
    i, v = np.concatenate(idx), np.concatenate(val)
    order = np.argsort(i, kind="stable")
    return i[order], v[order]


def read_static(path: Path, entity: str, component: str) -> np.ndarray:
    for chunk in (
        RrdReader(path).store().stream().filter(content=entity, is_static=True).to_chunks()
    ):
        if chunk.entity_path == entity:
            rb = chunk.to_record_batch()
            if component in rb.schema.names:
                return _values(rb.column(component), rb.num_rows)[0]
    raise AssertionError(f"no static {component} on {entity}")


def kinematics(sim: Simulator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """xpos (n, nbody, 3), xquat (n, nbody, 4) wxyz and site_xpos of every frame."""
    m = sim.model
    d = mujoco.MjData(m)
    Q = sim.timeline.qpos()
    xp, xq, sp = (np.empty((len(Q), k, w)) for k, w in ((m.nbody, 3), (m.nbody, 4), (m.nsite, 3)))
    for i, q in enumerate(Q):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        xp[i], xq[i], sp[i] = d.xpos, d.xquat, d.site_xpos
    return xp, xq, sp


# ---------------------------------------------------------------------- tests
def test_entity_paths(cell_rec: tuple[Simulator, Path]) -> None:
    sim, path = cell_rec
    m = sim.model
    body = [m.body(b).name for b in range(m.nbody)]
    expected = {"/world", "/events", "/joints/arm", "/joints/plain", "/gripper/arm"}
    expected |= {f"/joint_{k}/{r}" for k in ("speeds", "accelerations") for r in ("arm", "plain")}
    expected |= {"/world/tool_paths/arm", "/world/tool_paths/plain"}
    expected |= {f"/world/bodies/{b}" for b in body[1:]}
    expected |= {
        f"/world/bodies/{body[m.geom_bodyid[g]]}/{m.geom(g).name}"
        for g in range(m.ngeom)
        if m.geom_group[g] != 3  # collision pieces are not drawn
    }
    expected.add("/world/bodies/world/overview")  # the camera
    got = set(RrdReader(path).store().schema().entity_paths()) - {"/__properties"}
    assert got == expected
    assert not any(".col" in e for e in got)


def test_frame_counts_and_clocks(cell_rec: tuple[Simulator, Path]) -> None:
    sim, path = cell_rec
    n = sim.frames
    for entity, component in (
        ("/world/bodies/arm.link3", "Transform3D:translation"),
        ("/world/bodies/cube", "Transform3D:quaternion"),
        ("/joints/plain", "Scalars:scalars"),
        ("/world/tool_paths/arm", "LineStrips3D:strips"),
    ):
        frames, _ = read(path, entity, component)
        assert np.array_equal(frames, np.arange(n))
    t_ns, _ = read(path, "/joints/arm", "Scalars:scalars", index="sim_time")
    assert np.array_equal(t_ns, np.round(sim.timeline.sim_times() * 1e9).astype(np.int64))
    w_ns, _ = read(path, "/joints/arm", "Scalars:scalars", index="wall_time")
    assert np.array_equal(np.sort(w_ns), np.sort(np.round(sim.timeline.wall_times() * 1e9)))


def test_body_poses_equal_mujoco_kinematics(cell_rec: tuple[Simulator, Path]) -> None:
    sim, path = cell_rec
    m = sim.model
    xp, xq, _ = kinematics(sim)
    moving = [b for b in range(1, m.nbody) if m.body_weldid[b] != 0]
    assert m.body("cube").id in moving
    assert m.body("arm.gripper.left").id in moving
    assert np.ptp(xp[:, m.body("cube").id], axis=0).max() > 0.4  # the cube did move
    for b in moving:
        entity = f"/world/bodies/{m.body(b).name}"
        _, pos = read(path, entity, "Transform3D:translation")
        _, quat = read(path, entity, "Transform3D:quaternion")
        np.testing.assert_allclose(pos, xp[:, b], rtol=0, atol=1e-6)
        np.testing.assert_allclose(quat, xq[:, b][:, [1, 2, 3, 0]], rtol=0, atol=1e-6)
    base = m.body("plain.link0").id  # welded to the world: one static pose
    pos = read_static(path, "/world/bodies/plain.link0", "Transform3D:translation")
    np.testing.assert_allclose(pos, xp[0, base], atol=1e-6)
    np.testing.assert_allclose(pos, [1.0, 0.0, 0.0], atol=1e-6)


def test_joint_series_equal_timeline_qpos(cell_rec: tuple[Simulator, Path]) -> None:
    sim, path = cell_rec
    m = sim.model
    Q = sim.timeline.qpos()
    for robot in ("arm", "plain"):
        adr = [m.jnt_qposadr[m.joint(f"{robot}.j{i}").id] for i in range(1, 7)]
        _, deg = read(path, f"/joints/{robot}", "Scalars:scalars")
        np.testing.assert_allclose(deg, Q[:, adr] * 180 / np.pi, rtol=1e-13, atol=1e-12)
        names = read_static(path, f"/joints/{robot}", "SeriesLines:names").ravel().tolist()
        assert names == [f"j{i} (deg)" for i in range(1, 7)]
    assert np.ptp(deg[:, 0]) == pytest.approx(30.0)  # plain's joint 1 moved by -30 deg


def test_joint_speed_and_acceleration_series(cell_rec: tuple[Simulator, Path]) -> None:
    sim, path = cell_rec
    m = sim.model
    t, Q = sim.timeline.sim_times(), sim.timeline.qpos()
    adr = [m.jnt_qposadr[m.joint(f"plain.j{i}").id] for i in range(1, 7)]
    _, v = read(path, "/joint_speeds/plain", "Scalars:scalars")
    _, a = read(path, "/joint_accelerations/plain", "Scalars:scalars")
    q = np.degrees(Q[:, adr])
    k = next(i for i in range(2, len(t)) if t[i] > t[i - 1] > t[i - 2])  # three distinct times
    v_k = (q[k] - q[k - 1]) / (t[k] - t[k - 1])  # backward differences, by hand
    v_j = (q[k - 1] - q[k - 2]) / (t[k - 1] - t[k - 2])
    np.testing.assert_allclose(v[k], v_k, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(a[k], (v_k - v_j) / ((t[k] - t[k - 2]) / 2), rtol=1e-9, atol=1e-6)
    assert np.all(v[0] == 0)
    names = read_static(path, "/joint_speeds/plain", "SeriesLines:names").ravel().tolist()
    assert names == [f"j{i} (deg/s)" for i in range(1, 7)]
    names = read_static(path, "/joint_accelerations/plain", "SeriesLines:names").ravel().tolist()
    assert names == [f"j{i} (deg/s^2)" for i in range(1, 7)]


def test_tool_path_segments(cell_rec: tuple[Simulator, Path]) -> None:
    sim, path = cell_rec
    _, _, sp = kinematics(sim)
    tool = sp[:, sim.model.site("arm.tool").id]
    _, seg = read(path, "/world/tool_paths/arm", "LineStrips3D:strips")
    seg = seg.reshape(-1, 2, 3)
    np.testing.assert_allclose(seg[:, 1], tool, atol=1e-6)
    np.testing.assert_allclose(seg[1:, 0], tool[:-1], atol=1e-6)
    np.testing.assert_allclose(seg[0, 0], tool[0], atol=1e-6)


def test_static_mesh_geometry(cell_rec: tuple[Simulator, Path]) -> None:
    sim, path = cell_rec
    m = sim.model
    g = m.geom("arm.link2.upper_arm").id
    mesh = m.geom_dataid[g]
    faces = m.mesh_face[m.mesh_faceadr[mesh] : m.mesh_faceadr[mesh] + m.mesh_facenum[mesh]]
    verts = m.mesh_vert[m.mesh_vertadr[mesh] :][faces].reshape(-1, 3)
    entity = "/world/bodies/arm.link2/arm.link2.upper_arm"
    got = read_static(path, entity, "Mesh3D:vertex_positions").reshape(-1, 3)
    np.testing.assert_allclose(got, verts, atol=1e-7)
    tri = read_static(path, entity, "Mesh3D:triangle_indices").reshape(-1, 3)
    assert len(tri) == m.mesh_facenum[mesh]
    assert tri.max() == len(verts) - 1
    np.testing.assert_allclose(
        read_static(path, entity, "Transform3D:translation"), m.geom_pos[g], atol=1e-7
    )
    # the cube (convex): flat normals of unit length, pointing out of the solid
    cube = read_static(path, "/world/bodies/cube/cube.visual", "Mesh3D:vertex_positions")
    normals = read_static(path, "/world/bodies/cube/cube.visual", "Mesh3D:vertex_normals")
    cube, normals = cube.reshape(-1, 3, 3), normals.reshape(-1, 3, 3)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=2), 1.0, atol=1e-6)
    np.testing.assert_array_equal(normals[:, 0], normals[:, 2])
    outward = cube.mean(axis=1) - cube.reshape(-1, 3).mean(axis=0)
    assert len(cube) == 12
    assert np.all(np.einsum("fi,fi->f", normals[:, 0], outward) > 0.019)  # 0.02 m half size
    rgba = read_static(path, entity, "Mesh3D:albedo_factor")  # packed 0xRRGGBBAA
    assert int(rgba[0]) == int.from_bytes(np.round(m.geom_rgba[g] * 255).astype(np.uint8))


def test_events_and_gripper_state(cell_rec: tuple[Simulator, Path]) -> None:
    sim, path = cell_rec
    events = sim.timeline.events
    times = sim.timeline.sim_times()
    assert [e.kind for e in events[-5:]] == ["move", "collision", "release", "error", "note"]
    # each event on the frame the timeline gave it; the frameless one after 10 cube frames
    frame_of = [e.frame for e in events[:-1]] + [sim.frames - 31]
    by_time = [max(i for i, t in enumerate(times) if t <= e.t) for e in events]
    assert np.subtract(frame_of, by_time).tolist() == [0, 0, 0, 0, 0, 1, 0]  # the error's
    frames, _ = read(path, "/events", "TextLog:text")
    assert sorted(frames.tolist()) == sorted(frame_of)
    t_ns, _ = read(path, "/events", "TextLog:text", index="sim_time")
    assert sorted(t_ns.tolist()) == sorted(round(e.t * 1e9) for e in events)
    rb_levels = {}
    for chunk in RrdReader(path).store().stream().filter(content="/events").to_chunks():
        rb = chunk.to_record_batch()
        texts = rb.column("TextLog:text").flatten().to_pylist()
        levels = rb.column("TextLog:level").flatten().to_pylist()
        rb_levels.update(zip(texts, levels, strict=True))
    assert rb_levels["[arm] grasp: grasped cube"] == "INFO"
    assert rb_levels["[cell] collision: cube touches arm.link6"] == "WARN"
    assert rb_levels["[plain] error: joint 2 out of range"] == "ERROR"
    assert rb_levels["[cell] note: no frame"] == "INFO"
    assert sum(level == "DEBUG" for level in rb_levels.values()) == 2  # the two moves
    # gripper: the latest value at each frame is 1 from the grasp to the release
    f, v = read(path, "/gripper/arm", "Scalars:scalars")
    (grasp,) = (e.frame for e in events if e.kind == "grasp")
    (release,) = (e.frame for e in events if e.kind == "release")
    latest = np.array([v[f <= i][-1, 0] for i in range(sim.frames)])
    n = np.arange(sim.frames)
    assert 0 < grasp < release < sim.frames - 1
    np.testing.assert_array_equal(latest, ((n >= grasp) & (n < release)).astype(float))
    schema = set(RrdReader(path).store().schema().entity_paths())
    assert "/gripper/plain" not in schema  # no gripper, no series


def test_blueprint_stored(cell_rec: tuple[Simulator, Path]) -> None:
    _, path = cell_rec
    reader = RrdReader(path)
    (bp,) = reader.blueprints()
    assert bp.application_id == "workcell"
    views = set()
    for chunk in reader.store(store=bp).stream().filter(content="/view/**").to_chunks():
        rb = chunk.to_record_batch()
        if "ViewBlueprint:class_identifier" in rb.schema.names:
            kind = rb.column("ViewBlueprint:class_identifier").flatten().to_pylist()[0]
            origin = rb.column("ViewBlueprint:space_origin").flatten().to_pylist()[0]
            views.add((kind, origin))
    assert views == {
        ("3D", "/world"),
        ("TimeSeries", "/joints/arm"),
        ("TimeSeries", "/joints/plain"),
        ("TimeSeries", "/joint_speeds/arm"),
        ("TimeSeries", "/joint_speeds/plain"),
        ("TimeSeries", "/joint_accelerations/arm"),
        ("TimeSeries", "/joint_accelerations/plain"),
        ("TimeSeries", "/gripper"),
        ("TextLog", "/events"),
    }


def test_example1_file(joints_rec: tuple[Simulator, Path]) -> None:
    sim, path = joints_rec
    frames, deg = read(path, "/joints/puma", "Scalars:scalars")
    assert len(frames) == sim.frames
    assert sim.frames > 900
    np.testing.assert_allclose(deg[0], thesis_joints.START_DEG, atol=1e-9)
    np.testing.assert_allclose(deg[-1], thesis_joints.START_DEG, atol=1e-9)
    assert np.degrees(np.ptp(sim.timeline.qpos()[:, 0])) == pytest.approx(70.0)
    assert np.ptp(deg[:, 0]) == pytest.approx(70.0)
    assert "/gripper" not in str(RrdReader(path).store().schema().entity_paths())


def _temporal(path: Path) -> dict[tuple[str, str], np.ndarray]:
    """Every temporal component of a file: (entity, component) -> rows sorted by frame, with
    the three clocks in the first columns."""
    parts: dict[tuple[str, str], list[np.ndarray]] = defaultdict(list)
    for chunk in RrdReader(path).store().stream().filter(is_static=False).to_chunks():
        rb = chunk.to_record_batch()
        clocks = [rb.column(k).cast(pa.int64()).to_numpy() for k in TIMELINES]
        for name in rb.schema.names:
            if ":" in name:
                vals = _values(rb.column(name), rb.num_rows)  # numbers, or text as objects
                parts[(chunk.entity_path, name)].append(np.column_stack([*clocks, vals]))
    return {
        k: (a := np.concatenate(v))[np.argsort(a[:, 0], kind="stable")] for k, v in parts.items()
    }


def test_spilled_timeline_records_the_same(tmp_path: Path) -> None:
    sim = Simulator(thesis_joints.build(), "path", dt=0.001, memory_limit=0)
    thesis_joints.program(sim)
    assert sim.timeline.spilled_blocks >= 2
    tl, mem = sim.timeline, Timeline(sim.timeline.nq, memory_limit=None)
    done = 0
    for e in tl.events:  # the same frames and events, in the same order
        mem.extend(
            tl.sim_times(done, e.frame + 1),
            tl.wall_times(done, e.frame + 1),
            tl.qpos(done, e.frame + 1),
        )
        done = e.frame + 1
        mem.add_event(e.t, e.robot, e.kind, e.detail, data=e.data)
    mem.extend(tl.sim_times(done), tl.wall_times(done), tl.qpos(done))
    assert mem.events == tl.events
    sim_mem = copy.copy(sim)
    sim_mem.timeline = mem
    assert mem.spilled_blocks == 0
    a, b = tmp_path / "spilled.rrd", tmp_path / "memory.rrd"
    record(sim, a, chunk_frames=1000, fps=None)  # batches that straddle the timeline's blocks
    record(sim_mem, b, fps=None)
    ta, tb = _temporal(a), _temporal(b)
    assert ta.keys() == tb.keys()
    assert len(ta) > 10
    for key in ta:
        np.testing.assert_array_equal(ta[key], tb[key], err_msg=str(key))
    assert len(ta[("/joints/puma", "Scalars:scalars")]) == sim.frames


def test_sim_data_untouched_and_stats(tmp_path: Path) -> None:
    sim = run_cell()
    before = sim.data.qpos.copy(), sim.data.xpos.copy()
    stats = record(sim, tmp_path / "a.rrd")
    assert np.array_equal(sim.data.qpos, before[0])
    assert np.array_equal(sim.data.xpos, before[1])
    assert stats.frames == sim.frames
    assert stats.events == 7
    assert stats.moving_bodies == sum(sim.model.body_weldid[1:] != 0)
    assert stats.path == tmp_path / "a.rrd"
    assert stats.bytes == (tmp_path / "a.rrd").stat().st_size
    assert [p.name for p in tmp_path.iterdir()] == ["a.rrd"]  # no temp file left


def test_user_errors(joints_rec: tuple[Simulator, Path], tmp_path: Path) -> None:
    sim, _ = joints_rec
    with pytest.raises(RecordError, match="nowhere to record"):
        record(sim)
    with pytest.raises(RecordError, match=r"end in \.rrd"):
        record(sim, tmp_path / "run.txt")
    with pytest.raises(RecordError, match="does not exist"):
        record(sim, tmp_path / "missing" / "run.rrd")
    with pytest.raises(RecordError, match="chunk_frames"):
        record(sim, tmp_path / "run.rrd", chunk_frames=0)
    with pytest.raises(RecordError, match="viewer URL"):
        record(sim, connect="localhost")
    assert list(tmp_path.iterdir()) == []


def test_failed_recording_keeps_the_old_file(
    joints_rec: tuple[Simulator, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    sim, _ = joints_rec
    target = tmp_path / "run.rrd"
    target.write_bytes(b"old")

    def boom(*args: object, **kwargs: object) -> None:
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(rerun_log, "log_timeline", boom)
    with pytest.raises(RuntimeError, match="disk on fire"):
        record(sim, target)
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["run.rrd"]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_live_viewer_options_route_to_grpc(
    joints_rec: tuple[Simulator, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """No viewer is spawned: an in-process gRPC server stands in for it."""
    sim, _ = joints_rec
    server = rr.RecordingStream("stand_in_viewer")
    url = server.serve_grpc(grpc_port=_free_port())
    spawned: list[int] = []

    def fake_spawn(port: int) -> str:
        spawned.append(port)
        return url

    monkeypatch.setattr(rerun_log, "_spawn_viewer", fake_spawn)
    stats = record(sim, tmp_path / "also.rrd", spawn=True, port=12345, fps=None)
    assert spawned == [12345]
    assert stats.frames == sim.frames
    assert stats.path == tmp_path / "also.rrd"
    frames, _ = read(tmp_path / "also.rrd", "/joints/puma", "Scalars:scalars")
    assert len(frames) == sim.frames  # the file is complete beside the stream
    stats = record(sim, connect=url, fps=None)
    assert stats.path is None
    assert stats.bytes is None
    assert stats.frames == sim.frames
    assert spawned == [12345]
    server.disconnect()


def test_progress_bar_on_request(
    joints_rec: tuple[Simulator, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    sim, _ = joints_rec
    record(sim, tmp_path / "quiet.rrd")  # stderr is no terminal here: no bar
    assert capsys.readouterr().err == ""
    record(sim, tmp_path / "bar.rrd", progress=True)
    err = capsys.readouterr().err
    assert err.startswith("\rrecord:")
    assert f"/{sim.frames} [" in err


def test_a_1khz_run_is_recorded_at_60_fps_with_its_events_exact(tmp_path: Path) -> None:
    """The default keeps the first frame of each 1/60 s (plus the ends and every event's
    frame): about 60 frames per simulated second instead of 1000, at each kept frame the
    exact timeline pose, every event at its own frame and time."""
    from workcell.examples import thesis_pick_place as pp

    sim = pp.run("path", 0.001)
    n, T = sim.frames, sim.sim_time
    full, slim = tmp_path / "full.rrd", tmp_path / "slim.rrd"
    a = record(sim, full, fps=None)
    b = record(sim, slim)
    assert a.frames == n
    events = sim.events
    assert math.floor(T * 60) + 1 <= b.frames <= math.floor(T * 60) + 2 + len(events)
    assert b.bytes < a.bytes / 8
    frames, deg = read(slim, "/joints/puma", "Scalars:scalars")
    assert len(frames) == b.frames
    times = sim.timeline.sim_times()
    assert np.all(np.diff(times[frames]) <= 1 / 60 + 0.001 + 1e-9)  # gaps: 1/60 s + dt at most
    Q = sim.timeline.qpos()
    adr = sim._qadr["puma"]
    np.testing.assert_allclose(deg, np.degrees(Q[frames][:, adr]), atol=1e-9)
    assert {e.frame for e in events} <= set(frames.tolist())
    ev_frames, _ = read(slim, "/events", "TextLog:text")
    assert ev_frames.tolist() == sorted(e.frame for e in events)
    t_ns, _ = read(slim, "/events", "TextLog:text", index="sim_time")
    assert sorted(t_ns.tolist()) == sorted(round(e.t * 1e9) for e in events)
    with pytest.raises(RecordError, match="fps must be"):
        record(sim, tmp_path / "bad.rrd", fps=0)


def test_kept_frames_by_hand() -> None:
    t = np.arange(11) * 0.01  # 100 Hz for 0.1 s
    keep = rerun_log.kept_frames(t, 50.0)  # every 0.02 s
    assert np.flatnonzero(keep).tolist() == [0, 2, 4, 6, 8, 10]
    keep = rerun_log.kept_frames(t, 30.0, np.array([5]))  # 0, 1/30, 2/30, 3/30 s; event at 5
    assert np.flatnonzero(keep).tolist() == [0, 4, 5, 7, 10]
    assert rerun_log.kept_frames(t, None).all()
    assert rerun_log.kept_frames(t, 1000.0).all()


def _blueprint_column(path: Path, suffix: str) -> list:
    reader = RrdReader(path)
    (bp,) = reader.blueprints()
    for chunk in reader.store(store=bp).stream().to_chunks():
        rb = chunk.to_record_batch()
        for name in rb.schema.names:
            if name.endswith(suffix):
                return rb.column(name).flatten().flatten().to_pylist()
    raise AssertionError(f"no {suffix} in the blueprint")


def test_blueprint_frames_the_cell(cell_rec: tuple[Simulator, Path]) -> None:
    """The 3D view opens on the cell: every visual point of the first and last frames lies
    inside a 4:3 picture with MuJoCo's field of view (45 deg vertical) from the stored eye
    towards the stored look-at point."""
    sim, path = cell_rec
    eye = np.array(_blueprint_column(path, "EyeControls3D:position"), dtype=float)
    look = np.array(_blueprint_column(path, "EyeControls3D:look_target"), dtype=float)
    axis = (look - eye) / np.linalg.norm(look - eye)
    d = mujoco.MjData(sim.model)
    for i in (0, -1):
        d.qpos[:] = sim.timeline.frame(i)[2]
        mujoco.mj_kinematics(sim.model, d)
        P = visual_points(sim.model, d) - eye
        right = np.cross(axis, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        up = np.cross(right, axis)
        depth = P @ axis
        tv = math.tan(math.radians(sim.model.vis.global_.fovy) / 2)
        assert np.all(depth > 0)
        assert np.abs(P @ up / depth).max() < tv  # in a 640 x 480 picture of that camera
        assert np.abs(P @ right / depth).max() < tv * 4 / 3


def test_gripper_series_is_a_step(cell_rec: tuple[Simulator, Path]) -> None:
    """Points that share a pixel are drawn as their min and max, not averaged: a 0/1
    gripper signal stays a step when zoomed out (rerun's aggregation policy MinMax)."""
    _, path = cell_rec
    policy = read_static(path, "/gripper/arm", "SeriesLines:aggregation_policy")
    assert int(policy[0]) == int(rr.components.AggregationPolicy.MinMax.value)
