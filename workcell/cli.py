"""The ``workcell`` command line."""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

__all__ = ["main"]


def _demo_solids(args: argparse.Namespace) -> int:
    from workcell.examples.thesis_solids import build, format_report, report
    from workcell.modeller.model import Model

    t0 = time.perf_counter()
    model, exact = build()
    rows = report(model, exact)
    elapsed = time.perf_counter() - t0
    out = Path(args.save) if args.save else Path(tempfile.gettempdir()) / "thesis_solids.json"
    model.save(out)
    same = Model.load(out).to_dict() == model.to_dict()
    if args.json:
        print(
            json.dumps(
                {
                    "solids": [r.__dict__ for r in rows],
                    "model_file": str(out),
                    "round_trip_exact": same,
                    "wall_time_s": elapsed,
                }
            )
        )
    else:
        print("The thesis's example solids (ch. 2-3), built by the workcell modeller\n")
        print(format_report(rows))
        sq = model.info("square1")
        print(
            f"\nunit cube: one surface 'square1' pointed to {sq.pointed_by} times "
            f"(cube1 x6, para_block x6 by instancing)"
        )
        print(f"model saved to {out}; load gives an identical model: {same}")
        print(f"built, meshed and measured in {elapsed:.2f} s")
    return 0 if same and all(r.valid for r in rows) else 1


def _export(args: argparse.Namespace) -> int:
    from workcell.cell import Workcell, export_cell

    t0 = time.perf_counter()
    cell = Workcell.load(args.cell)
    path = export_cell(cell, args.out)
    print(f"wrote {path} ({time.perf_counter() - t0:.2f} s)")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``workcell`` command."""
    parser = argparse.ArgumentParser(
        prog="workcell", description="Robotic workcell simulator on MuJoCo."
    )
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="run a built-in example")
    demo.add_argument(
        "example", choices=["solids"], help="solids: the thesis's example solids (ch. 2-3)"
    )
    demo.add_argument("--save", metavar="FILE.json", help="where to save the example model")
    demo.add_argument(
        "--json", action="store_true", help="print one JSON object instead of a table"
    )
    demo.set_defaults(func=_demo_solids)
    export = sub.add_parser(
        "export", help="write a cell (JSON) as one MJCF file plus its STL meshes"
    )
    export.add_argument("cell", metavar="CELL.json", help="a cell saved by Workcell.save")
    export.add_argument("--out", metavar="DIR", required=True, help="output folder")
    export.set_defaults(func=_export)
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except Exception as exc:  # a WorkcellError is the user's; anything else is ours
        from workcell.errors import WorkcellError

        if isinstance(exc, WorkcellError):
            print(f"workcell: {type(exc).__name__}: {exc}", file=sys.stderr)
            return 2
        raise


if __name__ == "__main__":
    sys.exit(main())
