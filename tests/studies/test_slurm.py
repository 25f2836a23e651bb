"""Studies on a real SLURM (.ci/slurm-up makes a one-node cluster on this machine): a sweep and a
calibration whose workers are SLURM jobs that leave at a short lifetime mid-study and are
replaced; nothing finished is lost or run twice and the results are a local run's."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import threading
from collections.abc import Iterator
from pathlib import Path

import pandas as pd
import pytest

pytest.importorskip("dask_jobqueue")

ROOT = Path(__file__).resolve().parents[2]

CASE = ROOT / "cases" / "rebound-test.toml"
DATA = ROOT / "examples" / "calibration" / "measured.csv"
CLUSTER = """\
system = "slurm"
jobs = 2
cores = 1
memory = "1GB"
walltime = "00:01:00"
lifetime = "4s"
lifetime_stagger = "1s"
log_directory = "logs"
"""
"""Two one-core jobs at a time whose workers leave 3-5 s after they start: a run takes 0.2-2 s,
so most leave in the middle of one, and two workers can do at most 10 s of the study before
jobs must replace them."""


def slurm_idle() -> str | None:
    """Why the study cannot go to SLURM here, or None when a node is idle."""
    if shutil.which("sinfo") is None:
        return "SLURM is not installed (sinfo absent; .ci/slurm-up installs and starts it)"
    states = subprocess.run(
        ["sinfo", "--noheader", "--format=%T"], capture_output=True, text=True, check=False
    )
    if "idle" not in states.stdout.split():
        return f"no idle SLURM node (sinfo: {(states.stdout + states.stderr).strip()[:200]})"
    return None


@pytest.fixture(scope="module")
def slurm() -> None:
    """A SLURM with an idle node: skip saying why where there is none, fail under CI=true."""
    reason = slurm_idle()
    if reason is None:
        return
    if os.environ.get("CI") == "true":
        pytest.fail(f"{reason} and CI=true")
    pytest.skip(reason)


class RowWatch:
    """Every run's row.json under ``root``/runs, polled while a study runs: a row written
    again after it first appeared is a finished run run twice."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.seen: dict[Path, tuple[int, int]] = {}
        self.rewritten: set[Path] = set()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._poll, daemon=True)

    def _poll(self) -> None:
        while not self._stop.wait(0.05):
            for path in self.root.glob("runs/*/row.json"):
                try:
                    stat = path.stat()
                except FileNotFoundError:  # replaced this instant: seen at the next poll
                    continue
                mark = (stat.st_ino, stat.st_mtime_ns)
                if self.seen.setdefault(path, mark) != mark:
                    self.rewritten.add(path)

    def __enter__(self) -> RowWatch:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()


