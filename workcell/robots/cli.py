"""``workcell robots``: the library of built-in robots, one line each (name, axes, reach, IK family, source)."""

from __future__ import annotations

import argparse
import json

__all__ = ["register", "rows"]


def rows() -> list[dict[str, object]]:
    """One record per library robot: ``name``, ``model``, ``axes``, ``reach_m``,
    ``ik_family`` (closed form: opw, ur; else numerical), ``source``."""
    from workcell.robots.library import entries

    out = []
    for e in entries():
        robot = e.build(geometry=False)
        out.append(
            {
                "name": e.name,
                "model": e.maker,
                "axes": robot.dof,
                "reach_m": e.reach,
                "ik_family": robot.ik_family or "numerical",
                "source": robot.source,
            }
        )
    return out


def _robots(args: argparse.Namespace) -> int:
    table = rows()
    if args.json:
        print(json.dumps(table, indent=1))
        return 0
    print(f"{'name':18} {'axes':>4} {'reach':>8} {'IK':9} model; source")
    for r in table:
        print(
            f"{r['name']:18} {r['axes']:>4} {r['reach_m']:>6.3f} m {r['ik_family']:9} "
            f"{r['model']}; {r['source']}"
        )
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``robots`` to the ``workcell`` subparsers ``sub``."""
    p = sub.add_parser(
        "robots",
        help="list the library's robots (name, axes, reach, IK family, source)",
        description="The built-in robots, usable by name in cells ('cell add robot r1 ur5e', "
        "Workcell.add_robot(name, 'ur5e')).",
    )
    p.add_argument("--json", action="store_true", help="print a JSON list instead of a table")
    p.set_defaults(func=_robots)
