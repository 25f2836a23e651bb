"""What the resume tests of ``perga calibrate`` and ``perga window`` share: a stand-in for a run
(closed-form metrics, a row on disk as a run leaves it, each start and end logged with its
process), the command run with it in a subprocess and stopped by a signal once some runs have
finished, then run again, and the checks of the two parts against an uninterrupted study.

Only the simulation is replaced: the command line, the study, the Dask cluster of worker
processes and the finding of finished runs are perga's own.
"""

from __future__ import annotations

import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest

from perga.studies.jobs import ROW, Job

ROOT = Path(__file__).resolve().parents[2]
LOG = "executed.log"
"""The stand-in's log in the study folder: a line "start|end KEY PID" per event."""
DELAY = 0.1
"""Seconds a stand-in run takes: the study lasts long enough for a signal to land midway (at
0.02 s, the 6 runs left of the adaptive search's first round of 12 on two workers took 0.06 s,
and all of them could finish before a SIGINT sent at the sixth row stopped the study)."""


def _tangential(p: dict[str, Any], _rng: np.random.Generator) -> float:
    """β of a disc's rebound: sliding where tan θ > 3f(1 + e), else rolling (0)."""
    e, f = p["contacts.granule-hammer.restitution"], p["contacts.granule-hammer.friction"]
    return min(3 * f * (1 + e) / math.tan(p["granules.placement.angle"]) - 1, 0.0)


def _released(p: dict[str, Any], rng: np.random.Generator) -> float:
    """Rises with speed, falls with the bond's energy; the seed's noise."""
    energy = p.get("materials.beebread.detachment_energy", 0.06)
    noise = 0.02 * rng.normal()
    return 0.5 + 0.4 * (p["rotor.rpm"] - 1000.0) / 500.0 - 4.0 * (energy - 0.06) + noise


def _damaged(p: dict[str, Any], rng: np.random.Generator) -> float:
    """Rises with the hammer's mass; the seed's noise."""
    return 0.03 * p["hammers.mass"] / 0.05 + 0.02 * rng.normal()


MODELS: dict[str, Callable[[dict[str, Any], np.random.Generator], float]] = {
    "first_impact_restitution": lambda p, _: p["contacts.granule-hammer.restitution"],
    "first_impact_tangential_restitution_contact": _tangential,
    "released_fraction": _released,
    "damaged_fraction": _damaged,
    "throughput": lambda p, _: 1e-3 * p["rotor.rpm"] / 1000.0,
    "energy_per_kg": lambda p, _: 1e3 * p["hammers.mass"] / 0.05,
    "ledger_closure": lambda p, _: 0.0,
}
"""The stand-in's metrics of a run's parameters (SI), each drawing its noise from the run's
seeded generator."""


def _log(study: Path, event: str, key: str) -> None:
    with (study / LOG).open("a", encoding="utf-8") as stream:
        stream.write(f"{event} {key} {os.getpid()}\n")


def stand_in(job: Job) -> dict[str, Any]:
    """A run of ``job`` by :data:`MODELS` (seeded by the job's seed): its row, written to its
    directory as :func:`perga.studies.jobs.run_job` writes it (whole or not at all)."""
    directory = Path(job.directory)
    study = directory.parents[1]
    _log(study, "start", job.key)
    time.sleep(DELAY)
    rng = np.random.default_rng(job.seed)
    row = {"key": job.key, **job.parameters, "replicate": job.replicate, "seed": job.seed,
           **{m: float(MODELS[m](job.parameters, rng)) for m in job.metrics}, "status": "ok",
           "reason": "", "notes": "", "wall_time": DELAY, "directory": job.directory}  # fmt: skip
    directory.mkdir(parents=True, exist_ok=True)
    temporary = directory / (ROW + ".tmp")
    temporary.write_text(json.dumps(row), encoding="utf-8")
    os.replace(temporary, directory / ROW)
    _log(study, "end", job.key)
    return row


def run_defaults() -> list[dict[str, Any]]:
    """The keyword defaults of the study functions whose run ``function`` is a real run
    (:func:`perga.studies.jobs.run_job`) unless given: set ``function`` in each to
    :func:`stand_in` and the commands run with it."""
    from perga.studies.calibrate import calibrate
    from perga.studies.executor import run_missing
    from perga.studies.window_adaptive import run_adaptive
    from perga.studies.window_odds import run_odds

    return [f.__kwdefaults__ for f in (calibrate, run_missing, run_adaptive, run_odds)]


