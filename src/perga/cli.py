"""The ``perga`` command line: parses, calls the library, prints.

Exit codes: 0 success, 2 bad input (the problems are printed, never a traceback), 1 a failed run,
3 a run that reached its end with its energy ledger off (beyond ``solver.ledger_tolerance``),
128 + the signal's number after a stop signal (130 Ctrl-C, 143 SIGTERM, 129 SIGHUP;
:mod:`perga.stopping`). Everything heavy is imported inside the commands, after the stop signals
are handled, so a signal during start-up is a clean stop too.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

from perga import __version__
from perga.progress import counted, progress_bar
from perga.stopping import StopRequest, StopSignal, exit_status, raise_on_stop_signals

BUNDLED_CASES = Path(__file__).resolve().parents[2] / "cases"

EXAMPLES = """examples:
  perga new fed-separator -o my.toml          a commented case to start from
  perga validate my.toml                      every problem of a case, with the allowed range
  perga run my.toml --set rotor.rpm=1500      simulate (any key overridden) into runs/my
  perga report runs/my                        report.md with figures of the run
  perga run --resume runs/my                  go on after a stop or a crash
  perga sweep my.toml --set rotor.rpm=500:1700:4 --metric released_fraction -o sweep
  perga window my.toml --set rotor.rpm=500:1700:4 --set hammers.mass=0.025:0.075:3 -o window

