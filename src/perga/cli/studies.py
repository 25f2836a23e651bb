"""Studies on Dask: ``perga sweep``, ``perga window``, ``perga calibrate``, and ``perga
metrics`` (what a study keeps of a run)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from perga.cli.common import (
    AddParser,
    cluster,
    problems,
    study_options,
    where_options,
    with_progress,
)

if TYPE_CHECKING:
    from perga.studies.window import WindowStudy


def _study(args: argparse.Namespace):
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


def _failed(count: int, path: Path) -> int:
    """Say that ``count`` runs failed (their rows in ``path``); the exit status 1."""
    print(
        f"warning: {count} runs failed: their status and reason are in {path}; --retry-failed "
        "runs them again",
        file=sys.stderr,
    )
    return 1


def sweep(args: argparse.Namespace) -> int:
    """A study's runs and their plots."""
    from perga.studies.study_file import StudyError
    from perga.studies.sweep import sweep as run_sweep
    from perga.studies.sweep_report import write_plots

    try:
        study = _study(args)
    except StudyError as exc:
        return problems(exc.problems)
    start = time.perf_counter()
    result = with_progress(
        args,
        lambda progress: run_sweep(study, args.output, progress=progress, **cluster(args)),
    )
    plots = write_plots(result.rows, list(study.parameters), study.metrics, args.output)
    print(
        f"{len(result.rows)} runs ({result.ran} run now, {result.reused} found finished, "
        f"{result.failed} failed) in {time.perf_counter() - start:.1f} s -> {result.path}, "
        f"{len(plots)} plots"
    )
    return _failed(result.failed, result.path) if result.failed else 0


def window(args: argparse.Namespace) -> int:
    """The operating window's runs, maps and report."""
    from perga.studies.study_file import StudyError
    from perga.studies.window import in_window, run_window, window_study
    from perga.studies.window_report import write_maps, write_report, write_trade_offs

    try:
        study = window_study(
            args.case,
            args.set or [],
            replicates=args.replicates,
            seed=args.seed,
            release_target=args.release_target,
            damage_limit=args.damage_limit,
        )
    except StudyError as exc:
        return problems(exc.problems)
    if args.posterior is not None and args.adaptive is not None:
        return problems(["--posterior and --adaptive: give one of them"])
    if args.posterior is not None:
        return _window_odds(args, study)
    if args.adaptive is not None:
        return _window_adaptive(args, study)
    start = time.perf_counter()
    result = with_progress(
        args,
        lambda progress: run_window(study, args.output, progress=progress, **cluster(args)),
    )
    write_maps(result, args.output)
    write_trade_offs(result, args.output)
    write_report(result, args.output)
    best = result.best.point
    if best is None:
        verdict = "no point gave both a release and a damage fraction"
    else:
        where = f"{study.axes[0]} = {best.x:.6g}, {study.axes[1]} = {best.y:.6g}"
        verdict = (
            f"best {where}" if result.best.inside else f"no setting meets both; nearest {where}"
        )
    inside = sum(in_window(p, study.release_target, study.damage_limit) for p in result.points)
    print(
        f"{len(result.rows)} runs ({result.ran} run now, {result.reused} found finished, "
        f"{result.failed} failed) in {time.perf_counter() - start:.1f} s; {inside} of "
        f"{len(result.points)} points in the window; {verdict} "
        f"-> {args.output}/report.md, window.parquet, window.png, trade-offs.png"
    )
    if result.failed:
        return _failed(result.failed, args.output / "results.parquet")
    return 0


def _window_adaptive(args: argparse.Namespace, study: WindowStudy) -> int:
    """The window's boundary from at most ``--adaptive BUDGET`` runs."""
    from perga.studies.window_adaptive import RUNS, run_adaptive
    from perga.studies.window_adaptive_report import write_adaptive

    xs, ys = study.grid()
    start = time.perf_counter()
    try:
        result = with_progress(
            args,
            lambda progress: run_adaptive(
                study, args.output, budget=args.adaptive, progress=progress, **cluster(args)
            ),
            rows=RUNS,
        )
    except ValueError as exc:
        return problems([f"--adaptive: {exc}"])
    write_adaptive(result, args.output)
    search = result.search
    print(
        f"{search.runs} runs ({result.ran} run now) in {search.rounds} rounds, "
        f"{time.perf_counter() - start:.1f} s, stopped: {search.stopped}; "
        f"{int(search.inside.sum())} of {len(xs) * len(ys)} settings in the window "
        f"-> {args.output}/adaptive.md, adaptive.parquet, adaptive.png"
    )
    return 0


