"""The ``workcell render`` and ``workcell info`` subcommands.

``workcell render CELL.json --out FILE.png [--camera NAME] [--width W] [--height H]``
draws a saved cell in its initial state; ``workcell info CELL.json [--json]`` lists its
robots (joint limits), parts, cameras and which robot can reach each movable part.

Top-level imports stay light: ``workcell --help`` imports this module.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from typing import Any

from workcell.examples import CELL_HELP, load_cell

__all__ = [
    "GRASP_YAWS_DEG",
    "cell_info",
    "collision_info",
    "format_info",
    "reachability",
    "register",
]

GRASP_YAWS_DEG = (0.0, 45.0, 90.0, 135.0)  # yaws of the top-down grasps tried (deg)


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``render`` and ``info`` to the ``workcell`` subparsers ``sub``."""
    render = sub.add_parser(
        "render",
        help="draw a cell (JSON) in its initial state as a PNG",
        description="Render a saved cell in its initial state with MuJoCo's offscreen "
        "renderer (MUJOCO_GL=egl, else osmesa).",
    )
    render.add_argument("cell", metavar="CELL", help=CELL_HELP)
    render.add_argument("--out", metavar="FILE.png", required=True, help="the PNG to write")
    render.add_argument(
        "--camera",
        metavar="NAME",
        help="a camera of the cell, or a view: overview (the default), front, back, left, "
        "right, top",
    )
    render.add_argument("--width", type=int, default=640, help="pixels (default 640)")
    render.add_argument("--height", type=int, default=480, help="pixels (default 480)")
    render.add_argument(
        "--collision",
        action="store_true",
        help="draw the collision pieces (each its own colour) instead of the visual meshes",
    )
    _concavity_option(render)
    render.set_defaults(func=_render)
    info = sub.add_parser(
        "info",
        help="list a cell's robots, parts, cameras and reachability",
        description="Describe a saved cell: robots with joint limits, parts, cameras, and "
        "for each movable part and robot whether a top-down grasp over the part's "
        "centroid is reachable (kinematics only: joint limits, no collision check).",
    )
    info.add_argument("cell", metavar="CELL", help=CELL_HELP)
    info.add_argument("--json", action="store_true", help="print one JSON object")
    _concavity_option(info)
    info.set_defaults(func=_info)


def _concavity_option(parser: argparse.ArgumentParser) -> None:
    from workcell.decompose import DEFAULT_CONCAVITY

    parser.add_argument(
        "--concavity",
        type=float,
        default=DEFAULT_CONCAVITY,
        help="error bound of the convex decomposition of non-convex parts (CoACD "
        f"threshold, a fraction of the part's size; default {DEFAULT_CONCAVITY})",
    )


def _render(args: argparse.Namespace) -> int:
    from workcell.cli_common import check_outputs
    from workcell.record.render import gl_backend, render_cell, save_png

    check_outputs(png=args.out)
    t0 = time.perf_counter()
    cell = load_cell(args.cell)
    image = render_cell(
        cell,
        camera=args.camera,
        width=args.width,
        height=args.height,
        collision=args.collision,
        concavity=args.concavity,
    )
    path = save_png(image, args.out)
    view = f"camera '{args.camera}'" if args.camera else "overview camera"
    if args.collision:
        view += ", collision pieces"
    print(
        f"wrote {path} ({args.width} x {args.height}, {view}, {gl_backend()}, "
        f"{time.perf_counter() - t0:.2f} s)"
    )
    return 0


def _info(args: argparse.Namespace) -> int:
    info = cell_info(load_cell(args.cell), concavity=args.concavity)
    print(json.dumps(info) if args.json else format_info(info))
    return 0


def _r(v: Any, nd: int = 6) -> list[float]:
    return [round(float(x), nd) for x in v]