exit status: 0 done, 1 a run that failed, 2 bad input, 3 a run whose energy ledger is off,
128 + N after signal N. Every case key: docs/case-files.md (perga schema --markdown)."""


def _default_case(name: str) -> Path:
    """A bundled case: ./cases/NAME if present, else the one beside the installed sources."""
    local = Path("cases") / name
    return local if local.exists() else BUNDLED_CASES / name


def _paper_check(args: argparse.Namespace) -> int:
    from perga.case import load_case
    from perga.studies.paper_check import Params, check_paper
    from perga.studies.paper_report import format_json, format_markdown, format_text, write_plots

    start = time.perf_counter()
    fitted, realistic = load_case(args.fitted), load_case(args.realistic)
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


def _accuracy(args: argparse.Namespace) -> int:
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


def _validate(args: argparse.Namespace) -> int:
    from perga.case import CaseError, load_case

    failed = 0
    for path in args.cases:
        try:
            load_case(path)
        except CaseError as exc:
            failed += 1
            _problems(exc.problems)
        else:
            print(f"ok: {path}")
    return 2 if failed else 0


def _new(args: argparse.Namespace) -> int:
    from perga.case import CaseError, load_case
    from perga.case.templates import TEMPLATES, write_template

    if args.template not in TEMPLATES:
        names = ", ".join(f"{k} ({v[1]})" for k, v in TEMPLATES.items())
        return _problems([f"perga new: no template {args.template!r}; there are: {names}"])
    try:
        written = write_template(args.template, args.output, args.overwrite)
    except FileExistsError as exc:
        return _problems([str(exc)])
    except OSError as exc:
        return _problems([f"cannot write {args.output}: {exc.strerror or exc}"])
    try:
        load_case(args.output)
    except CaseError as exc:  # a template that does not load is perga's defect
        _problems(exc.problems)
        return 1
    print(f"wrote {', '.join(str(p) for p in written)}; next: perga run {args.output}")
    return 0


def _report(args: argparse.Namespace) -> int:
    from perga.case import CaseError
    from perga.studies.run_report import write_run_report

    try:
        path = write_run_report(args.run, args.output)
    except (FileNotFoundError, CaseError) as exc:
        return _problems([str(exc)])
    print(f"wrote {path} (figures beside it)")
    return 0


def _schema(args: argparse.Namespace) -> int:
    from perga.case.reference import json_schema, markdown_reference

    print(
        markdown_reference() if args.markdown else json_schema(), end="" if args.markdown else "\n"
    )
    return 0


def _run(args: argparse.Namespace) -> int:
    if (args.case is None) == (args.resume is None):
        return _problems(["perga run needs a CASE or --resume RUN (one of them)"])
    if args.resume is not None and (args.set or args.output or args.overwrite or args.start_from):
        return _problems(
            ["--resume RUN goes on with the run as it was: no --set, -o, --overwrite, --from"]
        )
    with StopRequest() as stop:  # the imports and the case, never stopped halfway
        from perga.case import load_case
        from perga.checkpoints import CheckpointError
        from perga.runner import (
            LEDGER_OFF,
            RunStoppedError,
            check_resumable,
            ledger_closure_text,
            prepare_directory,
            resume_run,
            run_case,
        )

        if args.resume is not None:
            if not (args.resume / "case.toml").is_file():
                return _problems([f"{args.resume} is not a perga run (it has no case.toml)"])
            case = load_case(args.resume / "case.toml")
        elif args.start_from is not None:
            problem, case = _case_from_run(args.case, args.set or [], args.start_from)
            if problem:
                return _problems([problem])
        else:
            case = load_case(args.case, overrides=args.set or ())
        stop.check()
    if case.chamber is None:  # a parameter set (for paper-check), not a scene
        return _problems(
            [f"{args.case}: [chamber] is missing: perga run needs the wall around the rotor "
             "(a case without one is a parameter set for perga paper-check)"]
        )  # fmt: skip
    if args.resume is not None:
        directory = args.resume
        try:
            check_resumable(directory)
        except CheckpointError as exc:
            return _problems([f"cannot resume: {exc}"])
    else:
        directory = args.output or Path(case.output.directory.format(case=args.case.stem))
        try:
            prepare_directory(directory, args.overwrite)
        except FileExistsError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        except OSError as exc:  # a file in the way, no permission, a read-only file system
            print(f"error: cannot make the run directory {directory}: {exc.strerror or exc}; "
                  "choose another -o DIR", file=sys.stderr)  # fmt: skip
            return 2
    bar = progress_bar(
        case.solver.duration,
        "s simulated",
        "perga run",
        args.quiet,
        bar_format="{l_bar}{bar}| {n:.4f}/{total:.4f} s simulated [{elapsed}<{remaining}{postfix}]",
    )
    started = time.perf_counter()

    def progress(t: float, _duration: float, steps: int) -> None:
        bar.update(min(t, bar.total) - bar.n)
        bar.set_postfix_str(f"{steps / max(time.perf_counter() - started, 1e-9):.0f} steps/s")

    try:
        if args.resume is not None:
            summary = resume_run(case, directory, progress)
        else:
            summary = run_case(case, args.case, directory, progress, args.start_from or "")
    except CheckpointError as exc:
        bar.close()
        return _problems([f"cannot resume: {exc}"])
    except KeyboardInterrupt as exc:
        bar.close()
        print(f"interrupted: everything up to now is in {directory}; perga run --resume "
              f"{directory} goes on from its last checkpoint", file=sys.stderr)  # fmt: skip
        return exit_status(exc)
    except RunStoppedError as exc:
        bar.close()
        print(f"error: the run stopped: {exc}\nwhat was written is in {directory}", file=sys.stderr)
        return 1
    except OSError as exc:  # a full disk, a file system gone read-only, a removed directory
        bar.close()
        print(f"error: the run could not write its output: {exc}\nwhat was written is in "
              f"{directory} (summary.json says where it stopped)", file=sys.stderr)  # fmt: skip
        return 1
    bar.close()
    status = summary.status
    if status == LEDGER_OFF:
        status = f"completed, ledger off by {summary.energy['closure']:+.2%}"
    print(
        f"{status}: {summary.steps} steps, {summary.simulated_time:.4g} s simulated in "
        f"{summary.wall_time:.3g} s, {summary.impacts} impacts -> {directory}"
    )
    pop = summary.population
    if pop and (pop["fed"] != summary.granules or pop["released"] or pop["departed"]):
        print(
            f"granules: {pop['fed']} fed, {pop['released']} released from cells, "
            f"{pop['departed']} departed, {pop['broken']} broken, {pop['present']} present"
        )
    facts = []
    if summary.energy:
        facts.append(f"energy ledger closes to {ledger_closure_text(summary.energy)}")
    if summary.speeds:
        facts.append(f"granule speeds at the end {summary.speeds['mean']:.3g} m/s mean, "
                     f"{summary.speeds['max']:.3g} max")  # fmt: skip
    print("; ".join([*facts, f"figures: perga report {directory}"]))
    state = directory / "vtk" / "paraview_state.py"
    if state.exists():
        print(f"ParaView: paraview --state={state}")
    for warning in summary.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    if summary.status == LEDGER_OFF:
        print(f"error: {summary.reason}", file=sys.stderr)
        return 3
    return 0


def _case_from_run(case_path: Path, overrides: list[str], start_from: str):
    """(a problem or "", the case) for ``perga run CASE --from RUN[:TIME]``: CASE with its
    granules replaced by RUN's at that frame (:func:`perga.runner.granules_of_run`)."""
    import numpy as np
    from pydantic import ValidationError

    from perga.case import CaseError, load_case
    from perga.case.load import overridden, read_case_data
    from perga.case.schema import Case
    from perga.case.sizes import initial_radii
    from perga.runner import RunStateError, granules_of_run

    run, _, time = start_from.rpartition(":")
    try:
        at = float(time) if run else None
    except ValueError:
        run, at = start_from, None  # a ':' in the path, no time
    run = run or start_from
    if at is not None and not (math.isfinite(at) and at >= 0):
        return f"--from {start_from}: the time must be a number of seconds >= 0", None
    try:
        taken, granules, radii = granules_of_run(Path(run), at)
    except RunStateError as exc:
        return f"--from {start_from}: {exc}", None
    everything = [*overrides, *granules]
    try:  # the sizes first, from the schema alone: a placement check would blame overlaps
        given = initial_radii(
            Case.model_validate(overridden(read_case_data(case_path), everything, case_path))
        )
    except (CaseError, ValidationError):
        given = radii  # load_case names the problem
    if not np.array_equal(given, radii):
        return (
            f"--from {start_from}: the run's granules at t = {taken} s have radii "
            f"{radii.min():g}-{radii.max():g} m, {case_path} gives {given.min():g}-"
            f"{given.max():g} m (granules.radius or granules.size): the sizes must be the same"
        ), None
    return "", load_case(case_path, overrides=everything)


