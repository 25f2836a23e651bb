"""Make the synthetic data of the calibration examples from perga runs at stated true values.

* ``rebound`` -> measured.csv: restitution e = 0.72 and friction f = 0.28 between bee bread and
  steel; the granule of cases/rebound-test.toml fired at 5 m/s at seven angles of incidence,
  0.2-1.4 rad; each shot's normal restitution and tangential restitution at the contact point
  plus Gaussian noise of the stated standard deviations (0.01 and 0.02), seeded.
* ``struck`` -> struck.csv: e = 0.7; the granule of cases/single-granule.toml struck by its
  hinged hammer at 300-1200 rpm; its speed after the first impact plus noise of sd 0.05 m/s.
* ``separator`` -> separator.csv: the bundled separator's contacts (cases/separator.toml: bee
  bread on steel e = 0.7, f = 0.35, on bee bread e = 0.6, f = 0.5), its first 0.2 s run with
  four seeds of the data's own (not the calibration's seed): each metric's mean over them and
  its standard error, as a measurement repeated on as many fillings would give it.

Seeded: the same files every time.

    python examples/calibration/make_data.py [rebound|struck|separator] [-o FILE] [--workers N]
"""

from __future__ import annotations

import argparse
import csv
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from perga.studies.study_file import Parameter, Study
from perga.studies.sweep import sweep

HERE = Path(__file__).resolve().parent
CASES = HERE.parents[1] / "cases"
SEED = 2026
"""The noise's and the replicates' seeds derive from this one; calibrations run with seed 0's."""


@dataclass(frozen=True)
class Example:
    """Runs at ``truth`` over a ``condition`` key's values; each metric with its noise sd
    (None: the replicates' standard error instead)."""

    case: Path
    output: str
    truth: dict[str, float]
    condition: tuple[str, list[float]]
    noise: dict[str, float | None]
    replicates: int = 1
    fixed: dict[str, float] = field(default_factory=dict)


EXAMPLES = {
    "rebound": Example(
        CASES / "rebound-test.toml", "measured.csv",
        {"contacts.granule-hammer.restitution": 0.72, "contacts.granule-hammer.friction": 0.28},
        ("granules.placement.angle", [0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.4]),
        {"first_impact_restitution": 0.01, "first_impact_tangential_restitution_contact": 0.02},
    ),
    "struck": Example(
        CASES / "single-granule.toml", "struck.csv",
        {"contacts.granule-hammer.restitution": 0.7},
        ("rotor.rpm", [300.0, 600.0, 900.0, 1200.0]),
        {"granule_speed_after_impact:1": 0.05},
        fixed={"solver.duration": 0.06},
    ),
    "separator": Example(
        CASES / "separator.toml", "separator.csv",
        {"contacts.beebread-steel.restitution": 0.7, "contacts.beebread-steel.friction": 0.35,
         "contacts.beebread-beebread.restitution": 0.6,
         "contacts.beebread-beebread.friction": 0.5},
        ("solver.duration", [0.2]),
        {"impact_count": None, "energy_gain_per_impact": None, "dissipated_fraction": None,
         "mean_speed_at_end": None},
        replicates=4,
    ),
}  # fmt: skip


def write(example: Example, path: Path, workers: int | None) -> Path:
    """Run ``example`` at its truth and write its data file to ``path``."""
    key, values = example.condition
    parameters = {k: Parameter(values=[v]) for k, v in {**example.truth, **example.fixed}.items()}
    parameters[key] = Parameter(values=values)
    study = Study(case=example.case, parameters=parameters, metrics=list(example.noise),
                  replicates=example.replicates, seed=SEED)  # fmt: skip
    with tempfile.TemporaryDirectory() as work:
        result = sweep(study, Path(work), workers=workers)
        if result.failed:
            reasons = {row["reason"] for row in result.rows if row["status"] != "ok"}
            raise SystemExit(f"{result.failed} run(s) failed, no data written: {reasons}")
        rows = result.rows
    rng = np.random.default_rng(SEED)
    with path.open("w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream)
        writer.writerow([key, *(c for m in example.noise for c in (m, f"{m}_sd"))])
        for value in values:
            runs = [row for row in rows if row[key] == value]
            cells: list[object] = [value]
            for metric, sd in example.noise.items():
                measured = np.array([row[metric] for row in runs])
                if sd is None:
                    error = measured.std(ddof=1) / np.sqrt(len(measured))
                    cells += [f"{measured.mean():.6g}", f"{error:.6g}"]
                else:
                    cells += [f"{measured.mean() + rng.normal(0.0, sd):.6f}", sd]
            writer.writerow(cells)
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("example", nargs="?", choices=list(EXAMPLES), default="rebound")
    parser.add_argument("-o", "--output", type=Path, help="default: the example's file here")
    parser.add_argument("--workers", type=int, default=None)
    args = parser.parse_args(argv)
    example = EXAMPLES[args.example]
    print(f"wrote {write(example, args.output or HERE / example.output, args.workers)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