def reachability(cell: Any) -> list[dict[str, Any]]:
    """For each movable part and each robot: can the tool reach a top-down grasp?

    The target is the part's centroid (world, from its initial pose) with the tool's z
    axis pointing straight down, at the yaws ``GRASP_YAWS_DEG`` about the vertical. An
    OPW or UR robot is solved in closed form (``Robot.ik_closed_form``, any solution
    within the joint limits), other robots by ``Robot.ik``. Kinematics only: no collision check.
    Returns ``{part, robot, reachable, configs, yaw_deg, reason}`` rows.
    """
    import numpy as np

    from workcell.errors import WorkcellError
    from workcell.spatial import invert, rot_x, rot_z

    rows = []
    for pname, part in cell.movable_parts.items():
        centre = (part.pose @ cell.centroid_frame(pname))[:3, 3]
        for rname, placed in cell.robots.items():
            robot, B = placed.robot, invert(placed.base)
            configs: list[str] = []
            yaw_ok: list[float] = []
            reason = ""
            for yaw in GRASP_YAWS_DEG:
                T = np.eye(4)
                T[:3, 3] = centre
                T = B @ T @ rot_z(math.radians(yaw)) @ rot_x(math.pi)  # tool z down
                try:
                    if robot.ik_family is not None:
                        sols = [s for s in robot.ik_closed_form(T, placed.q) if s.success]
                        found = [s.config or "" for s in sols]
                        if not found:
                            from workcell.robots.ik_closed import ik_report

                            reason = ik_report(robot, T, placed.q)[1] or "no solution"
                    else:
                        s = robot.ik(T, placed.q)
                        found = [s.config or "numeric"] if s.success else []
                        if not s.success:
                            reason = s.reason
                except WorkcellError as exc:
                    found, reason = [], str(exc)
                if found:
                    yaw_ok.append(yaw)
                    configs.extend(c for c in found if c not in configs)
            rows.append(
                {
                    "part": pname,
                    "robot": rname,
                    "reachable": bool(yaw_ok),
                    "configs": configs,
                    "yaw_deg": yaw_ok,
                    "reason": "" if yaw_ok else reason,
                    "target": _r(centre),
                }
            )
    return rows


def collision_info(cell: Any, entity: tuple[str, str], concavity: float) -> dict[str, Any]:
    """How a part collides: ``method`` (see :class:`workcell.meshgeoms.CollisionPieces`),
    the number of convex ``pieces`` and ``volume_excess``: the pieces' total volume over
    the part's exact volume, minus 1 (0 when exact; > 0 where pieces bridge concavities
    or overlap)."""
    from workcell.meshgeoms import collision_pieces

    c = collision_pieces(cell.model, entity, concavity)
    exact = float(cell.model.world_mesh(entity).volume)
    total = sum(float(p.volume) for p in c.pieces)
    return {
        "method": c.method,
        "pieces": len(c.pieces),
        "volume_excess": round(total / exact - 1.0, 9) if exact > 0 else None,
        "concavity": concavity if c.method == "coacd" else None,
    }


def cell_info(cell: Any, *, concavity: float | None = None) -> dict[str, Any]:
    """The cell as JSON-able data: robots (limits in deg or m), parts (with their collision
    pieces, non-convex ones decomposed within ``concavity``), cameras, reachability."""
    import numpy as np

    from workcell.decompose import DEFAULT_CONCAVITY

    concavity = DEFAULT_CONCAVITY if concavity is None else concavity

    robots = []
    for r in cell.robots.values():
        joints = []
        for j, lo, hi, q in zip(r.robot.joints, r.robot.lower, r.robot.upper, r.q, strict=True):
            f = math.degrees if j.kind == "revolute" else float
            joints.append(
                {
                    "name": j.name,
                    "kind": j.kind,
                    "unit": "deg" if j.kind == "revolute" else "m",
                    "lower": round(f(lo), 6),
                    "upper": round(f(hi), 6),
                    "initial": round(f(q), 6),
                }
            )
        robots.append(
            {
                "name": r.name,
                "model": r.builtin or r.robot.name,
                "gripper": r.robot.gripper is not None,
                "base_position_m": _r(r.base[:3, 3]),
                "tool_position_m": _r(r.tool_pose()[:3, 3]),
                "joints": joints,
            }
        )
    static = [
        {
            "name": p.name,
            "entity": list(p.entity),
            "position_m": _r(p.pose[:3, 3]),
            "collision": collision_info(cell, p.entity, concavity),
        }
        for p in cell.static_parts.values()
    ]
    movable = []
    for p in cell.movable_parts.values():
        lo, hi = cell.bounding_box(p.name)
        movable.append(
            {
                "name": p.name,
                "entity": list(p.entity),
                "position_m": _r(p.pose[:3, 3]),
                "centroid_m": _r((p.pose @ cell.centroid_frame(p.name))[:3, 3]),
                "size_m": _r(np.asarray(hi) - np.asarray(lo)),
                "mass_kg": round(cell.mass(p.name), 9),
                "collision": collision_info(cell, p.entity, concavity),
            }
        )
    cameras = [
        {
            "name": c.name,
            "position_m": _r(c.position),
            "target_m": _r(c.target),
            "fovy_deg": c.fovy,
        }
        for c in cell.cameras.values()
    ]
    return {
        "name": cell.name,
        "robots": robots,
        "static_parts": static,
        "movable_parts": movable,
        "cameras": cameras,
        "reachability": reachability(cell),
    }


