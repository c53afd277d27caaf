"""Robot files as a tree of rigid links, and the :class:`Robot` a chain through it gives.

The URDF and MJCF importers (:mod:`workcell.robots.urdf`, :mod:`workcell.robots.mjcf_import`)
read a file into the same tree: :class:`TreeLink` by name, each placed in its parent's
frame by ``origin`` (4x4, m; the URDF joint origin, the MJCF body pose at q = 0) and moved
by ``joint`` (a :class:`~workcell.robots.chain.Joint` whose ``origin`` is that placement;
None for a fixed joint or an MJCF body without joints), carrying :class:`Shape` meshes.
:func:`build_robot` turns it into a Robot:

1. **The chain**: the links from ``base`` to ``tip``; fixed joints fold into the origin of
   the next movable joint, those after the last one (and ``tool``, e.g. an MJCF site) into
   the robot's tool, so ``fk(q)`` is the tip frame (or the tool) in the base frame.
2. **Geometry**: every link attached to a chain link through fixed joints only moves with
   it; its shapes become :class:`~workcell.robots.robot.LinkGeometry` meshes of that
   chain link. A visible shape is one entry (colliding through its ``pieces`` when it has
   them); the hidden collision shapes of a link join its first visible shape that does
   not collide yet (else its first visible shape, else they are shown themselves).
3. **The gripper** (``keep_gripper``): a link whose rigid group (the link and what is
   fixed to it) has exactly two movable children, both prismatic, sliding in opposite
   directions with equal travel, with nothing movable behind them, is a parallel gripper
   (the Panda's hand). When it is fixed to the last chain link it becomes the robot's
   :class:`~workcell.robots.gripper.Gripper`: its frame is the palm's, turned so the
   fingers open along +-y (z as near the palm's z as that allows); each finger's q runs
   from closed (0) to open (``finger_travel``, its file range's length), the side that
   moves the fingers apart being open; solids are stored open; the TCP is ``tool`` when
   that lies on the palm, else on the fingers' middle a quarter of their length back from
   their tips (as :func:`~workcell.robots.gripper.parallel_gripper`'s default).
4. **Other branches** (links behind a movable joint off the chain: a second arm, a
   gripper not kept) are left out with a warning naming their joints.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import trimesh
from numpy.typing import NDArray

from workcell.errors import ModelError, WorkcellError
from workcell.modeller.model import Model
from workcell.robots.chain import Joint
from workcell.robots.gripper import Gripper, GripperPart
from workcell.robots.robot import LinkGeometry, Robot, RobotFile
from workcell.spatial import invert, translation

__all__ = ["Shape", "TreeLink", "build_robot", "default_tip"]

Array = NDArray[np.float64]
_EYE = np.eye(4)


@dataclass(frozen=True, eq=False)
class Shape:
    """A mesh on a link: ``mesh`` (m) in its own frame, placed by ``transform`` (4x4 rigid)
    in the link frame, RGBA ``colour`` (None: the default grey). ``visible``: drawn (a
    URDF visual, an MJCF geom in groups 0-2); ``pieces``: convex collision pieces in the
    shape's frame, ``()`` for the mesh's own hull, None when the shape does not collide."""

    mesh: trimesh.Trimesh
    transform: Array
    colour: tuple[float, ...] | None = None
    visible: bool = True
    pieces: tuple[trimesh.Trimesh, ...] | None = None


@dataclass(eq=False)
class TreeLink:
    """A rigid link of a robot file (see the module doc). ``what`` names it in messages
    (``"link 'x' (line 7)"``); ``unsupported`` says why its joint cannot be in a chain
    (a planar or floating joint, a body with two joints), empty when it can."""

    name: str
    parent: str | None
    origin: Array = field(default_factory=lambda: np.eye(4))
    joint: Joint | None = None
    shapes: list[Shape] = field(default_factory=list)
    what: str = ""
    unsupported: str = ""

    @property
    def movable(self) -> bool:
        """Moved by a joint of its own (its frame is not fixed in its parent's)."""
        return self.joint is not None or bool(self.unsupported)


def _children(links: Mapping[str, TreeLink]) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {name: [] for name in links}
    for link in links.values():
        if link.parent is not None:
            out[link.parent].append(link.name)
    return out


def _rigid(
    name: str, links: Mapping[str, TreeLink], children: Mapping[str, list[str]]
) -> Iterator[tuple[str, Array]]:
    """``name`` and the links fixed to it (through fixed joints only), each with its frame
    in ``name``'s frame."""
    stack = [(name, _EYE)]
    while stack:
        n, T = stack.pop()
        yield n, T
        stack.extend(
            (c, T @ links[c].origin) for c in reversed(children[n]) if not links[c].movable
        )


def _movable_children(
    name: str, links: Mapping[str, TreeLink], children: Mapping[str, list[str]]
) -> list[tuple[str, Array]]:
    """The movable links hanging off ``name``'s rigid group, each with its origin frame
    (its joint's frame at q = 0) in ``name``'s frame."""
    return [
        (c, T @ links[c].origin)
        for n, T in _rigid(name, links, children)
        for c in children[n]
        if links[c].movable
    ]


@dataclass(frozen=True)
class _Hand:
    palm: str
    fingers: tuple[tuple[str, Array, Array], tuple[str, Array, Array]]  # (link, T open, y dir)
    travel: float


def _solids_centre(
    name: str, T: Array, links: Mapping[str, TreeLink], children: Mapping[str, list[str]]
) -> Array | None:
    """Mean of the shape centroids of ``name``'s rigid group placed by T (None: no shapes)."""
    pts = [
        (T @ Tr @ s.transform)[:3, :3] @ s.mesh.centroid + (T @ Tr @ s.transform)[:3, 3]
        for n, Tr in _rigid(name, links, children)
        for s in links[n].shapes
    ]
    return np.mean(pts, axis=0) if pts else None


def _find_hands(links: Mapping[str, TreeLink], children: Mapping[str, list[str]]) -> list[_Hand]:
    """Parallel grippers of the tree (module doc, rule 3): a palm link whose rigid group
    has exactly two movable children, both prismatic children of the palm itself."""
    hands = []
    for palm in links:
        movers = _movable_children(palm, links, children)
        if len(movers) != 2 or any(
            links[c].parent != palm or links[c].joint is None or links[c].joint.kind != "prismatic"
            for c, _ in movers
        ):
            continue
        if any(_movable_children(c, links, children) for c, _ in movers):
            continue
        (a, Ta), (b, Tb) = movers
        ja, jb = links[a].joint, links[b].joint
        da, db = Ta[:3, :3] @ ja.axis, Tb[:3, :3] @ jb.axis
        ta, tb = (hi - lo for lo, hi in (ja.limits, jb.limits))
        if np.linalg.norm(da + db) > 1e-6 or abs(ta - tb) > 1e-9:
            continue
        # which way opens: the side that moves the fingers' solids (else frames) apart
        centres = []
        for c, T in movers:
            T_lo = T @ links[c].joint.motion(links[c].joint.limits[0])
            centre = _solids_centre(c, T_lo, links, children)
            centres.append(T_lo[:3, 3] if centre is None else centre)
        sign = 1.0 if float((centres[0] - centres[1]) @ da) >= 0 else -1.0
        fingers = []
        for (c, T), d in zip(movers, (da, db), strict=True):
            j = links[c].joint
            q_open = j.limits[1] if sign > 0 else j.limits[0]
            fingers.append((c, T @ j.motion(q_open), sign * d))
        hands.append(_Hand(palm, (fingers[0], fingers[1]), ta))
    return hands


def default_tip(links: Mapping[str, TreeLink], base: str, *, skip: Sequence[str] = ()) -> str:
    """The end of the longest chain below ``base``: the link of the last movable joint on
    the path with most movable joints (the first such path in file order; ``base``
    itself when nothing below it moves). Links in ``skip`` (gripper fingers) and what
    hangs off them are not counted."""
    children = _children(links)
    best, best_n = base, 0
    stack = [(base, 0, base)]
    while stack:
        n, k, last = stack.pop()
        if k > best_n:
            best, best_n = last, k
        for c in reversed(children[n]):
            if c in skip:
                continue
            moved = links[c].movable
            stack.append((c, k + moved, c if moved else last))
    return best


def _path(links: Mapping[str, TreeLink], base: str, tip: str, what: str) -> list[str]:
    """The links after ``base`` down to ``tip`` (ModelError when tip is not below base)."""
    path, n = [], tip
    while n != base:
        if n is None:
            raise ModelError(
                f"{what}: '{tip}' is not below '{base}' in the file's tree; a chain runs "
                f"from the base down to the tip"
            )
        path.append(n)
        n = links[n].parent
    return path[::-1]


def _entries(link: int, T: Array, shapes: Sequence[Shape]) -> list[LinkGeometry]:
    """LinkGeometry of one tree link's shapes, placed by T in chain link ``link``'s frame
    (module doc, rule 2)."""
    shown = [s for s in shapes if s.visible]
    hidden = [s for s in shapes if not s.visible and s.pieces is not None]
    if not shown:
        shown, hidden = hidden, []
    out = [
        LinkGeometry(
            link,
            None,
            T @ s.transform,
            s.colour,
            mesh=s.mesh,
            collision=s.pieces or (),
            collides=s.pieces is not None,
        )
        for s in shown
    ]
    if hidden and out:
        k = next((i for i, g in enumerate(out) if not g.collides), 0)
        host = shown[k]
        to_host = invert(host.transform)
        pieces = [
            p.copy().apply_transform(to_host @ s.transform)
            for s in hidden
            for p in (s.pieces or (s.mesh.convex_hull,))
        ]
        own = list(out[k].collision) or ([host.mesh.convex_hull] if out[k].collides else [])
        out[k] = replace(out[k], collision=tuple(own + pieces), collides=True)
    return out


def _gripper(
    hand: _Hand,
    links: Mapping[str, TreeLink],
    children: Mapping[str, list[str]],
    T_palm: Array,
) -> Gripper | None:
    """The hand as a Gripper mounted at ``T_palm`` (palm frame in the last chain link's
    frame, turned as the module doc says); None (with a warning) when it cannot be one."""
    y = hand.fingers[0][2] / np.linalg.norm(hand.fingers[0][2])
    z = np.array([0.0, 0.0, 1.0]) - y[2] * y
    if np.linalg.norm(z) < 0.1:
        warnings.warn(
            f"gripper at '{hand.palm}': its fingers slide along the palm's z axis; it is "
            "left out (attach a parallel_gripper() instead)",
            stacklevel=4,
        )
        return None
    z /= np.linalg.norm(z)
    G = np.eye(4)
    G[:3, 0], G[:3, 1], G[:3, 2] = np.cross(y, z), y, z
    to_g = invert(G)
    parts: list[GripperPart] = []
    heads = [("palm", hand.palm, _EYE)]
    heads += [(r, f[0], f[1]) for r, f in zip(("left", "right"), hand.fingers, strict=True)]
    for role, head, T0 in heads:
        for n, Tr in _rigid(head, links, children):
            for g in _entries(0, to_g @ T0 @ Tr, links[n].shapes):
                part = GripperPart(role, None, g.transform, g.colour, mesh=g.mesh)
                parts.append(replace(part, collision=g.collision, collides=g.collides))
    V = [p.vertices(Model()) for p in parts if p.role != "palm"]
    V = np.concatenate(V) if V else np.zeros((1, 3))
    tip, root = float(V[:, 2].max()), float(V[:, 2].min())
    mid = (V.min(axis=0) + V.max(axis=0)) / 2
    tcp = translation(mid[0], mid[1], tip - (tip - root) / 4)
    return Gripper(
        name="gripper",
        model=Model(),
        geometry=tuple(parts),
        max_opening=2.0 * hand.travel,
        finger_travel=hand.travel,
        tcp=tcp,
        mount=T_palm @ G,
    )


def build_robot(
    links: Mapping[str, TreeLink],
    *,
    base: str,
    tip: str | None,
    tool: Array | None = None,
    name: str,
    source: str,
    file: RobotFile | None = None,
    poses: Mapping[str, Mapping[str, float]] | None = None,
    keep_gripper: bool = True,
    what: str = "robot file",
) -> Robot:
    """The Robot of the chain from ``base`` to ``tip`` (module doc). ``tip`` None: the end
    of the longest chain, and the TCP of a kept gripper as the tool. ``tool`` (4x4) is
    placed in the tip frame (an MJCF site). ``poses``: named joint values by joint name
    (rad/m; missing joints 0). ``source`` gets the chain appended. ``what`` names the
    file in messages (ModelError)."""
    children = _children(links)
    hands = _find_hands(links, children)
    fingers = {f[0] for h in hands for f in h.fingers}
    given_tip = tip is not None
    tip = default_tip(links, base, skip=tuple(fingers)) if tip is None else tip
    path = _path(links, base, tip, what)
    on_path = set(path)
    joints: list[Joint] = []
    T = _EYE
    for n in path:
        link = links[n]
        T = T @ link.origin
        if link.unsupported:
            raise ModelError(f"{what}: {link.what}: {link.unsupported}")
        if link.joint is not None:
            try:
                joints.append(replace(link.joint, origin=T))
            except WorkcellError as exc:
                raise ModelError(f"{what}: {link.what}: {exc}") from exc
            T = _EYE
    if not joints:
        raise ModelError(f"{what}: no movable joint between '{base}' and '{tip}'")
    tool_T = T @ (_EYE if tool is None else tool)
    # the rigid groups: chain link k and what is fixed to it
    heads = [base] + [n for n in path if links[n].joint is not None]
    last_group = dict(_rigid(heads[-1], links, children))
    hand = next((h for h in hands if h.palm in last_group), None) if keep_gripper else None
    gripper = _gripper(hand, links, children, last_group[hand.palm]) if hand else None
    palm_group = {n for n, _ in _rigid(hand.palm, links, children)} if gripper else set()
    geometry: list[LinkGeometry] = []
    left_out: list[str] = []
    for k, head in enumerate(heads):
        for n, Tr in _rigid(head, links, children):
            if n not in palm_group:
                geometry.extend(_entries(k, Tr, links[n].shapes))
            for c in children[n]:
                if links[c].movable and c not in on_path and c not in fingers:
                    left_out.append(links[c].joint.name if links[c].joint else c)
    if gripper is not None:
        if not given_tip and tool is None:
            tool_T = gripper.mount @ gripper.tcp
        else:
            gripper = replace(gripper, tcp=invert(gripper.mount) @ tool_T)
    if left_out:
        warnings.warn(
            f"{what}: the links behind joint(s) {', '.join(left_out)} are not on the chain "
            f"'{base}' -> '{tip}' and are left out",
            stacklevel=3,
        )
    q_poses = {
        key: np.array([float(v.get(j.name, 0.0)) for j in joints])
        for key, v in (poses or {}).items()
    }
    try:
        return Robot(
            name=name,
            joints=tuple(joints),
            tool=tool_T,
            poses=q_poses,
            geometry=tuple(geometry),
            source=f"{source}, chain {base} -> {tip}",
            gripper=gripper,
            file=file,
        )
    except WorkcellError as exc:
        raise ModelError(f"{what}: {exc}") from exc
