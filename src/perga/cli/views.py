"""Looking at a run: ``perga render`` (a preview PNG) and ``perga report`` (a Markdown page)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from perga.cli.common import AddParser, at_least_one, problems


def render(args: argparse.Namespace) -> int:
    """A preview, the trajectories or the process figure of a run, as PNG."""
    from perga.output.render import TRACKS
    from perga.output.render import render as render_run

    if args.process:
        from perga.output.process_figure import process_figure

        out = args.output or args.run / "process.png"
        try:
            process_figure(args.run, out)
        except FileNotFoundError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        print(f"wrote {out}")
        return 0
    out = args.output or args.run / ("trajectories.png" if args.trajectories else "preview.png")
    try:
        t = render_run(
            args.run,
            out,
            time=args.time,
            trajectories=args.trajectories,
            tracks=args.tracks or TRACKS,
        )
    except FileNotFoundError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {out} (t = {t:.6g} s)")
    return 0


def report(args: argparse.Namespace) -> int:
    """RUN/report/report.md with its figures."""
    from perga.case import CaseError
    from perga.output.tables import TableError
    from perga.studies.run_report import write_run_report

    try:
        path = write_run_report(args.run, args.output)
    except (FileNotFoundError, CaseError, TableError) as exc:
        return problems([str(exc)])
    print(f"wrote {path} (figures beside it)")
    return 0


def add_parsers(add: AddParser) -> None:
    """``perga render`` and ``perga report``."""
    parser = add("render", help="a preview PNG of a run (matplotlib, no OpenGL)")
    parser.add_argument("run", type=Path, metavar="RUN", help="a run directory")
    parser.add_argument("--time", type=float, help="the frame nearest this time, s (default last)")
    parser.add_argument(
        "--trajectories", action="store_true",
        help="the paths of the granules with the most impacts, coloured by speed",
    )  # fmt: skip
    parser.add_argument(
        "--tracks", type=at_least_one,
        help="how many paths --trajectories draws (default 8)",
    )  # fmt: skip
    parser.add_argument(
        "--process", action="store_true",
        help="counts, outlet mass flow and survival over time (RUN/process.png)",
    )  # fmt: skip
    parser.add_argument("-o", "--output", type=Path, help="PNG (default RUN/preview.png)")
    parser.set_defaults(handler=render)
    parser = add(
        "report",
        help="a run as a Markdown page with figures (RUN/report/report.md)",
        epilog="example: perga run cases/separator.toml -o runs/sep && perga report runs/sep",
    )
    parser.add_argument("run", type=Path, metavar="RUN", help="a run directory")
    parser.add_argument("-o", "--output", type=Path, help="folder (default: RUN/report)")
    parser.set_defaults(handler=report)