def _render(args: argparse.Namespace) -> int:
    from perga.output.render import render

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
        t = render(args.run, out, time=args.time, trajectories=args.trajectories)
    except FileNotFoundError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {out} (t = {t:.6g} s)")
    return 0


def _compare(args: argparse.Namespace) -> int:
    from perga.case import load_case
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
    except FileNotFoundError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    fitted = _default_case("paper-fitted.toml")
    if args.paper:
        work = args.work or out / "runs"
        bar = progress_bar(0, "runs", "perga compare --paper", args.quiet)
        unfinished: list[str] = []
        try:
            runs += run_paper_study(fitted.parent, work, progress=counted(bar), **_cluster(args))
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
    print(
        f"wrote {out}/report.md ({len(data['figures'])} figures): {len(rows) - failed} of "
        f"{len(rows)} agreement rows within 1 %{largest}; "
        f"{len(data['rows']) - len(rows)} rows compare regimes that differ; "
        f"{len(data['unavailable'])} statistics not computed (report.md says why); "
        f"{time.perf_counter() - start:.1f} s"
    )
    return 1 if failed else 0


def _study_from_args(args: argparse.Namespace):
    """The study of ``perga sweep``: a study file, or a case with --set and --metric."""
    from perga.case.load import read_case_data
    from perga.studies.study_file import StudyError, load_study, study_from_options

    data = read_case_data(args.target)
    if "parameters" in data and "case" in data:
        if args.set or args.metric:
            raise StudyError([f"{args.target}: a study file takes no --set or --metric"])
        return load_study(args.target)
    return study_from_options(
        args.target, args.set or [], args.metric or [], args.replicates, args.seed
    )


