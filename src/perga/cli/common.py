"""What the commands share: printing problems (exit 2) and warnings, argument types, the study
options on Dask, progress bars around studies, the bundled cases."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from perga.progress import counted, progress_bar

if TYPE_CHECKING:
    from perga.case.schema import Case
    from perga.studies.executor import BatchCluster

BUNDLED_CASES = Path(__file__).resolve().parents[3] / "cases"

T = TypeVar("T")

AddParser = Callable[..., argparse.ArgumentParser]
"""A subcommand adder (``add_subparsers().add_parser``): each command group's module adds its
commands with it."""


def default_case(name: str) -> Path:
    """A bundled case: ./cases/NAME if present, else the one beside the installed sources."""
    local = Path("cases") / name
    return local if local.exists() else BUNDLED_CASES / name


def problems(lines: Sequence[str]) -> int:
    """Print each problem of a bad input as an error line; returns the exit status 2."""
    for line in lines:
        print(f"error: {line}", file=sys.stderr)
    return 2


def warn(path: object, case: Case) -> None:
    """Print a warning line for each implausible value of ``case`` (read from ``path``)."""
    from perga.case.plausibility import implausible

    for line in implausible(case):
        print(f"warning: {path}: {line}", file=sys.stderr)


def at_least_one(text: str) -> int:
    """An argparse type: a whole number >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a whole number >= 1 (got {text!r})") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"at least 1 (got {value})")
    return value


def study_options(parser: argparse.ArgumentParser) -> None:
    """The options a study with replicates shares: their seeds, and :func:`cluster_options`."""
    parser.add_argument("--seed", type=int, default=0, help="seed of the replicates' seeds")
    cluster_options(parser)


def cluster_options(parser: argparse.ArgumentParser) -> None:
    """The options of runs on Dask (:func:`cluster`) and their progress."""
    where_options(parser)
    parser.add_argument("--retry-failed", action="store_true", help="run failed runs again")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def where_options(parser: argparse.ArgumentParser) -> None:
    """Where runs on Dask execute: local workers, a running scheduler or a batch cluster."""
    parser.add_argument(
        "--workers", type=at_least_one, help="local worker processes, >= 1 (default: free cores)"
    )
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler")
    where.add_argument(
        "--cluster",
        dest="scheduler",
        type=batch_cluster,
        metavar="FILE.toml",
        help="workers as SLURM or PBS jobs, as the cluster file says (docs/how-to/cluster.md)",
    )


def batch_cluster(text: str) -> BatchCluster:
    """An argparse type: a cluster file read (:func:`perga.studies.executor.read_batch_cluster`),
    with dask-jobqueue installed."""
    from perga.studies.executor import read_batch_cluster

    try:
        import dask_jobqueue  # noqa: F401
    except ImportError:
        raise argparse.ArgumentTypeError(
            "needs dask-jobqueue: pip install 'perga[cluster]'"
        ) from None
    try:
        return read_batch_cluster(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def cluster(args: argparse.Namespace) -> dict[str, Any]:
    """A study's Dask options from the command line: scheduler (an address or a cluster
    file's :class:`~perga.studies.executor.BatchCluster`), workers, retry_failed."""
    return {"scheduler": args.scheduler, "workers": args.workers, "retry_failed": args.retry_failed}


def with_progress(
    args: argparse.Namespace,
    call: Callable[[Callable[[int, int], None]], T],
    rows: str = "results.parquet",
) -> T:
    """``call(progress)`` under a progress bar (unless ``args.quiet``); after a stop signal it
    says where the finished runs are (``rows`` in the study's folder) and how to resume, and
    re-raises."""
    bar = progress_bar(0, "runs", f"perga {args.command}", args.quiet)
    try:
        return call(counted(bar))
    except KeyboardInterrupt:
        bar.close()
        print(
            f"interrupted: the runs finished so far are in {args.output}/{rows}; "
            "run the same command again to resume",
            file=sys.stderr,
        )
        raise
    finally:
        bar.close()
