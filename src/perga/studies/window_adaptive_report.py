"""An adaptive window study's files: ``adaptive.parquet`` and ``adaptive.csv`` (per setting of
the grid: the probability of being inside, its class, the runs made there and each metric's
predicted mean and sd, SI), ``adaptive.png`` (the probability over the grid, the 0.5 contour,
the runs as dots sized by their count) and ``adaptive.md`` (the search, the map, the window it
found, what the map rests on), with ``adaptive.html`` (the same, one self-contained page)."""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq

from perga.output.figures import new_figure, save
from perga.output.html_report import write_markdown_report
from perga.run.summary import path_from
from perga.studies.user_units import axis_label, metric_label
from perga.studies.window import DAMAGE, RELEASE, foundations
from perga.studies.window_report import cell_edges

if TYPE_CHECKING:
    from perga.studies.window_adaptive import AdaptiveWindow


def write_adaptive(result: AdaptiveWindow, directory: Path) -> None:
    """The table, the map and the report, Markdown and HTML (module doc), into
    ``directory``."""
    search, window = result.search, result.window
    a, b = window.axes
    grid_x, grid_y = np.meshgrid(search.xs, search.ys)
    count = Counter(search.settings)
    columns: dict[str, Any] = {
        a: grid_x.ravel().tolist(),
        b: grid_y.ravel().tolist(),
        "probability": search.probability.ravel().tolist(),
        "inside": search.inside.ravel().tolist(),
        "runs": [
            count[(float(x), float(y))]
            for x, y in np.column_stack([grid_x.ravel(), grid_y.ravel()])
        ],
    }
    for m in (RELEASE, DAMAGE):
        columns[f"{m}_predicted"] = search.mean[m].ravel().tolist()
        columns[f"{m}_predicted_sd"] = search.sd[m].ravel().tolist()
    table = pa.table(columns)
    pq.write_table(table, directory / "adaptive.parquet")
    pacsv.write_csv(table, directory / "adaptive.csv")
    (xl, xf), (yl, yf) = axis_label(a), axis_label(b)
    ux, uy = search.xs * xf, search.ys * yf
    fig, ax = new_figure((7.5, 5.5))
    mesh = ax.pcolormesh(cell_edges(list(ux)), cell_edges(list(uy)), search.probability,
                         cmap="RdYlGn", vmin=0.0, vmax=1.0)  # fmt: skip
    fig.colorbar(mesh, ax=ax, label="P(inside the window)")
    if len(ux) >= 2 and len(uy) >= 2:
        ax.contour(ux, uy, search.probability, levels=[0.5], colors="k")
    ran = list(count.items())
    ax.scatter(
        [s[0] * xf for s, _ in ran], [s[1] * yf for s, _ in ran], s=[12 * n for _, n in ran],
        c="k", marker="o", label="runs (size: count)",
    )  # fmt: skip
    ax.legend(loc="upper left", fontsize=7)
    ax.set_xlabel(xl)
    ax.set_ylabel(yl)
    ax.set_title(f"adaptive: {search.runs} runs, {search.rounds} rounds; the window is P ≥ 0.5",
                 fontsize=9)  # fmt: skip
    save(fig, directory / "adaptive.png")
    rl, df = metric_label(RELEASE)[0], metric_label(DAMAGE)[0]
    lines = [
        "# Operating window, found adaptively",
        "",
        f"Case `{path_from(directory, window.study.case)}`; "
        f"window: {rl} ≥ {100 * window.release_target:g} "
        f"and {df} ≤ {100 * window.damage_limit:g}; grid {len(search.xs)} × {len(search.ys)} "
        f"({xl} {ux.min():.4g}-{ux.max():.4g}; {yl} {uy.min():.4g}-{uy.max():.4g}).",
        "",
        f"- runs: {search.runs} in {search.rounds} rounds ({result.ran} run now, the others "
        f"found finished); stopped: {search.stopped}",
        f"- settings in the window (P ≥ 0.5): {int(search.inside.sum())} of "
        f"{search.inside.size}; unsure (0.1 < P < 0.9): "
        f"{int(np.count_nonzero((search.probability > 0.1) & (search.probability < 0.9)))}",
        "",
        "![adaptive](adaptive.png)",
        "",
        "## What the map rests on",
        "",
        *foundations(window),
        "- each metric between the runs: a Gaussian process's prediction (adaptive.parquet "
        "gives its mean and sd at every setting)",
        "",
        "Files: adaptive.parquet, adaptive.csv, adaptive.png, adaptive-runs.parquet, runs/.",
        "",
    ]
    write_markdown_report(directory / "adaptive.md", "\n".join(lines))
