"""What a posterior costs: the calibration methods side by side on one data set, each from
fresh runs (its own folder), printing the runs, the wall time and the 95 % intervals' widths.

    python benchmarks/calibration_cost.py                        # the worked example
    python benchmarks/calibration_cost.py --methods surrogate two-fidelity
    python benchmarks/calibration_cost.py --case examples/calibration/published/kharaz2001.toml \\
        --data examples/calibration/published/kharaz2001_sliding.csv \\
        --fit contacts.alumina-glass.restitution=0.5:1 \\
        --fit contacts.alumina-glass.friction=0.01:0.5

The worked example (examples/calibration/measured.csv, made at e = 0.72, f = 0.28) by default;
``--steps`` sets emcee's steps (8 walkers each). Times are wall times on ``--workers`` Dask
workers (default 2); the machine's load is printed with them.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from perga.studies.calibrate import METHODS, calibrate

ROOT = Path(__file__).resolve().parents[1]
FITS = ["contacts.granule-hammer.restitution=0.4:0.95", "contacts.granule-hammer.friction=0.05:0.8"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", type=Path, default=ROOT / "cases" / "rebound-test.toml")
    parser.add_argument("--data", type=Path, default=ROOT / "examples/calibration/measured.csv")
    parser.add_argument("--fit", action="append", help="KEY=LO:HI (default: e and f)")
    parser.add_argument("--methods", nargs="+", choices=METHODS, default=list(METHODS))
    parser.add_argument("--steps", type=int, default=40, help="bayes: emcee's steps")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    print(f"{args.data.name}: load {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print(f"{'method':30s} {'runs':>5s} {'wall s':>7s}  key: value (95 % interval, width)")
    for method in args.methods:
        with tempfile.TemporaryDirectory() as work:
            start = time.perf_counter()
            fit = calibrate(
                args.case, args.data, args.fit or FITS, Path(work), method=method,
                steps=args.steps, workers=args.workers,
            ).fit  # fmt: skip
            wall = time.perf_counter() - start
        for i, (key, value, (lo, hi)) in enumerate(
            zip(fit.keys, fit.values, fit.intervals, strict=True)
        ):
            head = f"{fit.method:30s} {fit.runs:5d} {wall:7.1f}" if i == 0 else " " * 44
            print(f"{head}  {key.rsplit('.', 1)[-1]}: {value:.4f} ({lo:.4f} to {hi:.4f}, "
                  f"{hi - lo:.4f})")  # fmt: skip
        print(f"{'':44s}  load {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
