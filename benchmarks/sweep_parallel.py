"""A sweep of 16 rigid single-impact runs on 2 Dask workers against the same 16 runs one after
another in this process (issue 12: the sweep must take at most 0.6× as long).

The runs are rebound shots (cases/rebound-test.toml) at 16 angles with solver.dt = 2e-7 s
(15,000 steps, about 2 s each here), so that a run costs what a small study's run costs; the
sweep's time includes starting the local cluster. Both are measured ``--repeats`` times,
interleaved (sequential, sweep, sequential, ...), each sweep into a fresh folder (nothing is
found finished); medians and the machine's load are printed.

    python benchmarks/sweep_parallel.py [--repeats 3] [--dt 2e-7]
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

from perga.studies.jobs import run_job
from perga.studies.study_file import Parameter, Study
from perga.studies.sweep import jobs_of, sweep

CASE = Path(__file__).resolve().parents[1] / "cases" / "rebound-test.toml"


def study(dt: float) -> Study:
    angles = [round(0.1 + 1.3 * k / 15, 6) for k in range(16)]
    return Study(
        case=CASE,
        parameters={
            "granules.placement.angle": Parameter(values=angles),
            "solver.dt": Parameter(values=[dt]),
        },
        metrics=["first_impact_restitution", "first_impact_tangential_restitution_contact"],
    )


def sequential(s: Study) -> float:
    with tempfile.TemporaryDirectory() as work:
        start = time.perf_counter()
        for job in jobs_of(s, Path(work)):
            assert run_job(job)["status"] == "ok"
        return time.perf_counter() - start


def parallel(s: Study, workers: int) -> float:
    with tempfile.TemporaryDirectory() as work:
        start = time.perf_counter()
        result = sweep(s, Path(work), workers=workers)
        assert result.ran == 16 and result.failed == 0
        return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--dt", type=float, default=2e-7)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    s = study(args.dt)
    sequential(study(1e-5))  # imports and numba's cache, untimed
    load0 = os.getloadavg()[0]
    seq, par = [], []
    for _ in range(args.repeats):
        seq.append(sequential(s))
        par.append(parallel(s, args.workers))
        print(f"sequential {seq[-1]:.1f} s, sweep on {args.workers} workers {par[-1]:.1f} s")
    ratio = statistics.median(par) / statistics.median(seq)
    print(
        f"median: sequential {statistics.median(seq):.1f} s, sweep {statistics.median(par):.1f} s,"
        f" ratio {ratio:.2f} (target <= 0.6); load {load0:.2f} -> {os.getloadavg()[0]:.2f}"
    )


if __name__ == "__main__":
    main()