def _xyz(v: list[float]) -> str:
    return "(" + ", ".join(f"{x:.3f}" for x in v) + ")"


def _collision(c: dict[str, Any]) -> str:
    n, method = c["pieces"], c["method"]
    if method == "coacd":
        what = f"{n} CoACD pieces (concavity {c['concavity']:g})"
    elif method == "exact":
        what = f"{n} exact convex pieces (the convex blocks it is made of)"
    else:
        what = "convex, its own piece" if method == "convex" else "its convex hull"
    excess = c["volume_excess"]
    if c["method"] != "convex" and excess is not None:
        what += f", {excess * 100:+.2f} % volume"
    return f"collides as {what}"


def format_info(info: dict[str, Any]) -> str:
    """A human-readable report of :func:`cell_info` data."""
    out = [
        f"cell '{info['name']}': {len(info['robots'])} robot(s), "
        f"{len(info['static_parts'])} static and {len(info['movable_parts'])} movable "
        f"part(s), {len(info['cameras'])} camera(s)",
        "",
        "robots",
    ]
    if not info["robots"]:
        out.append("  none")
    for r in info["robots"]:
        grip = " with gripper" if r["gripper"] else ""
        out.append(
            f"  {r['name']}: {r['model']}{grip}, base at {_xyz(r['base_position_m'])} m, "
            f"tool at {_xyz(r['tool_position_m'])} m"
        )
        out.append(f"    {'joint':10s} {'lower':>9s} {'upper':>9s} {'initial':>9s}")
        for j in r["joints"]:
            out.append(
                f"    {j['name']:10s} {j['lower']:9.2f} {j['upper']:9.2f} {j['initial']:9.2f}"
                f"  {j['unit']}"
            )
    out += ["", "static parts"]
    out += [
        f"  {p['name']}: {p['entity'][0]} '{p['entity'][1]}' at {_xyz(p['position_m'])} m; "
        f"{_collision(p['collision'])}"
        for p in info["static_parts"]
    ] or ["  none"]
    out += ["", "movable parts"]
    out += [
        f"  {p['name']}: {p['entity'][0]} '{p['entity'][1]}', {p['mass_kg']:.4g} kg, "
        f"size {' x '.join(f'{s:.3f}' for s in p['size_m'])} m, "
        f"centroid {_xyz(p['centroid_m'])} m; {_collision(p['collision'])}"
        for p in info["movable_parts"]
    ] or ["  none"]
    out += ["", "cameras"]
    out += [
        f"  {c['name']}: at {_xyz(c['position_m'])} m looking at {_xyz(c['target_m'])} m, "
        f"fovy {c['fovy_deg']:g} deg"
        for c in info["cameras"]
    ] or ["  none"]
    out += ["", "reachability (top-down grasp over each movable part's centroid; kinematics only)"]
    if not info["reachability"]:
        out.append("  no movable parts or no robots")
    for row in info["reachability"]:
        if row["reachable"]:
            yaws = ", ".join(f"{y:g}" for y in row["yaw_deg"])
            verdict = f"reachable ({', '.join(row['configs'])}; yaw {yaws} deg)"
        else:
            verdict = f"NOT reachable: {row['reason']}"
        out.append(f"  {row['part']:12s} by {row['robot']:10s} {verdict}")
    return "\n".join(out)
