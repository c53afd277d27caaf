"""Benchmark the solid modeller against trimesh's own functions, measured in one run.

Prints, for each case, our median time, trimesh's median time for the same shape, and
the ratio (targets: within 3x of trimesh; the 1,000-instance scene to one world mesh in
under 1 s):

- sphere m=128, n=64 built and meshed  vs  trimesh.creation.revolve of the same polyhedron;
- translational sweep of a surface with 200 holes  vs  trimesh.creation.extrude_polygon;
- a scene of 1,000 instanced blocks to one world mesh  vs  trimesh.util.concatenate of
  1,000 transformed copies.

Usage: python scripts/bench_modeller.py [--repeat N]
"""

from __future__ import annotations

import argparse

import numpy as np
import trimesh
from benchutil import paired_median_times
from shapely.geometry import Polygon

from workcell import solids, spatial
from workcell.modeller.model import Model
from workcell.modeller.surface import Surface


def holes_surface(n_holes: int = 200, segments: int = 16) -> tuple[Surface, Polygon]:
    side = int(np.ceil(np.sqrt(n_holes)))
    main = [(0, 0), (2 * side, 0), (2 * side, 2 * side), (0, 2 * side)]
    t = 2 * np.pi * np.arange(segments) / segments
    holes = [
        np.column_stack(
            [1 + 2 * (i % side) + 0.5 * np.cos(t), 1 + 2 * (i // side) + 0.5 * np.sin(t)]
        )
        for i in range(n_holes)
    ]
    return Surface(main, holes, name="plate"), Polygon(main, [h[::-1] for h in holes])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=31)
    args = ap.parse_args()
    rows = []

    m_, n_ = 128, 64

    def ours_sphere() -> trimesh.Trimesh:
        m = Model()
        solids.sphere(m, "s", radius=1.0, m=m_, n=n_)
        return m.world_mesh("s")

    def trimesh_sphere() -> trimesh.Trimesh:
        phi = np.linspace(-np.pi / 2, np.pi / 2, 2 * n_ + 1)
        return trimesh.creation.revolve(np.column_stack([np.cos(phi), np.sin(phi)]), sections=m_)

    a, b = ours_sphere(), trimesh_sphere()
    assert abs(a.volume - b.volume) < 1e-9 * b.volume, (a.volume, b.volume)
    rows.append(
        (
            "sphere m=128 n=64 build+mesh",
            len(a.faces),
            *paired_median_times(ours_sphere, trimesh_sphere, args.repeat),
        )
    )

    surf, poly = holes_surface()

    def ours_extrude() -> trimesh.Trimesh:
        m = Model()
        solids.extrude(m, "plate", surf, height=1.0)
        return m.world_mesh("plate")

    def trimesh_extrude() -> trimesh.Trimesh:
        return trimesh.creation.extrude_polygon(poly, 1.0)

    a, b = ours_extrude(), trimesh_extrude()
    assert abs(a.volume - b.volume) < 1e-9 * b.volume, (a.volume, b.volume)
    rows.append(
        (
            "extrude, 200 holes build+mesh",
            len(a.faces),
            *paired_median_times(ours_extrude, trimesh_extrude, args.repeat),
        )
    )

    m = Model()
    solids.cylinder(m, "part", radius=0.1, height=0.2, n=32)
    m.create("object", "obj")
    m.attach("obj", "part")
    m.create("scene", "cell")
    rng = np.random.default_rng(0)
    Ts = np.stack(
        [
            spatial.euler(rng.uniform(-np.pi, np.pi, 3), translation=rng.uniform(-5, 5, 3))
            for _ in range(1000)
        ]
    )
    m.attach_many("cell", "obj", Ts)
    m.world_mesh("part")  # block mesh cached, as in any real scene

    def ours_scene() -> trimesh.Trimesh:
        m._get("cell").cache.clear()
        m._get("obj").cache.clear()
        return m.world_mesh("cell")

    part = m.world_mesh("part")

    def trimesh_scene() -> trimesh.Trimesh:
        return trimesh.util.concatenate([part.copy().apply_transform(T) for T in Ts])

    a, b = ours_scene(), trimesh_scene()
    assert abs(a.volume - b.volume) < 1e-9 * b.volume
    rows.append(
        (
            "scene of 1,000 instances to world mesh",
            len(a.faces),
            *paired_median_times(ours_scene, trimesh_scene, args.repeat),
        )
    )

    print(f"{'case':40s} {'faces':>7s} {'ours ms':>9s} {'trimesh ms':>11s} {'ratio':>6s}  target")
    for name, faces, ours, theirs in rows:
        target = "<= 3x" + (", < 1 s" if "scene" in name else "")
        print(
            f"{name:40s} {faces:7d} {ours * 1e3:9.2f} {theirs * 1e3:11.2f} {ours / theirs:6.2f}  {target}"
        )


if __name__ == "__main__":
    main()
