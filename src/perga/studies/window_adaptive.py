"""``perga window --adaptive``: the window's boundary on its dense grid from few runs
(:func:`perga.studies.adaptive.adaptive_window`), every run a study run on Dask.

The k-th run asked of a setting is replicate k with the dense study's seed for it
(:func:`perga.studies.jobs.derived_seed`), so an adaptive study and a dense one in the same
folder share their runs (found by key, :mod:`perga.studies.jobs`): the adaptive one costs
nothing there, and it can be checked against the dense map cell by cell.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from perga.studies.adaptive import AdaptiveResult, adaptive_window
from perga.studies.design import points
from perga.studies.executor import BatchCluster, Progress, dask_client, run_missing
from perga.studies.jobs import Job, derived_seed, make_job, run_job
from perga.studies.sweep import write_table
from perga.studies.window import WindowStudy

RUNS = "adaptive-runs.parquet"
"""The adaptive search's rows (a dense study in the same folder keeps its results.parquet)."""

COARSE_REPLICATES = 2
"""Runs per setting of the first, coarse grid: two, so that the Gaussian processes see the
seeds' scatter from the start (from one run per setting they fit it as signal, sure of a class
the seeds do not settle)."""


@dataclass(frozen=True)
class AdaptiveWindow:
    """A finished adaptive study: the search's result, the rows of its runs and how many ran
    now (the others were found finished)."""

    window: WindowStudy
    search: AdaptiveResult
    rows: list[dict[str, Any]]
    ran: int


def run_adaptive(
    window: WindowStudy,
    directory: Path,
    *,
    budget: int,
    tolerance: float = 0.1,
    scheduler: str | BatchCluster | None = None,
    workers: int | None = None,
    retry_failed: bool = False,
    progress: Progress | None = None,
    function: Callable[[Job], dict[str, Any]] = run_job,
) -> AdaptiveWindow:
    """The adaptive search over ``window``'s grid (module doc) with at most ``budget`` runs
    (each by ``function``, a run; failed ones found again run again only with
    ``retry_failed``), its rows in ``DIR/adaptive-runs.parquet``."""
    directory.mkdir(parents=True, exist_ok=True)
    study = window.study
    fixed = next(iter(points(study)))
    asked: dict[tuple[float, float], int] = {}
    rows: list[dict[str, Any]] = []
    ran = 0
    with dask_client(None, scheduler, workers) as client:

        def evaluate(settings: list[tuple[float, float]]) -> list[dict[str, float]]:
            nonlocal ran
            jobs = []
            for x, y in settings:
                k = asked.get((x, y), 0)
                asked[(x, y)] = k + 1
                parameters = {**fixed, window.axes[0]: x, window.axes[1]: y}
                jobs.append(make_job(study.case, parameters, k, derived_seed(study.seed, k),
                                     tuple(study.metrics), directory))  # fmt: skip
            got: dict[str, dict[str, Any]] = {}
            ran += run_missing(jobs, lambda r: got.__setitem__(r["key"], r), client=client,
                               retry_failed=retry_failed, function=function)  # fmt: skip
            batch = [got[j.key] for j in jobs]
            rows.extend(batch)
            write_table(rows, directory / RUNS)
            if progress:
                progress(len(rows), budget)
            return [_metrics(r) for r in batch]

        xs, ys = window.grid()
        search = adaptive_window(
            xs, ys, evaluate, release_target=window.release_target,
            damage_limit=window.damage_limit, budget=budget, tolerance=tolerance,
            replicates=COARSE_REPLICATES,
        )  # fmt: skip
    return AdaptiveWindow(window, search, rows, ran)


def _metrics(row: dict[str, Any]) -> dict[str, float]:
    """A row's release and damage fractions (nan unless the run is ok)."""
    ok = row.get("status") == "ok"
    out = {}
    for name in ("released_fraction", "damaged_fraction"):
        value = row.get(name)
        out[name] = float(value) if ok and value is not None else float("nan")
    return out
