"""``perga window --posterior CALIBRATION``: the operating window under a calibration's
uncertainty.

At every setting of the window's grid the same ``draws`` parameter sets θ_d, drawn from the
calibration's posterior sample (``posterior.parquet``, :mod:`perga.studies.calibrate`), each
run with ``seeds`` seeds of its own (replicate d·S + s, :func:`perga.studies.jobs.derived_seed`:
no two runs of a setting share a seed, so the draws' seed noise is independent and the variance
splits, :mod:`perga.studies.window_posterior`). The runs are study runs (keyed, resumable) in
``DIR/runs``; a row per run in ``DIR/results.parquet``. Per setting the probability that it is
inside the window and each metric's variance split into its parameter and its seed part.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq

from perga.case.load import overridden, read_case_data
from perga.case.overrides import apply_overrides
from perga.studies.calibrate import POSTERIOR
from perga.studies.design import points
from perga.studies.executor import BatchCluster, Progress, run_missing
from perga.studies.jobs import Job, derived_seed, make_job, run_job
from perga.studies.study_file import StudyError
from perga.studies.sweep import RESULTS, write_table
from perga.studies.window import METRICS, WindowStudy, fixed_overrides
from perga.studies.window_posterior import SettingOdds, best_setting, setting_odds


@dataclass(frozen=True)
class Posterior:
    """Parameter sets drawn from a calibration's posterior: the fitted case keys, the draws
    (draws × keys, SI) and the file they came from."""

    keys: list[str]
    draws: np.ndarray
    source: Path


def read_posterior(calibration: Path, draws: int, seed: int) -> Posterior:
    """``draws`` rows of ``CALIBRATION/posterior.parquet`` (a directory of ``perga
    calibrate``, or the file itself), chosen at random (``seed``) without replacement where
    the sample is large enough; StudyError naming the file if it cannot be read."""
    path = calibration / POSTERIOR if calibration.is_dir() else calibration
    try:
        table = pq.read_table(path).to_pydict()
    except (OSError, ValueError) as exc:
        raise StudyError(
            [f"--posterior {calibration}: no posterior sample readable at {path} ({exc}); "
             "give a perga calibrate output directory"]
        ) from None  # fmt: skip
    keys = list(table)
    sample = np.column_stack([np.asarray(table[k], dtype=float) for k in keys]) if keys else None
    if sample is None or sample.shape[0] == 0 or not np.isfinite(sample).all():
        raise StudyError([f"--posterior {path}: the sample is empty or holds non-finite values"])
    if not 2 <= draws <= 10_000:
        raise StudyError([f"--draws: parameter sets per setting, in [2, 10000] (got {draws})"])
    rng = np.random.default_rng(seed)
    rows = rng.choice(sample.shape[0], draws, replace=sample.shape[0] < draws)
    return Posterior(keys, sample[rows], path)


def odds_jobs(window: WindowStudy, posterior: Posterior, seeds: int, root: Path) -> list[Job]:
    """Every run: each setting × draw × seed (module doc); StudyError if a posterior key is
    one of the window's axes."""
    clash = sorted(set(posterior.keys) & set(window.axes))
    if clash:
        raise StudyError(
            [f"--posterior: {', '.join(clash)} is an axis of the window and a fitted key"]
        )
    if not 2 <= seeds <= 1000:
        raise StudyError([f"--replicates: seeds per parameter set, in [2, 1000] (got {seeds})"])
    study = window.study
    metrics = tuple(study.metrics)
    jobs = []
    for point in points(study):
        for d, theta in enumerate(posterior.draws):
            drawn = {k: float(v) for k, v in zip(posterior.keys, theta, strict=True)}
            for s in range(seeds):
                replicate = d * seeds + s
                jobs.append(
                    make_job(
                        study.case,
                        {**point, **drawn},
                        replicate,
                        derived_seed(study.seed, replicate),
                        metrics,
                        root,
                    )
                )
    return jobs


@dataclass(frozen=True)
class OddsResult:
    """A finished study under uncertainty: per setting (x fastest) its odds, the best setting
    (None if no setting has a chance), the posterior, and the runs' rows and counts."""

    window: WindowStudy
    odds: list[SettingOdds]
    best: SettingOdds | None
    posterior: Posterior
    seeds: int
    rows: list[dict[str, Any]]
    ran: int
    failed: int


def run_odds(
    window: WindowStudy,
    posterior: Posterior,
    seeds: int,
    directory: Path,
    *,
    scheduler: str | BatchCluster | None = None,
    workers: int | None = None,
    retry_failed: bool = False,
    progress: Progress | None = None,
    function: Callable[[Job], dict[str, Any]] = run_job,
) -> OddsResult:
    """Run what is missing of the study into ``directory`` (each job by ``function``, a run)
    and reduce it (module doc)."""
    directory.mkdir(parents=True, exist_ok=True)
    jobs = odds_jobs(window, posterior, seeds, directory)
    rows: dict[str, dict[str, Any]] = {}
    try:
        ran = run_missing(
            jobs,
            lambda row: rows.__setitem__(row["key"], row),
            scheduler=scheduler,
            workers=workers,
            retry_failed=retry_failed,
            progress=progress,
            function=function,
        )
    finally:
        write_table([rows[j.key] for j in jobs if j.key in rows], directory / RESULTS)
    xs, ys = window.grid()
    draws = len(posterior.draws)
    odds = []
    for y in ys:
        for x in xs:
            values = {m: np.full((draws, seeds), math.nan) for m in METRICS}
            for job in jobs:
                if job.parameters[window.axes[0]] != x or job.parameters[window.axes[1]] != y:
                    continue
                row = rows.get(job.key, {})
                if row.get("status") != "ok":
                    continue
                d, s = divmod(job.replicate, seeds)
                for m in METRICS:
                    value = row.get(m)
                    values[m][d, s] = math.nan if value is None else float(value)
            odds.append(setting_odds(values, window.release_target, window.damage_limit, x=x, y=y))
    failed = sum(rows.get(j.key, {}).get("status") != "ok" for j in jobs)
    return OddsResult(
        window, odds, best_setting(odds), posterior, seeds,
        [rows[j.key] for j in jobs if j.key in rows], ran, failed,
    )  # fmt: skip


ASSUMED_TABLES = ("materials", "contacts", "contact_model")
"""The case's tables whose values a map takes as known unless fitted."""
FITTED = "<fitted>"


def assumed_values(window: WindowStudy, fitted: list[str]) -> list[str]:
    """Every value of the case's materials, contacts and contact model (with the study's
    fixed overrides) that is not ``fitted``, as ``KEY = VALUE``: what the map assumes."""
    case = window.study.case
    data = overridden(read_case_data(case), fixed_overrides(window), case)
    marked = apply_overrides(data, [(k, FITTED) for k in fitted])
    out: list[str] = []

    def walk(prefix: str, value: Any) -> None:
        if isinstance(value, dict):
            for k, v in value.items():
                walk(f"{prefix}.{k}", v)
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for v in value:
                label = "-".join(map(str, v.get("pair", [])))
                walk(f"{prefix}.{label}", {k: x for k, x in v.items() if k != "pair"})
        elif value != FITTED:
            out.append(f"{prefix} = {value}")

    for table in ASSUMED_TABLES:
        if table in marked:
            walk(table, marked[table])
    return out