def perga(*args: str | Path, cwd: Path) -> str:
    """``perga ARGS`` in ``cwd``: its output, asserting exit 0."""
    done = subprocess.run(
        ["perga", *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=900
    )
    assert done.returncode == 0, done.stdout + done.stderr[-3000:]
    return done.stdout


@pytest.fixture
def cluster_file(tmp_path: Path) -> Iterator[Path]:
    """The cluster file; after the test, no job of its study is left in the queue."""
    path = tmp_path / "cluster.toml"
    path.write_text(CLUSTER)
    yield path
    left = [j for j in job_ids(tmp_path / "logs") if j in queued()]
    assert not left, f"jobs left in the queue: {left}"


def job_ids(logs: Path) -> set[str]:
    """The SLURM jobs that ran workers: one error log each (dask-worker-JOBID.err)."""
    return {m.group(1) for p in logs.glob("*.err") if (m := re.search(r"-(\d+)\.err$", p.name))}


def queued() -> set[str]:
    """The jobs SLURM has queued or running."""
    out = subprocess.run(["squeue", "--noheader", "--format=%i"], capture_output=True, text=True)
    return set(out.stdout.split())


def lifetimes_reached(logs: Path) -> int:
    """Workers that left at their lifetime, from their logs."""
    left = re.compile(r"Closing worker gracefully: .* Reason: worker-lifetime-reached")
    return sum(len(left.findall(p.read_text())) for p in logs.glob("*.err"))


def on_slurm(study: list[str | Path], tmp_path: Path, cluster_file: Path) -> tuple[Path, int]:
    """``perga STUDY --cluster cluster_file -o slurm``, rows watched: the study's folder and
    the number of runs finished twice; asserts workers left at their lifetime mid-study and
    new jobs replaced them."""
    before = job_ids(tmp_path / "logs")
    out = tmp_path / "slurm"
    with RowWatch(out) as watch:
        perga(*study, "--cluster", cluster_file, "-o", out, "--quiet", cwd=tmp_path)
    jobs = job_ids(tmp_path / "logs") - before
    left = lifetimes_reached(tmp_path / "logs")
    print(f"{len(jobs)} SLURM jobs, {left} workers left at their lifetime")
    assert left >= 1, "no worker reached its lifetime: the study was too short to show it"
    assert len(jobs) > 2, f"no job replaced a worker that left: jobs {sorted(jobs)}"
    return out, len(watch.rewritten)


@pytest.mark.slow
def test_a_sweep_on_slurm_loses_and_repeats_nothing(slurm, tmp_path, cluster_file):
    """120 runs on jobs whose workers leave mid-study: every run's row once, equal to a local
    sweep's. At about 0.2 s a run the study is about 24 s of work, more than the first two
    workers can do, so jobs must replace them."""
    study = [
        "sweep", CASE, "--set", "granules.placement.angle=0.2:1.4:120",
        "--metric", "first_impact_tangential_restitution_centre",
    ]  # fmt: skip
    out, twice = on_slurm(study, tmp_path, cluster_file)
    perga(*study, "--workers", "2", "-o", tmp_path / "local", "--quiet", cwd=tmp_path)
    kept = ["key", "granules.placement.angle", "first_impact_tangential_restitution_centre"]
    slurm, local = (
        pd.read_parquet(d / "results.parquet").sort_values("key").reset_index(drop=True)
        for d in (out, tmp_path / "local")
    )
    assert twice == 0, f"{twice} finished runs ran again"
    assert len(slurm) == 120 and (slurm["status"] == "ok").all(), slurm[["key", "status"]]
    assert len(list(out.glob("runs/*/row.json"))) == 120
    pd.testing.assert_frame_equal(slurm[kept], local[kept])


@pytest.mark.slow
def test_a_calibration_on_slurm_fits_as_a_local_one(slurm, tmp_path, cluster_file):
    """A least-squares fit to seven data rows on jobs whose workers leave mid-study: no run
    finished twice, the fit of a local calibration."""
    study = [
        "calibrate", CASE, "--data", DATA,
        "--fit", "contacts.granule-hammer.restitution=0.4:0.95",
    ]  # fmt: skip
    out, twice = on_slurm(study, tmp_path, cluster_file)
    perga(*study, "--workers", "2", "-o", tmp_path / "local", "--quiet", cwd=tmp_path)
    slurm, local = (json.loads((d / "fit.json").read_text()) for d in (out, tmp_path / "local"))
    assert twice == 0, f"{twice} finished runs ran again"
    assert slurm["values"] == local["values"] and slurm["rss"] == local["rss"]
    assert (out / "best.toml").read_text() == (tmp_path / "local" / "best.toml").read_text()


@pytest.mark.parametrize(
    ("line", "says"),
    [
        ('system = "sge"', "system: Input should be 'slurm' or 'pbs'"),
        ("jobs = 0", "jobs: Input should be greater than or equal to 1"),
        ("processes = 2", "processes: 1 to cores (1) (got 2)"),
        ('memory = "lots"', "memory: a size above 0 such as '4GB'"),
        ('walltime = "1h"', "walltime: HH:MM:SS, above 00:00:00"),
        (
            'lifetime = "59s"',
            "lifetime ± lifetime_stagger: 0 <= stagger < lifetime and lifetime + stagger below "
            "the walltime (60 s) (got 59 s ± 1 s)",
        ),
        ('lifetme = "5m"', "lifetme: unknown key; did you mean 'lifetime'?"),
    ],
)
def test_a_bad_cluster_file_is_refused_before_anything_is_submitted(tmp_path, line, says):
    """Each bad key of a cluster file: one error line naming the file, the key and what it
    allows, exit 2."""
    key = line.split(" = ")[0]
    kept = [k for k in CLUSTER.splitlines() if not k.startswith(f"{key} =")]
    path = tmp_path / "cluster.toml"
    path.write_text("\n".join([*kept, line]) + "\n")
    done = subprocess.run(
        ["perga", "sweep", CASE, "--set", "solver.seed=1", "--metric", "first_impact_restitution",
         "--cluster", path, "-o", tmp_path / "out"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    error = done.stderr.splitlines()[-1]
    assert done.returncode == 2 and f"{path}: {says}" in error, done.stderr
    assert not (tmp_path / "out").exists()