def _window_odds(args: argparse.Namespace, study: WindowStudy) -> int:
    """The window under the calibration's uncertainty (``--posterior``)."""
    from perga.studies.study_file import StudyError
    from perga.studies.window import foundations
    from perga.studies.window_odds import assumed_values, odds_jobs, read_posterior, run_odds
    from perga.studies.window_odds_report import (
        write_odds_map,
        write_odds_report,
        write_odds_table,
    )

    try:
        posterior = read_posterior(args.posterior, args.draws, args.seed)
        odds_jobs(study, posterior, args.replicates, args.output)
    except StudyError as exc:
        return problems(exc.problems)
    start = time.perf_counter()
    result = with_progress(
        args,
        lambda progress: run_odds(
            study, posterior, args.replicates, args.output, progress=progress, **cluster(args)
        ),
    )
    write_odds_table(result, args.output)
    write_odds_map(result, args.output)
    numerics = foundations(study, calibrated=True)
    write_odds_report(result, assumed_values(study, posterior.keys), numerics, args.output)
    best = result.best
    verdict = (
        "no setting has a draw inside the window"
        if best is None
        else f"best {study.axes[0]} = {best.x:.6g}, {study.axes[1]} = {best.y:.6g}: "
        f"P = {best.probability:.2f} ({best.low:.2f}-{best.high:.2f})"
    )
    print(
        f"{len(result.rows)} runs ({result.ran} run now, {result.failed} failed) in "
        f"{time.perf_counter() - start:.1f} s; {verdict} -> {args.output}/report.md, "
        "odds.parquet, odds.png"
    )
    if result.failed:
        return _failed(result.failed, args.output / "results.parquet")
    return 0


def calibrate(args: argparse.Namespace) -> int:
    """The fit, its intervals, best.toml and fit.json."""
    from perga.model.compile import load_system
    from perga.studies.calibrate import calibrate as fit_keys
    from perga.studies.calibrate_report import write_plots
    from perga.studies.study_file import StudyError

    load_system(args.case)  # the case itself first: its problems are a case file's
    start = time.perf_counter()
    try:
        result = fit_keys(
            args.case,
            args.data,
            args.fit,
            args.output,
            method=args.method,
            steps=args.steps,
            runs=args.runs,
            scheduler=args.scheduler,
            workers=args.workers,
            progress=None if args.quiet else lambda line: print(line, file=sys.stderr),
        )
    except StudyError as exc:
        return problems(exc.problems)
    except KeyboardInterrupt:
        print(
            f"interrupted: the runs finished so far are in {args.output}/runs; run the same "
            "command again to resume",
            file=sys.stderr,
        )
        raise
    write_plots(result, args.output)
    fit = result.fit
    for key, value, (lo, hi) in zip(fit.keys, fit.values, fit.intervals, strict=True):
        print(f"{key} = {value:.6g}  (95 %: {lo:.6g} to {hi:.6g})")
    print(
        f"{fit.method}: {fit.runs} runs ({result.ran} run now, {fit.runs - result.ran} found "
        f"finished), residual sum of squares {fit.rss:.4g}, "
        f"{time.perf_counter() - start:.1f} s -> {args.output}/best.toml, fit.json"
    )
    return 0


def metrics(args: argparse.Namespace) -> int:
    """The metrics of a run, or the list of them."""
    from perga.stats import load_run
    from perga.stats.metrics import METRICS, MetricUnavailableError, evaluate

    if args.run is None:
        for m in METRICS.values():
            arg = f":ARG ({m.argument})" if m.argument else ""
            print(f"{m.name}{arg} [{m.unit}]: {m.description}")
            if m.bounds is not None:
                print(f"    in [{m.bounds[0]:.6g}, {m.bounds[1]:.6g}]: {m.convention}")
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


