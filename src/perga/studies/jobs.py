"""One run of a study: a case with overrides, run into its own directory, reduced to a row of
metrics (:func:`run_job`, which a Dask worker executes), and the key that names it.

A run's key is a hash of its resolved case (the file's data with the overrides applied), the
contents of the geometry files it points to, its seed and the perga version: the same run in
another study, or the same study run again, has the same key and directory, so finished runs
are found and not run again, and an edited case or geometry file makes new runs. A run that fails is
a row with ``status = "failed"`` and the reason; :func:`run_job` never raises for it.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from perga import __version__
from perga.case.files import file_tables
from perga.case.load import overridden, read_case_data

ROW = "row.json"
"""A finished run's row, in its directory."""


def toml_value(value: Any) -> str:
    """``value`` as a TOML value for an override (floats exactly: repr)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(float(value)) if isinstance(value, float) else str(value)
    return json.dumps(str(value))


@dataclass(frozen=True)
class Job:
    """One run: the base case file, the parameter values (case key -> value), the replicate and
    its seed, the metrics to compute, the run directory and the run's key."""

    case: str
    parameters: dict[str, Any]
    replicate: int
    seed: int
    metrics: tuple[str, ...]
    directory: str
    key: str
    extra: tuple[str, ...] = field(default=())
    """Further ``KEY=VALUE`` overrides, applied before the parameters' (values in TOML, e.g.
    ``output.record=["granules"]``)."""

    @property
    def overrides(self) -> tuple[str, ...]:
        """The ``KEY=VALUE`` overrides of this run, the seed's last."""
        own = tuple(f"{k}={toml_value(v)}" for k, v in self.parameters.items())
        return (*self.extra, *own, f"solver.seed={self.seed}")


def pointed_files(data: Any, folder: Path) -> dict[str, str]:
    """SHA-256 of each geometry file the case data names (:func:`perga.case.files.file_tables`:
    its ``path``, relative to ``folder`` or absolute), by the path as written; "unreadable" for
    one that cannot be read (its run then fails and says why)."""
    digests = {}
    for table in file_tables(data):
        try:
            digests[table["path"]] = hashlib.sha256(
                (folder / table["path"]).read_bytes()
            ).hexdigest()
        except OSError:
            digests[table["path"]] = "unreadable"
    return digests


def run_key(case: str | Path, overrides: tuple[str, ...], seed: int) -> str:
    """The key of a run: a hash of the resolved case data, the geometry files it points to
    (:func:`pointed_files`), the seed and perga's version."""
    data = overridden(read_case_data(case), overrides, case)
    files = pointed_files(data, Path(case).resolve().parent)
    text = json.dumps(
        {"case": data, "seed": seed, "perga": __version__} | ({"files": files} if files else {}),
        sort_keys=True,
        default=str,
    )
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def make_job(
    case: str | Path,
    parameters: dict[str, Any],
    replicate: int,
    seed: int,
    metrics: tuple[str, ...],
    root: Path,
    extra: tuple[str, ...] = (),
) -> Job:
    """The job of one run of a study whose runs live under ``root``/runs."""
    probe = Job(str(case), dict(parameters), replicate, seed, metrics, "", "", extra)
    key = run_key(case, probe.overrides, seed)
    return Job(
        str(case), dict(parameters), replicate, seed, metrics, str(root / "runs" / key), key, extra
    )


def finished_row(job: Job) -> dict[str, Any] | None:
    """The row a run of this key left, if it finished (ok or failed), else None."""
    path = Path(job.directory) / ROW
    if not path.exists():
        return None
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError):
        return None  # cut short while written: run it again


def _write_row(directory: Path, row: dict[str, Any]) -> None:
    temporary = directory / (ROW + ".tmp")
    temporary.write_text(json.dumps(row, default=float) + "\n", encoding="utf-8")
    os.replace(temporary, directory / ROW)


def failed_row(job: Job, reason: str) -> dict[str, Any]:
    """The row of a run that did not end with a result: status "failed" and ``reason``."""
    return {
        "key": job.key,
        **job.parameters,
        "replicate": job.replicate,
        "seed": job.seed,
        **{m: math.nan for m in job.metrics},
        "status": "failed",
        "reason": reason,
        "notes": "",
        "wall_time": math.nan,
        "directory": job.directory,
    }


def run_job(job: Job) -> dict[str, Any]:
    """Run ``job`` (on one numba thread) and return its row; the row is also written to the run
    directory (``row.json``) once the run has ended, whatever ended it."""
    import numba

    from perga.model.compile import load_system
    from perga.run import prepare_directory, run_case
    from perga.stats.metrics import MetricUnavailableError, evaluate
    from perga.stats.tables import load_run

    numba.set_num_threads(1)
    start = time.perf_counter()
    directory = Path(job.directory)
    row = failed_row(job, "")
    try:
        case, system = load_system(job.case, overrides=job.overrides)
        prepare_directory(directory, overwrite=True)
        summary = run_case(case, Path(job.case), directory, system=system)
        run = load_run(directory)
        notes = {}
        for name in job.metrics:
            try:
                row[name] = float(evaluate(run, name))
            except MetricUnavailableError as exc:
                notes[name] = str(exc)
        row["notes"] = json.dumps(notes) if notes else ""
        row["status"] = summary.status if summary.status != "completed" else "ok"
        row["reason"] = summary.reason
    except BaseException as exc:  # a failed run is a row; it never stops the study
        row["reason"] = f"{type(exc).__name__}: {exc}"
        if isinstance(exc, KeyboardInterrupt | SystemExit):
            raise
    row["wall_time"] = time.perf_counter() - start
    directory.mkdir(parents=True, exist_ok=True)
    _write_row(directory, row)
    return row


def derived_seed(base: int, replicate: int) -> int:
    """Replicate ``replicate``'s seed: the same for every point of a study (common random
    numbers), independent between replicates (numpy's SeedSequence)."""
    return int(np.random.SeedSequence(base, spawn_key=(replicate,)).generate_state(1)[0] >> 1)
