"""``perga sweep``: run a study's points on Dask and collect one row per run.

``DIR/results.parquet`` holds a row per run: the run's key, the parameters (one column per case
key), the replicate and its seed, the metrics (nan where a run cannot give one; the reason in
``notes``), ``status`` ("ok", "failed", "interrupted"), ``reason``, ``wall_time`` (s) and the
run's directory (``DIR/runs/KEY``); ``DIR/results.csv`` the same for a spreadsheet, a metric's
and the wall time's unit in its header (``throughput [kg/s]``). Both are rewritten atomically as
rows arrive, so an interrupted study leaves readable tables. Running a study again runs only
what is missing: finished runs are found by key (:mod:`perga.studies.jobs`); failed ones run
again only with ``retry_failed``.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq
from distributed import Client

from perga.stats.metrics import METRICS
from perga.studies.design import points
from perga.studies.executor import BatchCluster, Progress, run_missing
from perga.studies.jobs import Job, derived_seed, make_job
from perga.studies.study_file import Study
from perga.studies.user_units import si_label

RESULTS = "results.parquet"


def jobs_of(study: Study, directory: Path) -> list[Job]:
    """Every run of ``study``: its points × replicates, each with its seed and key."""
    metrics = tuple(study.metrics)
    seeds = [derived_seed(study.seed, r) for r in range(study.replicates)]
    jobs = [
        make_job(study.case, point, r, seeds[r], metrics, directory)
        for point in points(study)
        for r in range(study.replicates)
    ]
    unique: dict[str, Job] = {}
    for job in jobs:
        unique.setdefault(job.key, job)
    return list(unique.values())


def write_table(rows: list[dict[str, Any]], path: Path) -> None:
    """``rows`` as a Parquet table at ``path`` and a CSV beside it (the same name, ``.csv``; a
    metric's unit in its header, :func:`unit_header`), each written to a temporary file then
    renamed."""
    columns: dict[str, list[Any]] = {}
    for row in rows:
        for name in row:
            columns.setdefault(name, [])
    table = pa.table({name: [row.get(name) for row in rows] for name in columns})
    temporary = path.with_name(path.name + ".tmp")
    pq.write_table(table, temporary)
    os.replace(temporary, path)
    spreadsheet = path.with_suffix(".csv")
    temporary = spreadsheet.with_name(spreadsheet.name + ".tmp")
    pacsv.write_csv(table.rename_columns([unit_header(n) for n in table.column_names]), temporary)
    os.replace(temporary, spreadsheet)


def unit_header(column: str) -> str:
    """A results column's CSV header: a metric's name with its unit (``throughput [kg/s]``,
    ``released_fraction [-]``), ``wall_time [s]``; any other column as it is."""
    if column == "wall_time":
        return "wall_time [s]"
    return si_label(column) if column.split(":", 1)[0] in METRICS else column


def read_table(path: Path) -> dict[str, list[Any]]:
    """A results table as {column: values}."""
    return pq.read_table(path).to_pydict()


@dataclass(frozen=True)
class SweepResult:
    """What a sweep did: the table's path, its rows, and the runs it ran now, found finished
    and that failed."""

    path: Path
    rows: list[dict[str, Any]]
    ran: int
    reused: int
    failed: int


def sweep(
    study: Study,
    directory: Path,
    *,
    client: Client | None = None,
    scheduler: str | BatchCluster | None = None,
    workers: int | None = None,
    retry_failed: bool = False,
    progress: Progress | None = None,
) -> SweepResult:
    """Run what ``study`` still lacks into ``directory`` (module doc) and return the table.
    The runs execute on ``client``, on the cluster at ``scheduler``, or on a local cluster
    of ``workers`` processes (:mod:`perga.studies.executor`)."""
    directory.mkdir(parents=True, exist_ok=True)
    jobs = jobs_of(study, directory)
    rows: dict[str, dict[str, Any]] = {}
    path = directory / RESULTS
    order = [j.key for j in jobs]

    def table() -> list[dict[str, Any]]:
        return [rows[k] for k in order if k in rows]

    last_write = 0.0

    def on_row(row: dict[str, Any]) -> None:
        nonlocal last_write
        rows[row["key"]] = row
        if time.monotonic() - last_write > 2.0:
            write_table(table(), path)
            last_write = time.monotonic()

    try:
        ran = run_missing(
            jobs,
            on_row,
            client=client,
            scheduler=scheduler,
            workers=workers,
            retry_failed=retry_failed,
            progress=progress,
        )
    finally:
        write_table(table(), path)
    done = table()
    failed = sum(r["status"] != "ok" for r in done)
    return SweepResult(path, done, ran, len(jobs) - ran, failed)