@pytest.fixture
def uninterrupted(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[[Sequence[str]], None]]:
    """``perga ARGS`` in this process with the stand-in, to its end, on a cluster of threads."""
    from distributed import LocalCluster

    from perga.cli import main

    for defaults in run_defaults():
        monkeypatch.setitem(defaults, "function", stand_in)
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                      dashboard_address=None) as cluster:  # fmt: skip

        def run(args: Sequence[str]) -> None:
            assert main([*args, "--scheduler", cluster.scheduler_address, "--quiet"]) == 0

        yield run


def drive() -> None:
    """``python -c "from tests.studies.study_resume import drive; drive()" ARGS``: ``perga
    ARGS`` with the stand-in for every run."""
    from perga.cli import main

    for defaults in run_defaults():
        defaults["function"] = stand_in
    sys.exit(main(sys.argv[1:]))


def rows_on_disk(study: Path) -> dict[str, bytes]:
    """Every finished run's row file in ``study``: {key: its bytes}."""
    return {p.parent.name: p.read_bytes() for p in (study / "runs").glob(f"*/{ROW}")}


def log_lines(study: Path) -> list[tuple[str, str, int]]:
    """The stand-in's log of ``study``: (event, key, pid) per line."""
    path = study / LOG
    if not path.exists():
        return []
    lines = path.read_text(encoding="utf-8").splitlines()
    return [(e, k, int(p)) for e, k, p in (line.split() for line in lines)]


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


@dataclass(frozen=True)
class Resumed:
    """A study stopped by a signal and run again: the first part's exit status and stderr, the
    rows on disk between the parts, the runs the second part started (keys), its stdout and
    the rows on disk at the end."""

    stopped: int
    stopped_err: str
    between: dict[str, bytes]
    second: list[str]
    out: str
    after: dict[str, bytes]


def stop_and_resume(args: Sequence[str], study: Path, signum: int, after: int) -> Resumed:
    """``perga ARGS`` (-o ``study``) with the stand-in, sent ``signum`` once ``after`` runs have
    left their rows; once its worker processes are gone too, run to its end."""
    command = [sys.executable, "-c", "from tests.studies.study_resume import drive; drive()",
               *args, "--workers", "2", "--quiet"]  # fmt: skip
    proc = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)  # fmt: skip
    end = time.monotonic() + 120
    while len(rows_on_disk(study)) < after:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < end, "no runs finished in 120 s"
        time.sleep(0.05)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=60)
    workers = {pid for _, _, pid in log_lines(study)}
    end = time.monotonic() + 30
    while not all(_gone(pid) for pid in workers):  # a killed command's workers end with it
        assert time.monotonic() < end, f"workers {workers} outlived the stopped command"
        time.sleep(0.1)
    between, logged = rows_on_disk(study), len(log_lines(study))
    finished = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert finished.returncode == 0, finished.stderr
    second = [k for e, k, _ in log_lines(study)[logged:] if e == "start"]
    return Resumed(proc.returncode, err, between, second, finished.stdout, rows_on_disk(study))


def check_resumed(resumed: Resumed, signum: int, reference: Path) -> None:
    """The stopped command's exit (130 after SIGINT with the resume hint; killed by SIGKILL);
    some runs but not all finished before the stop; the second part ran none of them again,
    each once, and left their rows as they were; at the end the runs are the uninterrupted
    study's in ``reference``."""
    if signum == signal.SIGINT:
        assert resumed.stopped == 130, resumed.stopped_err
        assert "run the same command again to resume" in resumed.stopped_err
        named = re.search(r"the runs finished so far are in (\S+);", resumed.stopped_err)
        assert named and Path(named.group(1)).exists(), resumed.stopped_err
    else:
        assert resumed.stopped == -signal.SIGKILL
    everything = rows_on_disk(reference)
    assert 0 < len(resumed.between) < len(everything), (len(resumed.between), len(everything))
    assert not set(resumed.second) & set(resumed.between), "a finished run was run again"
    assert len(resumed.second) == len(set(resumed.second)), "a run ran twice in the second part"
    assert {k: resumed.after[k] for k in resumed.between} == resumed.between
    assert set(resumed.after) == set(everything)


def same_table(path: Path, reference: Path, drop: tuple[str, ...] = ()) -> None:
    """The Parquet tables at ``path`` and ``reference`` hold the same values (NaN equal to NaN),
    less the columns ``drop``."""
    a, b = (pq.read_table(p).to_pydict() for p in (path, reference))
    for name in drop:
        a.pop(name, None)
        b.pop(name, None)
    assert list(a) == list(b)
    for name in a:
        assert _same(a[name], b[name]), name


def _same(a: list[Any], b: list[Any]) -> bool:
    def nan(x: Any) -> bool:
        return isinstance(x, float) and math.isnan(x)

    return len(a) == len(b) and all(
        x == y or (nan(x) and nan(y)) for x, y in zip(a, b, strict=True)
    )
