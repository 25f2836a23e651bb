"""Make the synthetic rebound-test data of examples/calibration/measured.csv.

Stated true values: restitution e = 0.72 and friction f = 0.28 between bee bread and steel.
The granule of cases/rebound-test.toml is fired at 5 m/s at seven angles of incidence,
0.2-1.4 rad; each shot's normal restitution and tangential restitution come from a perga run at
the true values (perga.stats.metrics), plus Gaussian noise of the stated standard deviations
(0.01 and 0.02), seeded: the same file every time.

    python examples/calibration/make_data.py [-o measured.csv] [--workers N]
"""

from __future__ import annotations

import argparse
import csv
import tempfile
from pathlib import Path

import numpy as np

from perga.studies.study_file import Parameter, Study
from perga.studies.sweep import sweep

HERE = Path(__file__).resolve().parent
CASE = HERE.parents[1] / "cases" / "rebound-test.toml"
TRUE = {"contacts.granule-hammer.restitution": 0.72, "contacts.granule-hammer.friction": 0.28}
ANGLES = [0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.4]
NOISE = {"first_impact_restitution": 0.01, "first_impact_tangential_restitution_contact": 0.02}
SEED = 2026


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, default=HERE / "measured.csv")
    parser.add_argument("--workers", type=int, default=None)
    args = parser.parse_args(argv)
    parameters = {k: Parameter(values=[v]) for k, v in TRUE.items()}
    parameters["granules.placement.angle"] = Parameter(values=ANGLES)
    study = Study(case=CASE, parameters=parameters, metrics=list(NOISE))
    with tempfile.TemporaryDirectory() as work:
        result = sweep(study, Path(work), workers=args.workers)
    rng = np.random.default_rng(SEED)
    rows = sorted(result.rows, key=lambda r: r["granules.placement.angle"])
    with args.output.open("w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream)
        writer.writerow(["granules.placement.angle", *(c for m in NOISE for c in (m, f"{m}_sd"))])
        for row in rows:
            cells = [row["granules.placement.angle"]]
            for metric, sd in NOISE.items():
                cells += [f"{row[metric] + rng.normal(0.0, sd):.6f}", sd]
            writer.writerow(cells)
    print(f"wrote {args.output} ({len(rows)} rows)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
