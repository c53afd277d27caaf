"""Collision geometry of imported robot links: hulls where they fit, coarse CoACD pieces
elsewhere, all in one batch on every core, each link bounded in time.

MuJoCo collides a mesh as its convex hull, so a non-convex link mesh of a robot file
(an elbow, a fork, a hollow casting) needs convex pieces. An importer hands each such
mesh to a :class:`LinkBatch` while it reads the file and asks for all the pieces at the
end (:meth:`LinkBatch.run`): one batch of child processes
(:func:`workcell.decompose.decompositions`), cached on disk as every decomposition is.
For each mesh:

1. **The hull, when it fits** (:data:`LINK_HULL_FIT`): the hull lies within 5 % of the
   link's size (its bounding-box diagonal) of the mesh's surface everywhere, and adds at
   most 10 % to the volume of a closed mesh. CoACD's pieces at the robot setting below
   come no closer (measured: they stand out from the surface by 3.7 % of the diagonal on
   average, 5.0 % at most, and add 37 % volume on average), so nothing is lost. Of the
   rtb-data and pybullet links, the iiwa's wrist links fit (3.9 %, +4.8 %) and most of
   pybullet's Panda's small collision parts; a typical elbow or fork strays 8-18 %.
2. **CoACD's pieces at the robot setting** (:data:`LINK_CONCAVITY` 0.1 with
   :data:`LINK_OPTIONS`: a voxel remesh at 20 instead of 50, 500 surface samples instead
   of 2000, 20 MCTS iterations of 10 nodes, depth 2, instead of 150 of 20, depth 3).
   Measured on 14 typical links of the rtb-data and pybullet robots (KR 3, KR 6, iiwa,
   IRB 140, Puma 560, Trossen, pybullet iiwa): 14.9 s of CPU for all 14 (0.1-3.6 s a
   link, 113 pieces), where CoACD's defaults take 5-50 s a link (KR 6 R900 link 2: 12 s,
   iiwa link 5: 26 s, KR 3 link 4: 47 s, IRB 140 link 4: 50 s); the pieces keep the
   concavities open that the hull fills (the hull adds 106 % volume on average). The
   existing contact tests pass with them (the L-shaped link keeps its notch open).
3. **The hull, when CoACD runs out of time** (:data:`LINK_SECONDS` = 20 s of wall time a
   link, at most ``max_native_seconds``): a warning names the link and the link collides
   as its hull, which is conservative (it may report contact inside a concavity, never
   miss one); the outcome is cached with the bound, so the next import is as fast and
   says the same, and a larger ``link_seconds`` tries again.

A native crash (an abort, out of memory) is a :class:`~workcell.errors.NativeCrashError`
(a ModelError) naming the file and the link; Ctrl-C stops the children at once. On a
terminal a progress bar with an estimate of the time left runs while links are
decomposed; otherwise one summary line goes to stderr. Nothing is printed when every
link comes from the cache.
"""

from __future__ import annotations

import sys
import time
import warnings
from collections import Counter
from dataclasses import dataclass, field

import trimesh

from workcell.decompose import HullFit, decompositions

__all__ = ["LINK_CONCAVITY", "LINK_HULL_FIT", "LINK_OPTIONS", "LINK_SECONDS", "LinkBatch"]

LINK_CONCAVITY = 0.1  # CoACD's threshold for robot links (parts: 0.05)
LINK_OPTIONS: dict[str, object] = {
    "preprocess_resolution": 20,  # CoACD's default 50 (its documented range 20-100)
    "resolution": 500,  # 2000: surface samples of the concavity measure
    "mcts_iterations": 20,  # 150
    "mcts_nodes": 10,  # 20
    "mcts_max_depth": 2,  # 3
}
LINK_HULL_FIT = HullFit(distance=0.05, volume=0.1)
LINK_SECONDS = 20.0  # s of wall time a link's decomposition may take


@dataclass
class LinkBatch:
    """The non-convex collision meshes of one robot file, decomposed together (module
    doc). ``what`` names the file in messages, ``robot`` in the progress line;
    ``concavity`` and ``seconds`` as :data:`LINK_CONCAVITY` and :data:`LINK_SECONDS`."""

    what: str
    robot: str = "robot"
    concavity: float = LINK_CONCAVITY
    seconds: float = LINK_SECONDS
    meshes: list[trimesh.Trimesh] = field(default_factory=list)
    labels: list[str] = field(default_factory=list)

    def add(self, mesh: trimesh.Trimesh, label: str) -> int:
        """Queue ``mesh`` (a link's collision mesh, ``label`` naming it: "link 'x' (line
        7) collision 1"); its index in :meth:`run`'s result."""
        self.meshes.append(mesh)
        self.labels.append(label)
        return len(self.meshes) - 1

    def run(self) -> list[tuple[trimesh.Trimesh, ...]]:
        """The convex pieces of every queued mesh (in its frame, m), in order."""
        if not self.meshes:
            return []
        progress = _Progress(self.robot, len(self.meshes))
        try:
            found = decompositions(
                self.meshes,
                self.concavity,
                labels=[f"{self.what}: {lb}" for lb in self.labels],
                on_start=progress.start,
                on_done=progress.done,
                options=LINK_OPTIONS,
                hull_fit=LINK_HULL_FIT,
                seconds=self.seconds,
            )
        finally:
            progress.close()
        for label, d in zip(self.labels, found, strict=True):
            if d.method == "timeout":
                warnings.warn(
                    f"{self.what}: {label}: its convex decomposition took over "
                    f"{self.seconds:g} s, so it collides as its convex hull (larger than "
                    "the mesh where the mesh is hollow or concave); give more time with "
                    "link_seconds=",
                    stacklevel=4,
                )
        pieces = sum(len(d.pieces) for d in found if d.method == "coacd")
        progress.summary(Counter(d.method for d in found), pieces)
        return [tuple(d.pieces) for d in found]


class _Progress:
    """A tqdm bar on a terminal while links are decomposed; one line otherwise."""

    def __init__(self, robot: str, total: int) -> None:
        self.robot, self.total, self.ran = robot, total, 0
        self.t0 = time.perf_counter()
        self.bar = None
        self.tty = sys.stderr.isatty()

    def start(self, n: int) -> None:
        if self.tty:
            from tqdm import tqdm

            self.bar = tqdm(
                total=n,
                desc=f"{self.robot}: link collision geometry",
                unit="link",
                file=sys.stderr,
                leave=False,
            )

    def done(self, i: int, label: str, seconds: float) -> None:
        self.ran += 1
        if self.bar is not None:
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()

    def summary(self, methods: Counter, pieces: int) -> None:
        if not self.ran:  # everything came from the cache: say nothing
            return
        parts = [f"{methods['coacd']} decomposed ({pieces} pieces in all)"]
        if methods["hull"]:
            parts.append(f"{methods['hull']} close to their hulls")
        if methods["timeout"] + methods["unsplit"]:
            parts.append(f"{methods['timeout'] + methods['unsplit']} left as hulls")
        print(
            f"workcell: {self.robot}: collision geometry of {self.total} non-convex link "
            f"mesh(es) in {time.perf_counter() - self.t0:.1f} s: {', '.join(parts)}",
            file=sys.stderr,
        )