T = TypeVar("T")


def _problems(problems: Sequence[str]) -> int:
    """Print each problem of a bad input as an error line; returns the exit status 2."""
    for problem in problems:
        print(f"error: {problem}", file=sys.stderr)
    return 2


def _at_least_one(text: str) -> int:
    """An argparse type: a whole number >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a whole number >= 1 (got {text!r})") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"at least 1 (got {value})")
    return value


def _study_options(parser: argparse.ArgumentParser) -> None:
    """The options a study with replicates shares: their seeds, and ``_cluster_options``."""
    parser.add_argument("--seed", type=int, default=0, help="seed of the replicates' seeds")
    _cluster_options(parser)


def _cluster_options(parser: argparse.ArgumentParser) -> None:
    """The options of runs on Dask (``_cluster``) and their progress."""
    parser.add_argument(
        "--workers", type=_at_least_one, help="local worker processes, >= 1 (default: free cores)"
    )
    parser.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler")
    parser.add_argument("--retry-failed", action="store_true", help="run failed runs again")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def _cluster(args: argparse.Namespace) -> dict[str, Any]:
    """A study's Dask options from the command line: scheduler, workers, retry_failed."""
    return {"scheduler": args.scheduler, "workers": args.workers, "retry_failed": args.retry_failed}


def _with_progress(args: argparse.Namespace, call: Callable[[Callable[[int, int], None]], T]) -> T:
    """``call(progress)`` under a progress bar (unless ``args.quiet``); after a stop signal it
    says where the finished runs are and how to resume, and re-raises."""
    bar = progress_bar(0, "runs", f"perga {args.command}", args.quiet)
    try:
        return call(counted(bar))
    except KeyboardInterrupt:
        bar.close()
        print(
            f"interrupted: the runs finished so far are in {args.output}/results.parquet; "
            "run the same command again to resume",
            file=sys.stderr,
        )
        raise
    finally:
        bar.close()


def _sweep(args: argparse.Namespace) -> int:
    from perga.studies.study_file import StudyError
    from perga.studies.sweep import sweep
    from perga.studies.sweep_report import write_plots

    try:
        study = _study_from_args(args)
    except StudyError as exc:
        return _problems(exc.problems)
    start = time.perf_counter()
    result = _with_progress(
        args,
        lambda progress: sweep(study, args.output, progress=progress, **_cluster(args)),
    )
    plots = write_plots(result.rows, list(study.parameters), study.metrics, args.output)
    print(
        f"{len(result.rows)} runs ({result.ran} run now, {result.reused} found finished, "
        f"{result.failed} failed) in {time.perf_counter() - start:.1f} s -> {result.path}, "
        f"{len(plots)} plots"
    )
    if result.failed:
        print(
            f"warning: {result.failed} runs failed: their status and reason are in "
            f"{result.path}; --retry-failed runs them again",
            file=sys.stderr,
        )
        return 1
    return 0


def _window(args: argparse.Namespace) -> int:
    from perga.studies.study_file import StudyError
    from perga.studies.window import in_window, run_window, window_study
    from perga.studies.window_report import write_maps, write_report

    try:
        window = window_study(
            args.case,
            args.set or [],
            replicates=args.replicates,
            seed=args.seed,
            release_target=args.release_target,
            damage_limit=args.damage_limit,
        )
    except StudyError as exc:
        return _problems(exc.problems)
    start = time.perf_counter()
    result = _with_progress(
        args,
        lambda progress: run_window(window, args.output, progress=progress, **_cluster(args)),
    )
    write_maps(result, args.output)
    write_report(result, args.output)
    best = result.best.point
    if best is None:
        verdict = "no point gave both a release and a damage fraction"
    else:
        where = f"{window.axes[0]} = {best.x:.6g}, {window.axes[1]} = {best.y:.6g}"
        verdict = (
            f"best {where}" if result.best.inside else f"no setting meets both; nearest {where}"
        )
    inside = sum(in_window(p, window.release_target, window.damage_limit) for p in result.points)
    print(
        f"{len(result.rows)} runs ({result.ran} run now, {result.reused} found finished, "
        f"{result.failed} failed) in {time.perf_counter() - start:.1f} s; {inside} of "
        f"{len(result.points)} points in the window; {verdict} "
        f"-> {args.output}/report.md, window.parquet, window.png"
    )
    if result.failed:
        print(
            f"warning: {result.failed} runs failed: their status and reason are in "
            f"{args.output}/results.parquet; --retry-failed runs them again",
            file=sys.stderr,
        )
        return 1
    return 0


