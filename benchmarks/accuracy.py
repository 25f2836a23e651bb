"""What accuracy costs in time: the full work-precision study of ``perga accuracy``.

Runs every scene and setting of :func:`perga.studies.accuracy.studies` once (wall times: medians
of up to 3 runs where a run is cheap) and prints the recommended settings, then for each
reference and error level the cheapest setting of each contact model and its cost relative to
the cheapest overall. Errors are deterministic; wall times depend on the machine's load, which
is printed. Figures and interpretation: docs/explanation/accuracy.md.

    python benchmarks/accuracy.py                 # ~1.5-3 min on the shared 2-core machine
    python benchmarks/accuracy.py -o docs/explanation/accuracy  # also the CSV, Markdown and PNGs
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from perga.studies.accuracy import LEVELS, Row, run_study
from perga.studies.accuracy_report import recommended_table, write_outputs


def cheapest(rows: list[Row], reference: str, model: str, level: float) -> Row | None:
    """The cheapest ok row of one model reaching ``level`` on ``reference``."""
    good = [
        r
        for r in rows
        if r.reference == reference and r.model == model and r.status == "ok" and r.error <= level
    ]
    return min(good, key=lambda r: r.wall_per_sim) if good else None


def model_ratios(rows: list[Row]) -> str:
    """Markdown: per reference and level, each model's cheapest wall s per simulated s and its
    ratio to the cheapest model."""
    out = [
        "| reference | error ≤ | rigid | linear | hertz |",
        "|---|---:|---:|---:|---:|",
    ]
    for reference in dict.fromkeys(r.reference for r in rows):
        for level in LEVELS:
            best = {m: cheapest(rows, reference, m, level) for m in ("rigid", "linear", "hertz")}
            costs = [b.wall_per_sim for b in best.values() if b is not None]
            floor = min(costs) if costs else math.nan
            cells = [
                "–" if b is None else f"{b.wall_per_sim:.3g} ({b.wall_per_sim / floor:.3g}×)"
                for b in best.values()
            ]
            out.append(f"| {reference} | {100 * level:g} % | " + " | ".join(cells) + " |")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("-o", "--output", type=Path, help="also write CSV, Markdown and PNGs here")
    p.add_argument("--quick", action="store_true", help="the small subset of the tests")
    args = p.parse_args(argv)
    result = run_study(quick=args.quick, progress=lambda line: print(line, flush=True))
    print(
        f"\nstudy: {result.wall:.0f} s, load average {result.load[0]:.2f} -> {result.load[1]:.2f}"
    )
    print("\nRecommended settings (cheapest reaching each level):\n")
    print(recommended_table(result.rows))
    print("Cheapest setting per model, wall s per simulated s (× the cheapest model):\n")
    print(model_ratios(result.rows))
    if args.output:
        paths = write_outputs(result, args.output)
        print(f"\nwrote {len(paths)} files to {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
