"""Shared test helpers for the modeller tests (reference values come from outside the code)."""

from __future__ import annotations

import math

import numpy as np
import trimesh

from workcell import spatial

D90 = math.pi / 2
UNIT_SQUARE = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
# the thesis's SRT rows for cube1 (§2), radians
THESIS_ROWS = [
    spatial.srt(rotation=(D90, 0, 0)),
    spatial.srt(rotation=(D90, 0, 0), translation=(0, 1, 0)),
    spatial.srt(rotation=(0, -D90, 0)),
    spatial.srt(rotation=(0, -D90, 0), translation=(1, 0, 0)),
    spatial.srt(),
    spatial.srt(translation=(0, 0, 1)),
]


def ngon_area(n: int, r: float) -> float:
    """Area of a regular n-gon with vertices on a circle of radius r (m^2)."""
    return 0.5 * n * r**2 * np.sin(2 * np.pi / n)


def snapshot(model):
    """Everything a failed constructor must leave alone: names, reference counts, relations."""
    out = {}
    for level, names in model.list().items():
        for nm in names:
            info = model.info((level, nm))
            out[(level, nm)] = (info.pointed_by, info.n_relations)
    return out


def check_solid(model, name):
    """World mesh is a closed, consistently and outwardly wound solid; our validity agrees."""
    mesh = model.world_mesh(name)
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert mesh.volume > 0
    report = model.validity(name)
    assert report.ok, report.problems
    return mesh


def assembled_as_placed(model, block):
    """The block's boundary built here, independently of the world mesher: every related
    surface triangulated, placed by its transform (winding reversed under a reflection, so
    the front side stays the front side) and welded by trimesh. No face is re-oriented."""
    vs, fs, base = [], [], 0
    for rel in model.relations(block):
        V2, F = model.surface(rel.target).triangulate()
        V = np.column_stack([V2, np.zeros(len(V2))]) @ rel.transform[:3, :3].T
        F = np.asarray(F)[:, ::-1] if np.linalg.det(rel.transform[:3, :3]) < 0 else F
        vs.append(V + rel.transform[:3, 3])
        fs.append(np.asarray(F) + base)
        base += len(V2)
    return trimesh.Trimesh(np.vstack(vs), np.vstack(fs), process=True)
