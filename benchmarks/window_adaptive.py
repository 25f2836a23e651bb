"""The adaptive window against the dense one: the bundled bee-bread separator over a 10 × 10
grid of rotor speed and hammer mass, 3 replicates per cell (the dense map), then the adaptive
search on the same grid in the same folder (its runs are the dense study's, found by key: it
costs nothing here and is judged cell by cell). Prints the runs each used and the cells they
classify differently; writes the dense study's report and maps, the adaptive one's, and
adaptive-vs-dense.png (the two classifications side by side, the cells they differ on marked).

    python benchmarks/window_adaptive.py [--budget 100] [--duration 0.3] [--workers 2] [-o DIR]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from perga.output.figures import new_figure, save
from perga.studies.adaptive import AdaptiveResult
from perga.studies.user_units import axis_label
from perga.studies.window import in_window, run_window, window_study
from perga.studies.window_adaptive import run_adaptive
from perga.studies.window_adaptive_report import write_adaptive
from perga.studies.window_report import cell_edges, write_maps, write_report, write_trade_offs

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


def side_by_side(
    dense: np.ndarray, adaptive: AdaptiveResult, axes: tuple[str, str], path: Path
) -> None:
    """The dense classification and the adaptive one on one figure, differing cells marked."""
    (xl, xf), (yl, yf) = axis_label(axes[0]), axis_label(axes[1])
    ux, uy = np.asarray(adaptive.xs) * xf, np.asarray(adaptive.ys) * yf
    fig, (left, right) = new_figure((11.0, 4.8), ncols=2)
    for ax, inside, title in (
        (left, dense, f"dense: {dense.size} cells × 3 replicates"),
        (right, adaptive.inside, f"adaptive: {adaptive.runs} runs"),
    ):
        ax.pcolormesh(cell_edges(list(ux)), cell_edges(list(uy)), inside.astype(float),
                      cmap="RdYlGn", vmin=-0.3, vmax=1.3)  # fmt: skip
        ax.set_title(f"{title}; green: inside", fontsize=9)
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
    grid_x, grid_y = np.meshgrid(ux, uy)
    differ = dense != adaptive.inside
    right.scatter(grid_x[differ], grid_y[differ], marker="x", c="k", s=60,
                  label="classified otherwise than dense")  # fmt: skip
    if differ.any():
        right.legend(loc="upper left", fontsize=7)
    save(fig, path)


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
    for write in (write_maps, write_trade_offs, write_report):
        write(dense, args.output)
    write_adaptive(adaptive, args.output)
    side_by_side(inside, search, window.axes, args.output / "adaptive-vs-dense.png")
    print(f"-> {args.output}/report.md, adaptive.md, adaptive-vs-dense.png")


if __name__ == "__main__":
    main()