def _calibrate(args: argparse.Namespace) -> int:
    from perga.case import load_case
    from perga.studies.calibrate import calibrate
    from perga.studies.calibrate_report import write_plots
    from perga.studies.study_file import StudyError

    load_case(args.case)  # the case itself first: its problems are a case file's
    start = time.perf_counter()
    try:
        result = calibrate(
            args.case,
            args.data,
            args.fit,
            args.output,
            method=args.method,
            steps=args.steps,
            scheduler=args.scheduler,
            workers=args.workers,
        )
    except StudyError as exc:
        return _problems(exc.problems)
    write_plots(result, args.output)
    fit = result.fit
    for key, value, (lo, hi) in zip(fit.keys, fit.values, fit.intervals, strict=True):
        print(f"{key} = {value:.6g}  (95 %: {lo:.6g} to {hi:.6g})")
    print(
        f"{fit.method}: {fit.runs} runs, residual sum of squares {fit.rss:.4g}, "
        f"{time.perf_counter() - start:.1f} s -> {args.output}/best.toml, fit.json"
    )
    return 0


def _metrics(args: argparse.Namespace) -> int:
    from perga.stats import load_run
    from perga.stats.metrics import METRICS, MetricUnavailableError, evaluate

    if args.run is None:
        for m in METRICS.values():
            arg = f":ARG ({m.argument})" if m.argument else ""
            print(f"{m.name}{arg} [{m.unit}]: {m.description}")
        return 0
    try:
        run = load_run(args.run)
    except FileNotFoundError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    status = 0
    for name in args.names or [n for n, m in METRICS.items() if m.argument is None]:
        try:
            print(f"{name} = {evaluate(run, name):.10g}")
        except MetricUnavailableError as exc:
            print(f"{name}: unavailable: {exc}")
        except ValueError as exc:
            print(f"error: {exc}", file=sys.stderr)
            status = 2
    return status


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    parser = argparse.ArgumentParser(
        prog="perga",
        description="perga: bee-bread granules struck by hammers on a rotor (2-D DEM), checked "
        "against the analytical model. Every run is driven by a case file (TOML).",
        epilog=EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"perga {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    check = sub.add_parser(
        "paper-check",
        help="evaluate every numerical claim of the paper under fitted and realistic parameters",
    )
    check.add_argument(
        "--fitted",
        type=Path,
        default=_default_case("paper-fitted.toml"),
        help="case with the parameters fitted to the paper (default: cases/paper-fitted.toml)",
    )
    check.add_argument(
        "--realistic",
        type=Path,
        default=_default_case("paper-realistic.toml"),
        help="case with realistic parameters (default: cases/paper-realistic.toml)",
    )
    check.add_argument("--format", choices=("text", "markdown", "json"), default="text")
    check.add_argument("--plots", metavar="DIR", help="write one PNG per claim into DIR")
    check.set_defaults(handler=_paper_check)
    run = sub.add_parser("run", help="simulate a case: tables and summary.json in a run directory")
    run.add_argument("case", type=Path, metavar="CASE", nargs="?")
    run.add_argument(
        "--resume",
        type=Path,
        metavar="RUN",
        help="go on with the stopped or killed run RUN from its newest checkpoint (no CASE)",
    )
    run.add_argument("-o", "--output", type=Path, help="run directory (default: output.directory)")
    run.add_argument(
        "--from",
        dest="start_from",
        metavar="RUN[:TIME]",
        help="start CASE's granules where the run RUN had them at its last frame at or before "
        "TIME s (default: its last): positions, velocities, spins; RUN's sizes must be CASE's",
    )
    run.add_argument("--overwrite", action="store_true", help="replace an existing run directory")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="override a key of the case, e.g. rotor.rpm=2400 or "
        "contacts.granule-hammer.restitution=0.65 (repeat for several; checked like the file)",
    )
    run.set_defaults(handler=_run)
    render = sub.add_parser("render", help="a preview PNG of a run (matplotlib, no OpenGL)")
    render.add_argument("run", type=Path, metavar="RUN", help="a run directory")
    render.add_argument("--time", type=float, help="the frame nearest this time, s (default last)")
    render.add_argument("--trajectories", action="store_true", help="granule paths, by time")
    render.add_argument(
        "--process", action="store_true",
        help="counts, outlet mass flow and survival over time (RUN/process.png)",
    )  # fmt: skip
    render.add_argument("-o", "--output", type=Path, help="PNG (default RUN/preview.png)")
    render.set_defaults(handler=_render)
    accuracy = sub.add_parser(
        "accuracy", help="work-precision study: error against closed forms vs wall time"
    )
    accuracy.add_argument(
        "-o", "--output", default="accuracy", help="output folder (default: ./accuracy)"
    )
    accuracy.add_argument("--quick", action="store_true", help="a small subset (tests, < 30 s)")
    accuracy.add_argument("--quiet", action="store_true", help="no line per setting on stderr")
    accuracy.set_defaults(handler=_accuracy)
    compare = sub.add_parser(
        "compare", help="runs against the analytical model: Markdown + PNG + JSON report"
    )
    compare.add_argument("runs", nargs="*", type=Path, metavar="RUN", help="run directories")
    compare.add_argument(
        "--paper",
        action="store_true",
        help="run the bundled paper cases and sweeps first (on Dask, as a sweep's runs)",
    )
    compare.add_argument("-o", "--output", type=Path, help="report folder (default reports/...)")
    compare.add_argument("--work", type=Path, help="--paper runs folder (default OUT/runs)")
    _cluster_options(compare)
    compare.set_defaults(handler=_compare)
    sweep = sub.add_parser(
        "sweep",
        help="run a case over parameter values on Dask: results.parquet and plots",
        description="Run a study (a study file, or a case with --set KEY=V1,V2 or "
        "KEY=LO:HI:N and --metric NAME) on a local Dask cluster or the one at --scheduler. "
        "Finished runs are found by key and not run again.",
    )
    sweep.add_argument("target", type=Path, metavar="STUDY_OR_CASE")
    sweep.add_argument("-o", "--output", type=Path, required=True, help="the study's folder")
    sweep.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUES",
        help="a case key and its values: V1,V2,... or LO:HI:N (a grid)",
    )
    sweep.add_argument("--metric", action="append", metavar="NAME", help="a metric to keep")
    sweep.add_argument("--replicates", type=int, default=1, help="runs per point (own seeds)")
    _study_options(sweep)
    sweep.set_defaults(handler=_sweep)
    window = sub.add_parser(
        "window",
        help="operating window over two keys on Dask: release, damage, throughput, energy/kg",
        description="Run a case over a grid of two keys (--set KEY=LO:HI:N twice; other --set "
        "KEY=VALUE are fixed), each point --replicates times with its own solver.seed, and map "
        "the mean and sd of released_fraction, damaged_fraction, throughput and energy_per_kg: "
        "window.parquet/.csv, window.png and report.md with the best setting inside "
        "released_fraction >= --release-target and damaged_fraction <= --damage-limit.",
    )
    window.add_argument("case", type=Path, metavar="CASE")
    window.add_argument("-o", "--output", type=Path, required=True, help="the study's folder")
    window.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUES",
        help="an axis KEY=LO:HI:N (exactly two), or a fixed KEY=VALUE",
    )
    window.add_argument("--replicates", type=int, default=2, help="runs per point (default 2)")
    window.add_argument(
        "--release-target", type=float, default=0.9, help="least released fraction, in [0, 1]"
    )
    window.add_argument(
        "--damage-limit", type=float, default=0.05, help="most damaged fraction, in [0, 1]"
    )
    _study_options(window)
    window.set_defaults(handler=_window)
    calibrate = sub.add_parser(
        "calibrate",
        help="fit case keys to measured data (least squares or Bayesian) on Dask",
        description="Each data row is simulated with its condition columns and the fitted "
        "keys; writes best.toml, fit.json and plots.",
    )
    calibrate.add_argument("case", type=Path, metavar="CASE")
    calibrate.add_argument("--data", type=Path, required=True, help="CSV: conditions, metrics")
    calibrate.add_argument(
        "--fit",
        action="append",
        required=True,
        metavar="KEY=LO:HI",
        help="a case key to fit and its bounds",
    )
    calibrate.add_argument("--method", choices=("least-squares", "bayes"), default="least-squares")
    calibrate.add_argument("--steps", type=int, default=100, help="bayes: emcee steps")
    calibrate.add_argument("-o", "--output", type=Path, required=True, help="output folder")
    calibrate.add_argument("--workers", type=int, help="local worker processes")
    calibrate.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler")
    calibrate.set_defaults(handler=_calibrate)
    metrics = sub.add_parser("metrics", help="the metrics of a run (or, without RUN, the list)")
    metrics.add_argument("run", type=Path, nargs="?", metavar="RUN")
    metrics.add_argument("names", nargs="*", metavar="NAME")
    metrics.set_defaults(handler=_metrics)
    new = sub.add_parser(
        "new",
        help="start a case from a commented template",
        description="Write a commented case to start from (a bundled case, its geometry files "
        "copied beside it). Templates: single-impact, rebound, separator, soft-separator, "
        "fed-separator.",
        epilog="example: perga new fed-separator -o my.toml && perga run my.toml",
    )
    new.add_argument("template", nargs="?", default="separator", help="default: separator")
    new.add_argument("-o", "--output", type=Path, required=True, help="the case file to write")
    new.add_argument("--overwrite", action="store_true", help="replace files in the way")
    new.set_defaults(handler=_new)
    report = sub.add_parser(
        "report",
        help="a run as a Markdown page with figures (RUN/report/report.md)",
        epilog="example: perga run cases/separator.toml -o runs/sep && perga report runs/sep",
    )
    report.add_argument("run", type=Path, metavar="RUN", help="a run directory")
    report.add_argument("-o", "--output", type=Path, help="folder (default: RUN/report)")
    report.set_defaults(handler=_report)
    validate = sub.add_parser("validate", help="check case files: schema and physical cross-checks")
    validate.add_argument("cases", nargs="+", type=Path, metavar="CASE")
    validate.set_defaults(handler=_validate)
    schema = sub.add_parser("schema", help="print the case-file JSON Schema")
    schema.add_argument("--markdown", action="store_true", help="the reference docs/case-files.md")
    schema.set_defaults(handler=_schema)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``perga`` console script."""
    raise_on_stop_signals()
    try:
        with StopRequest() as stop:  # imports are never interrupted halfway (perga.stopping)
            from perga.case import CaseError

            args = build_parser().parse_args(argv)
            stop.check()
        try:
            return args.handler(args)
        except CaseError as exc:
            return _problems(exc.problems)
    except KeyboardInterrupt as exc:  # a stop signal (perga.stopping) outside a run's own report
        name = exc.name if isinstance(exc, StopSignal) else "SIGINT"
        print(f"stopped by {name}", file=sys.stderr)
        return exit_status(exc)


if __name__ == "__main__":
    sys.exit(main())
