"""The ``workcell`` command line."""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import json
import signal
import sys
import time
from pathlib import Path

from workcell import limits
from workcell.cli_common import add_record_fps, check_outputs, interrupted, run_command
from workcell.examples import CELL_HELP, CELLS

__all__ = ["SUBCOMMAND_MODULES", "add_record_fps", "check_outputs", "main", "run_command"]

# Modules that add their own subcommands: each has ``register(sub)``, which adds its
# parsers to the ``argparse`` subparsers ``sub`` and sets ``func`` (args -> exit code).
# Keep their top-level imports light: ``workcell --help`` imports every one of them.
SUBCOMMAND_MODULES: tuple[str, ...] = (
    "workcell.record.cli_render",
    "workcell.program.cli",
    "workcell.robots.cli",
    "workcell.study.cli",
    "workcell.program.progcli",
    "workcell.view.cli",
)


def _demo_solids(args: argparse.Namespace) -> int:
    from workcell.examples.thesis_solids import build, format_report, report
    from workcell.modeller.model import Model

    if args.save:
        from workcell.errors import ModelError
        from workcell.files import check_writable

        check_writable(args.save, error=ModelError)
    t0 = time.perf_counter()
    model, exact = build()
    rows = report(model, exact)
    elapsed = time.perf_counter() - t0
    # the save/load round trip: through the file asked for, else through JSON text in memory
    if args.save:
        out: Path | None = Path(args.save)
        model.save(out)
        same = Model.load(out).to_dict() == model.to_dict()
    else:
        out = None
        data = json.loads(json.dumps(model.to_dict()))
        same = Model.from_dict(data).to_dict() == model.to_dict()
    if args.json:
        print(
            json.dumps(
                {
                    "solids": [r.__dict__ for r in rows],
                    "model_file": None if out is None else str(out),
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
        where = f"saved to {out}" if out else "saved as JSON in memory (--save FILE writes it)"
        print(f"model {where}; loading it gives an identical model: {same}")
        print(f"built, meshed and measured in {elapsed:.2f} s")
    return 0 if same and all(r.valid for r in rows) else 1


TITLES = {
    "conveyor": "beyond the thesis: a belt, a light beam and a UR5e stacking boxes",
    "joints": "the thesis's example 1 (ch. 5): one Puma 260 moved in joint space",
    "pick-place": "the thesis's example 2 (ch. 5): pick and place with one Puma 260",
    "handoff": "the thesis's example 3 (ch. 5): two Puma 260s hand a sphere over",
    "obstacle": "beyond the thesis: a wall between two stages, direct against pick/place",
}


def _demo_cell(args: argparse.Namespace) -> int:
    from workcell.cell import export_cell
    from workcell.examples import example as example_module

    example = example_module(args.example)
    check_outputs(rrd=args.save, png=args.render, folder=args.mjcf)
    t0 = time.perf_counter()
    sim = example.run(args.mode, args.dt)
    result = sim
    if args.physics:
        from workcell.sim.physics import run_physics

        result = run_physics(sim, progress=not args.json)
    out = result.summary()
    if args.mjcf:
        out["mjcf"] = str(export_cell(example.build(), args.mjcf))
    if args.save:
        from workcell.record import record

        stats = record(
            result,
            args.save,
            progress=None if args.json else True,
            images_fps=args.images,
            fps=args.record_fps or None,
        )
        out["rrd"] = str(stats.path)
        out["rrd_bytes"] = stats.bytes
        out["rrd_frames"] = stats.frames
    if args.render:
        from workcell.record import contact_sheet

        # the key moments: the start and every grasp and release (moves when none)
        kinds = ("grasp", "release")
        if not any(e.kind in kinds for e in result.events):
            kinds = ("move",)
        keys = contact_sheet(
            result, args.render, kinds=kinds, tile_width=400, tile_height=300, columns=5
        )
        out["png"] = str(Path(args.render))
        out["png_frames"] = [k.frame for k in keys]
    elapsed = time.perf_counter() - t0
    if args.json:
        print(json.dumps(out))
        return 0
    kind = "physics (mj_step)" if args.physics else f"kinematic, {args.mode} mode"
    print(f"{TITLES[args.example]}; {kind}\n")
    for e in out["events"]:
        print(f"  t = {e['t']:8.3f} s  {e['robot'] or '-':8s} {e['kind']:9s} {e['detail']}")
    print(
        f"\nsimulated time {out['sim_time_s']:.2f} s; {out['frames']} frames at dt = {args.dt:g} s; "
        f"{out['collisions']} collision(s)"
    )
    if args.mode == "joint-by-joint" and not args.physics:
        from workcell.program.format import joint_by_joint_clocks

        print(joint_by_joint_clocks(out["sim_time_s"], out["frames"], args.dt))
    if args.example == "joints":
        print("(eq. 4.27: 170 deg / 0.3 rad/s = 9.89 s)")
    for name, pos in out["objects"].items():
        print(f"{name}'s centroid ends at ({', '.join(f'{v:.4f}' for v in pos)}) m")
    phys = out.get("physics")
    if phys:
        for robot, t in phys["tracking"].items():
            print(
                f"{robot} tracking: joints max {t['joint_max_rad'] * 1e3:.2f} mrad "
                f"(rms {t['joint_rms_rad'] * 1e3:.2f}), tool max {t['tool_max_m'] * 1e3:.2f} mm"
            )
        for part, p in phys["parts"].items():
            state = "resting" if p["resting"] else "still moving"
            print(
                f"{part} settled {p['distance_m'] * 1e3:.2f} mm from the kinematic result, {state}"
            )
    wall = max(out["wall_time_s"], 1e-12)
    print(
        f"simulator wall clock {out['wall_time_s']:.3f} s ({out['sim_time_s'] / wall:.0f}x real "
        f"time); total {elapsed:.2f} s"
    )
    if out.get("mjcf"):
        print(
            f"cell written to {out['mjcf']} (open it with: python -m mujoco.viewer --mjcf {out['mjcf']})"
        )
    if out.get("rrd"):
        mb = (out.get("rrd_bytes") or 0) / 1e6
        print(
            f"recording written to {out['rrd']} ({mb:.1f} MB, {out['rrd_frames']} of "
            f"{out['frames']} frames; open it with: rerun {out['rrd']})"
        )
    if out.get("png"):
        print(f"picture written to {out['png']}")
    return 0


def _demo(args: argparse.Namespace) -> int:
    if args.example == "solids":
        return _demo_solids(args)
    if args.dt is None:
        args.dt = 0.01
    if not args.dt > 0:
        from workcell.errors import ProgramError

        raise ProgramError(f"--dt must be > 0 s, got {args.dt}")
    if args.example == "conveyor":
        from workcell.record.conveyor_demo import demo

        check_outputs(rrd=args.save, png=args.render, folder=args.mjcf)
        return demo(
            args.mode, args.dt, render=args.render, as_json=args.json, save=args.save,
            mjcf=args.mjcf, physics=args.physics, record_fps=args.record_fps or None,
        )  # fmt: skip
    if args.example == "obstacle":
        from workcell.record.obstacle_demo import demo

        if args.physics:
            from workcell.errors import ProgramError

            raise ProgramError("demo obstacle has no --physics run; try demo pick-place --physics")
        return demo(
            args.mode,
            args.dt,
            render=args.render,
            as_json=args.json,
            save=args.save,
            mjcf=args.mjcf,
        )
    return _demo_cell(args)


def _export(args: argparse.Namespace) -> int:
    from workcell.cell import export_cell
    from workcell.examples import load_cell

    t0 = time.perf_counter()
    cell = load_cell(args.cell)
    path = export_cell(cell, args.out)
    print(f"wrote {path} ({time.perf_counter() - t0:.2f} s)")
    return 0


def _export_cell(args: argparse.Namespace) -> int:
    from workcell.examples import load_cell

    cell = load_cell(args.cell)
    cell.save(args.out)
    print(
        f"wrote {args.out} (cell '{cell.name}': {len(cell.robots)} robot(s), "
        f"{len(cell.static_parts)} static and {len(cell.movable_parts)} movable part(s))"
    )
    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``workcell`` command (Ctrl-C at any moment: one line, status 130).

    While the subcommands' modules are imported (MuJoCo, trimesh, ...: about a second), a
    Ctrl-C is held until the imports are done: some extension modules turn an interrupt
    in their initialisation into an ImportError, or lose it.
    """
    held: list[int] = []
    previous = signal.getsignal(signal.SIGINT)
    hold = previous is signal.default_int_handler  # not when Ctrl-C is ignored or handled
    if hold:
        signal.signal(signal.SIGINT, lambda signum, frame: held.append(signum))
    try:
        parser = _parser()
    finally:
        if hold:
            signal.signal(signal.SIGINT, previous)
    if held:
        return interrupted()
    return run_command(parser.parse_args(argv))


def _parser() -> argparse.ArgumentParser:
    from workcell import __version__

    parser = argparse.ArgumentParser(
        prog="workcell", description="Robotic workcell simulator on MuJoCo."
    )
    parser.add_argument("--version", action="version", version=f"workcell {__version__}")
    parser.add_argument(
        "--limit",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="raise (or lower) a work limit of workcell.limits for this run, e.g. "
        "--limit max_facets=2e6 (limits: "
        + ", ".join(f.name for f in dataclasses.fields(limits.Limits))
        + ")",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="run a built-in example")
    demo.add_argument(
        "example",
        choices=["solids", *CELLS],
        help="solids: the thesis's example solids (ch. 2-3); joints, pick-place, handoff: "
        "its three example workcells (ch. 5); obstacle: a wall between two stages, the "
        "direct program against pick/place; conveyor: a belt, a light beam and a UR5e "
        "stacking boxes, two programs run together (throughput and utilisation)",
    )
    demo.add_argument(
        "--mode",
        choices=["path", "joint-by-joint", "playback"],
        default="path",
        help="simulation mode (thesis 4.4; default path). In joint-by-joint mode the joints "
        "move one after another, a frame every dt, but the simulated time is the thesis's "
        "clock: each move lasts its largest joint motion / speed, as in path mode, so "
        "frames x dt is longer than the simulated time (both are printed)",
    )
    demo.add_argument("--dt", type=float, metavar="SECONDS", help="sampling interval (0.01)")
    demo.add_argument("--mjcf", metavar="DIR", help="also export the cell as MJCF to DIR")
    demo.add_argument(
        "--physics", action="store_true", help="also run the program dynamically (mj_step)"
    )
    demo.add_argument(
        "--save",
        metavar="FILE",
        help="solids: save the model (JSON) to FILE; cells: record the run to FILE.rrd",
    )
    add_record_fps(demo)
    demo.add_argument(
        "--images",
        type=float,
        metavar="FPS",
        help="with --save: also put pictures in the recording, FPS per simulated second",
    )
    demo.add_argument(
        "--render",
        metavar="FILE.png",
        help="a picture of the run: the start and every grasp and release, side by side",
    )
    demo.add_argument(
        "--json", action="store_true", help="print one JSON object instead of a table"
    )
    demo.set_defaults(func=_demo)
    export = sub.add_parser(
        "export", help="write a cell (JSON) as one MJCF file plus its STL meshes"
    )
    export.add_argument("cell", metavar="CELL", help=CELL_HELP)
    export.add_argument("--out", metavar="DIR", required=True, help="output folder")
    export.set_defaults(func=_export)
    export_cell = sub.add_parser(
        "export-cell",
        help="write a cell as its versioned JSON (an example cell by name, or a cell file)",
        description="Write a cell as the JSON that Workcell.save writes and 'workcell render', "
        "'info', 'export', 'shell --cell' and 'cell load' read: "
        "workcell export-cell pick-place --out cell.json",
    )
    export_cell.add_argument("cell", metavar="CELL", help=CELL_HELP)
    export_cell.add_argument("--out", metavar="FILE.json", required=True, help="the file to write")
    export_cell.set_defaults(func=_export_cell)
    for module in SUBCOMMAND_MODULES:
        importlib.import_module(module).register(sub)
    return parser


if __name__ == "__main__":
    sys.exit(main())