def add_parsers(add: AddParser) -> None:
    """``perga sweep``, ``window``, ``calibrate`` and ``metrics``."""
    parser = add(
        "sweep",
        help="run a case over parameter values on Dask: results.parquet and plots",
        description="Run a study (a study file, or a case with --set KEY=V1,V2 or "
        "KEY=LO:HI:N and --metric NAME) on a local Dask cluster or the one at --scheduler. "
        "Finished runs are found by key and not run again.",
    )
    parser.add_argument("target", type=Path, metavar="STUDY_OR_CASE")
    parser.add_argument("-o", "--output", type=Path, required=True, help="the study's folder")
    parser.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUES",
        help="a case key and its values: V1,V2,... or LO:HI:N (a grid)",
    )
    parser.add_argument("--metric", action="append", metavar="NAME", help="a metric to keep")
    parser.add_argument("--replicates", type=int, default=1, help="runs per point (own seeds)")
    study_options(parser)
    parser.set_defaults(handler=sweep)
    parser = add(
        "window",
        help="operating window over two keys on Dask: release, damage, throughput, energy/kg",
        description="Run a case over a grid of two keys (--set KEY=LO:HI:N twice; other --set "
        "KEY=VALUE are fixed), each point --replicates times with its own solver.seed, and map "
        "the mean and sd of released_fraction, damaged_fraction, throughput and energy_per_kg: "
        "window.parquet/.csv, window.png and report.md with the best setting inside "
        "released_fraction >= --release-target and damaged_fraction <= --damage-limit.",
    )
    parser.add_argument("case", type=Path, metavar="CASE")
    parser.add_argument("-o", "--output", type=Path, required=True, help="the study's folder")
    parser.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUES",
        help="an axis KEY=LO:HI:N (exactly two), or a fixed KEY=VALUE",
    )
    parser.add_argument(
        "--replicates",
        type=int,
        default=2,
        help="runs per point (default 2); with --posterior, seeds per parameter set",
    )
    parser.add_argument(
        "--posterior",
        type=Path,
        metavar="CALIBRATION",
        help="a perga calibrate output: map the probability that each setting is inside the "
        "window over parameter sets drawn from its posterior (odds.png, report.md)",
    )
    parser.add_argument(
        "--draws", type=int, default=8, help="with --posterior: parameter sets, in [2, 10000]"
    )
    parser.add_argument(
        "--adaptive",
        type=int,
        metavar="BUDGET",
        help="find the window's boundary on the grid from at most BUDGET runs: a coarse grid, "
        "then runs where Gaussian-process predictions leave a setting's class unsure "
        "(adaptive.png, adaptive.md)",
    )
    parser.add_argument(
        "--release-target", type=float, default=0.9, help="least released fraction, in [0, 1]"
    )
    parser.add_argument(
        "--damage-limit", type=float, default=0.05, help="most damaged fraction, in [0, 1]"
    )
    study_options(parser)
    parser.set_defaults(handler=window)
    parser = add(
        "calibrate",
        help="fit case keys to measured data (least squares or Bayesian) on Dask",
        description="Each data row is simulated with its condition columns and the fitted "
        "keys; writes best.toml, fit.json and plots.",
    )
    parser.add_argument("case", type=Path, metavar="CASE")
    parser.add_argument("--data", type=Path, required=True, help="CSV: conditions, metrics")
    parser.add_argument(
        "--fit",
        action="append",
        required=True,
        metavar="KEY=LO:HI",
        help="a case key to fit and its bounds",
    )
    parser.add_argument(
        "--method",
        choices=("least-squares", "bayes", "surrogate", "two-fidelity"),
        default="least-squares",
        help="least-squares (default); bayes: emcee over runs; surrogate: the posterior on "
        "Gaussian-process surrogates; two-fidelity: on the analytical model corrected by a GP",
    )
    parser.add_argument("--steps", type=int, default=100, help="bayes: emcee steps")
    parser.add_argument(
        "--runs", type=int, default=100, help="surrogate, two-fidelity: most runs (default 100)"
    )
    parser.add_argument("-o", "--output", type=Path, required=True, help="output folder")
    where_options(parser)
    parser.add_argument(
        "--quiet", action="store_true", help="no progress lines (runs so far, best vector)"
    )
    parser.set_defaults(handler=calibrate)
    parser = add("metrics", help="the metrics of a run (or, without RUN, the list)")
    parser.add_argument("run", type=Path, nargs="?", metavar="RUN")
    parser.add_argument("names", nargs="*", metavar="NAME")
    parser.set_defaults(handler=metrics)
