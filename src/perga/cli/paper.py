"""The paper and the theory: ``perga paper-check`` (every numerical claim of the paper),
``perga compare`` (runs against the analytical model), ``perga accuracy`` (what accuracy costs
in time)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from perga.cli.common import AddParser, cluster, cluster_options, default_case
from perga.progress import counted, progress_bar


def paper_check(args: argparse.Namespace) -> int:
    """Every claim under the fitted and the realistic parameter sets."""
    from perga.case import load_case
    from perga.model.compile import check_parameters
    from perga.studies.paper_check import Params, check_paper
    from perga.studies.paper_report import format_json, format_markdown, format_text, write_plots

    start = time.perf_counter()
    fitted, realistic = load_case(args.fitted), load_case(args.realistic)
    for parameters in (fitted, realistic):
        check_parameters(parameters)
    rows = check_paper(fitted, realistic)
    fit_p, real_p = Params.from_case(fitted), Params.from_case(realistic)
    if args.format == "json":
        print(format_json(rows, fit_p, real_p))
    elif args.format == "markdown":
        print(format_markdown(rows), end="")
    else:
        print(format_text(rows))
    if args.plots:
        paths = write_plots(rows, fit_p, real_p, Path(args.plots))
        print(f"wrote {len(paths)} plots to {args.plots}", file=sys.stderr)
    verdicts = [r.fitted.verdict for r in rows]
    print(
        f"{len(rows)} rows: {verdicts.count('yes')} reproduced, {verdicts.count('partly')} partly, "
        f"{verdicts.count('no')} not (fitted set); {time.perf_counter() - start:.2f} s",
        file=sys.stderr,
    )
    return 0


def accuracy(args: argparse.Namespace) -> int:
    """The work-precision study: its tables, figure and recommended settings."""
    from perga.studies.accuracy import run_study
    from perga.studies.accuracy_report import recommended_table, write_outputs

    def progress(line: str) -> None:
        if not args.quiet:
            print(line, file=sys.stderr, flush=True)

    result = run_study(quick=args.quick, progress=progress)
    paths = write_outputs(result, Path(args.output))
    print(recommended_table(result.rows), end="")
    print(
        f"{len(result.rows)} rows, {len(paths)} files in {args.output}; {result.wall:.0f} s "
        f"(load {result.load[0]:.2f} -> {result.load[1]:.2f})",
        file=sys.stderr,
    )
    return 0


def compare(args: argparse.Namespace) -> int:
    """Runs (and with --paper the bundled paper runs) against the analytical model."""
    from perga.case import load_case
    from perga.output.tables import TableError
    from perga.stats import load_run
    from perga.studies.compare import analyse
    from perga.studies.compare_report import write_report
    from perga.studies.paper_check import Params
    from perga.studies.paper_runs import PaperRunsFailedError, run_paper_study

    if not args.runs and not args.paper:
        print("error: give run directories or --paper", file=sys.stderr)
        return 2
    start = time.perf_counter()
    out = args.output or Path("reports/paper" if args.paper else "reports/compare")
    try:
        runs = [load_run(d) for d in args.runs]
    except (FileNotFoundError, TableError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    fitted = default_case("paper-fitted.toml")
    if args.paper:
        work = args.work or out / "runs"
        bar = progress_bar(0, "runs", "perga compare --paper", args.quiet)
        unfinished: list[str] = []
        try:
            runs += run_paper_study(fitted.parent, work, progress=counted(bar), **cluster(args))
        except PaperRunsFailedError as exc:
            unfinished = exc.failed
        finally:
            bar.close()
        for run in unfinished:
            print(f"error: the paper run {run}", file=sys.stderr)
        if unfinished:
            print("--retry-failed runs them again", file=sys.stderr)
            return 1
    analyses = analyse(runs, Params.from_case(load_case(fitted)))
    command = "perga compare " + " ".join(sys.argv[2:]) if sys.argv[1:2] == ["compare"] else ""
    data = write_report(analyses, out, Params.from_case(load_case(fitted)), command)
    rows = [r for r in data["rows"] if r["tolerance"] is not None]
    failed = sum(not r["agrees"] for r in rows)
    worst = data["largest_agreement_error"]
    largest = f", largest error {worst:.2e}" if worst is not None else ""
    agreement = (
        f"{len(rows) - failed} of {len(rows)} agreement rows within 1 %{largest}"
        if rows
        else "no row compares the same physics"
    )
    print(
        f"wrote {out}/report.md ({len(data['figures'])} figures): {agreement}; "
        f"{len(data['rows']) - len(rows)} rows compare regimes that differ; "
        f"{len(data['unavailable'])} statistics not computed (report.md says why); "
        f"{time.perf_counter() - start:.1f} s"
    )
    return 1 if failed else 0


def add_parsers(add: AddParser) -> None:
    """``perga paper-check``, ``accuracy`` and ``compare``."""
    parser = add(
        "paper-check",
        help="evaluate every numerical claim of the paper under fitted and realistic parameters",
    )
    parser.add_argument(
        "--fitted",
        type=Path,
        default=default_case("paper-fitted.toml"),
        help="case with the parameters fitted to the paper (default: cases/paper-fitted.toml)",
    )
    parser.add_argument(
        "--realistic",
        type=Path,
        default=default_case("paper-realistic.toml"),
        help="case with realistic parameters (default: cases/paper-realistic.toml)",
    )
    parser.add_argument("--format", choices=("text", "markdown", "json"), default="text")
    parser.add_argument("--plots", metavar="DIR", help="write one PNG per claim into DIR")
    parser.set_defaults(handler=paper_check)
    parser = add("accuracy", help="work-precision study: error against closed forms vs wall time")
    parser.add_argument(
        "-o", "--output", default="accuracy", help="output folder (default: ./accuracy)"
    )
    parser.add_argument("--quick", action="store_true", help="a small subset (tests, < 30 s)")
    parser.add_argument("--quiet", action="store_true", help="no line per setting on stderr")
    parser.set_defaults(handler=accuracy)
    parser = add("compare", help="runs against the analytical model: Markdown + PNG + JSON report")
    parser.add_argument("runs", nargs="*", type=Path, metavar="RUN", help="run directories")
    parser.add_argument(
        "--paper",
        action="store_true",
        help="run the bundled paper cases and sweeps first (on Dask, as a sweep's runs)",
    )
    parser.add_argument("-o", "--output", type=Path, help="report folder (default reports/...)")
    parser.add_argument("--work", type=Path, help="--paper runs folder (default OUT/runs)")
    cluster_options(parser)
    parser.set_defaults(handler=compare)
