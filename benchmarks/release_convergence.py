"""Does the separator's outcome depend on the numerics? The bundled bee-bread separator at two
settings, its released fraction, throughput and damaged fraction against the step (×1, ½, ¼)
and, with soft contacts, the contact duration (×1, ½, ¼), rigid and soft, each over seeded
replicates on Dask; printed as a Markdown table of mean ± sd per row and, per setting and
model, the largest departure from the ×1 row in units of the replicates' sd.

    python benchmarks/release_convergence.py [--replicates 3] [--duration 0.3] [--workers 2]
        [--set KEY=VALUE ...] [-o DIR]

``--set`` changes the case for every run (e.g. ``materials.beebread.detachment_energy=0.1``).
The runs stay in DIR/runs (found again by key: a second call with the same options runs only
those that failed).
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from pathlib import Path

from perga.model.compile import load_system
from perga.studies.executor import run_missing
from perga.studies.jobs import derived_seed, make_job

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "bee-bread-separator.toml"
SETTINGS = ((700.0, 0.05), (1300.0, 0.075))
"""(rpm, hammer mass kg): one near the release edge, one inside the window."""
METRICS = ("released_fraction", "throughput", "damaged_fraction")
FACTORS = (1.0, 0.5, 0.25)
RECORD = 'output.record=["granules", "impacts", "energy", "releases", "outflow"]'


def variants(extra: tuple[str, ...]) -> list[tuple[str, str, dict[str, object], tuple[str, ...]]]:
    """(model, label, parameters, overrides) of every row: the step and the duration scaled."""
    _, soft = load_system(CASE, overrides=extra)
    rigid_extra = (*extra, 'contact_model={kind="rigid"}')
    _, rigid = load_system(CASE, overrides=rigid_extra)
    t_c = soft.contact_model.duration if hasattr(soft.contact_model, "duration") else 1e-4
    rows = []
    for f in FACTORS:
        rows.append(("rigid", f"step ×{f:g}", {"solver.dt": rigid.granule_dt * f}, rigid_extra))
    for f in FACTORS:
        rows.append(("soft", f"step ×{f:g}", {"contact_model.steps_per_contact": 50.0 / f}, extra))
    for f in FACTORS[1:]:
        rows.append(("soft", f"duration ×{f:g}", {"contact_model.duration": t_c * f}, extra))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--replicates", type=int, default=3)
    parser.add_argument("--duration", type=float, default=0.3, help="simulated time, s")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--set", action="append", default=[], dest="sets")
    parser.add_argument("-o", "--output", type=Path, default=Path("release-convergence"))
    args = parser.parse_args()
    extra = (RECORD, f"solver.duration={args.duration!r}", *args.sets)
    jobs, labels = [], {}
    rows_of_table = variants(extra)
    order = {label: i for i, (_, label, _, _) in enumerate(rows_of_table)}
    for rpm, mass in SETTINGS:
        for model, label, parameters, overrides in rows_of_table:
            for rep in range(args.replicates):
                job = make_job(
                    CASE,
                    {"rotor.rpm": rpm, "hammers.mass": mass, **parameters},
                    rep,
                    derived_seed(0, rep),
                    (*METRICS, "ledger_closure"),
                    args.output,
                    overrides,
                )
                jobs.append(job)
                labels[job.key] = (rpm, mass, model, label)
    rows: dict[tuple, list[dict]] = {}
    start = time.perf_counter()
    ran = run_missing(jobs, lambda row: rows.setdefault(labels[row["key"]], []).append(row),
                      workers=args.workers, retry_failed=True)  # fmt: skip
    wall = time.perf_counter() - start
    print(f"{len(jobs)} runs of {args.duration:g} s ({ran} run now, the others found finished), "
          f"{wall:.0f} s on {args.workers} workers")  # fmt: skip
    print(f"case changes: {', '.join(args.sets) or 'none'}\n")
    print("| rpm | hammer g | model | numerics | " + " | ".join(METRICS) + " | failed |")
    print("|---|---|---|---|" + "---|" * (len(METRICS) + 1))
    worst: dict[tuple, dict[str, float]] = {}
    base: dict[tuple, dict[str, tuple[float, float]]] = {}
    for key in sorted(rows, key=lambda k: (k[0], k[2], order[k[3]])):
        rpm, mass, model, label = key
        ok = [r for r in rows[key] if r["status"] == "ok"]
        cells, stats = [], {}
        for m in METRICS:
            values = [r[m] for r in ok if r[m] is not None and math.isfinite(r[m])]
            mean = statistics.fmean(values) if values else math.nan
            sd = statistics.stdev(values) if len(values) > 1 else math.nan
            stats[m] = (mean, sd)
            cells.append(f"{mean:.4g} ± {sd:.2g}")
        print(f"| {rpm:g} | {mass * 1e3:g} | {model} | {label} | {' | '.join(cells)} | "
              f"{len(rows[key]) - len(ok)} |")  # fmt: skip
        group = (rpm, mass, model)
        if label == "step ×1":
            base[group] = stats
        elif group in base:
            w = worst.setdefault(group, {})
            for m in METRICS:
                (m0, s0), (m1, s1) = base[group][m], stats[m]
                spread = math.hypot(s0, s1) or math.nan
                w[m] = max(w.get(m, 0.0), abs(m1 - m0) / spread)
    print("\nLargest |mean − mean at ×1| / √(sd² + sd×1²) per setting and model:")
    for group, w in sorted(worst.items()):
        print(f"  {group[0]:g} rpm, {group[1] * 1e3:g} g, {group[2]}: "
              + ", ".join(f"{m} {v:.2f}" for m, v in w.items()))  # fmt: skip
    print("\nRigid against soft at ×1, |difference| / √(sd² + sd²):")
    for rpm, mass in SETTINGS:
        rigid, soft = base.get((rpm, mass, "rigid")), base.get((rpm, mass, "soft"))
        if rigid and soft:
            parts = []
            for m in METRICS:
                (m0, s0), (m1, s1) = rigid[m], soft[m]
                parts.append(f"{m} {abs(m1 - m0) / (math.hypot(s0, s1) or math.nan):.2f}")
            print(f"  {rpm:g} rpm, {mass * 1e3:g} g: " + ", ".join(parts))


if __name__ == "__main__":
    main()
