"""The adaptive window against the dense one: the bundled bee-bread separator over a 10 × 10
grid of rotor speed and hammer mass, 3 replicates per cell (the dense map), then the adaptive
search on the same grid in the same folder (its runs are the dense study's, found by key: it
costs nothing here and is judged cell by cell). Prints the runs each used and the cells they
classify differently.

    python benchmarks/window_adaptive.py [--budget 100] [--duration 0.3] [--workers 2] [-o DIR]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from perga.studies.window import in_window, run_window, window_study
from perga.studies.window_adaptive import run_adaptive

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "bee-bread-separator.toml"
RECORD = 'record = ["granules", "impacts", "energy", "releases", "outflow"]'


def quiet_case(directory: Path) -> Path:
    """The bundled case without its ParaView output (the metrics do not read it)."""
    text = CASE.read_text().replace("../geometry", str(ROOT / "geometry"))
    start = text.index("record = [", text.index("[output]"))
    text = text[:start] + RECORD + text[text.index("\n", start) :]
    path = directory / "bee-bread-separator.toml"
    path.write_text(text)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--budget", type=int, default=100, help="the adaptive search's runs")
    parser.add_argument("--duration", type=float, default=0.3, help="simulated time, s")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--release-target", type=float, default=0.9)
    parser.add_argument("--damage-limit", type=float, default=0.08)
    parser.add_argument("-o", "--output", type=Path, default=Path("window-adaptive"))
    args = parser.parse_args()
    args.output.mkdir(parents=True, exist_ok=True)
    sets = ["rotor.rpm=400:1600:10", "hammers.mass=0.025:0.1:10",
            f"solver.duration={args.duration!r}"]  # fmt: skip
    window = window_study(
        quiet_case(args.output), sets, replicates=3, release_target=args.release_target,
        damage_limit=args.damage_limit,
    )  # fmt: skip
    start = time.perf_counter()
    dense = run_window(window, args.output, workers=args.workers)
    dense_time = time.perf_counter() - start
    xs, ys = window.grid()
    inside = np.zeros((len(ys), len(xs)), dtype=bool)
    for p in dense.points:
        inside[ys.index(p.y), xs.index(p.x)] = in_window(p, args.release_target, args.damage_limit)
    start = time.perf_counter()
    adaptive = run_adaptive(window, args.output, budget=args.budget, workers=args.workers)
    search = adaptive.search
    differ = int(np.count_nonzero(search.inside != inside))
    print(f"window: released ≥ {args.release_target:g}, damaged ≤ {args.damage_limit:g}; "
          f"runs of {args.duration:g} s")  # fmt: skip
    print(f"dense:    {len(dense.rows)} runs ({dense.ran} run now, {dense_time:.0f} s), "
          f"{int(inside.sum())} of {inside.size} cells inside")  # fmt: skip
    print(
        f"adaptive: {search.runs} runs in {search.rounds} rounds (stopped: {search.stopped}; "
        f"{adaptive.ran} not found among the dense runs), {int(search.inside.sum())} cells "
        f"inside; {differ} of {inside.size} cells classified otherwise than dense "
        f"({100 * differ / inside.size:.0f} %), {time.perf_counter() - start:.0f} s"
    )
    print(f"runs: adaptive/dense = {search.runs / len(dense.rows):.2f}")


if __name__ == "__main__":
    main()
