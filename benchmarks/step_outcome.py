"""What a longer soft step changes in a separator's outcome, and what it saves: a case run at
several values of one setting (``contact_model.steps_per_contact`` unless ``--key`` names
another, such as ``contact_model.granule_substeps``) over seeds, one thread, each run in this
process one after the other (numba's cache warmed first).

Per run: the wall time of the run (``summary.json``), the granule-hammer impacts, their median
restitution −v_n'/v_n (``impacts.csv``), the mean approach speed, the granules' mean energy
gain per impact, the dissipated fraction, the mean speed at the end and the ledger's closure
(:mod:`perga.stats.metrics`). Printed: mean and sd over the seeds per setting, then the largest
shift from the first setting in units of the seeds' sd (a shift within about 2 sd is what
another seed would give: a chaotic many-granule run is compared by its statistics, not its
paths).

    python benchmarks/step_outcome.py                     # the 1,000-granule separator, 0.05 s
    python benchmarks/step_outcome.py --values 50 20 15 --seeds 7 8 9
    python benchmarks/step_outcome.py --key contact_model.granule_substeps --values 5 25 50
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
from pathlib import Path

import pandas as pd

from perga.case import load_case
from perga.run import prepare_directory, run_case
from perga.stats import load_run
from perga.stats.metrics import evaluate

ROOT = Path(__file__).resolve().parents[1]
METRICS = ("energy_gain_per_impact", "dissipated_fraction", "mean_speed_at_end", "ledger_closure")


def outcome(case: Path, overrides: list[str], out: Path) -> dict[str, float]:
    """One run of ``case`` with ``overrides`` into ``out``: its wall time and statistics."""
    loaded = load_case(case, overrides=["solver.threads=1", *overrides])
    prepare_directory(out, overwrite=True)
    summary = run_case(loaded, case, out)
    if summary.status != "completed":
        raise RuntimeError(f"{case} with {overrides}: {summary.status}")
    impacts = pd.read_csv(out / "impacts.csv")
    run = load_run(out)
    return {
        "wall s": summary.wall_time,
        "impacts": len(impacts),
        "median e": (-impacts.normal_velocity_after / impacts.normal_velocity_before).median(),
        "approach m/s": -impacts.normal_velocity_before.mean(),
        **{name: evaluate(run, name) for name in METRICS},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--case", type=Path, default=ROOT / "benchmarks/cases/soft-separator-1000.toml"
    )
    parser.add_argument("--duration", type=float, default=0.05, help="simulated time, s")
    parser.add_argument("--key", default="contact_model.steps_per_contact", help="the setting")
    parser.add_argument("--values", nargs="+", default=["50", "20", "15"], help="its values")
    parser.add_argument("--seeds", type=int, nargs="+", default=[7, 8, 9])
    args = parser.parse_args()
    base = [f"solver.duration={args.duration!r}"]
    print(f"load average at start: {os.getloadavg()[0]:.2f}; cores: {os.cpu_count()}")
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        outcome(args.case, ["solver.duration=0.001"], Path(scratch) / "warm")
        for seed in args.seeds:  # seeds outermost: the settings' runs interleaved in time
            for value in args.values:
                sets = [*base, f"{args.key}={value}", f"solver.seed={seed}"]
                result = outcome(args.case, sets, Path(scratch) / "run")
                rows.append({"value": value, "seed": seed, **result})
    table = pd.DataFrame(rows)
    columns = [c for c in table.columns if c not in ("value", "seed")]
    stats = table.groupby("value", sort=False)[columns].agg(["mean", "std"])
    first = args.values[0]
    print(f"\n{args.case.name}, {args.duration} s, seeds {args.seeds}: mean (sd) over the seeds;")
    print(f"then each value's shift from {args.key} = {first}, in the seeds' mean sd")
    print(f"{args.key.rsplit('.', 1)[-1]:>22}  " + "".join(f"{n:>20}" for n in args.values))
    for column in columns:
        mean, sd = stats[(column, "mean")], stats[(column, "std")]
        cells = "".join(f"{f'{mean[n]:.4g} ({sd[n]:.2g})':>20}" for n in args.values)
        shifts = "".join(
            f"{abs(mean[n] - mean[first]) / statistics.fmean([sd[n], sd[first]]):6.1f}"
            for n in args.values[1:]
        )
        print(f"{column:>22}  {cells}  {shifts}")
    print(f"\nload average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
