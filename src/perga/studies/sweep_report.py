"""Plots of a sweep's table: every metric against every parameter (each run a point, the mean
over replicates a line), and for a grid over two parameters a map of each metric (the mean over
replicates); PNG files in the sweep's folder, in the designer's units where perga knows them
(:mod:`perga.studies.user_units`: rpm, g, %, kg/h, kJ/kg; otherwise SI, with the unit named)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from perga.output.figures import new_figure, save
from perga.studies.user_units import axis_label, metric_label


def _numeric(values: list[Any]) -> np.ndarray | None:
    try:
        out = np.array([math.nan if v is None else float(v) for v in values])
    except (TypeError, ValueError):
        return None
    return out


def _slug(name: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in name).strip("_")


def write_plots(
    rows: list[dict[str, Any]], parameters: list[str], metrics: list[str], directory: Path
) -> list[Path]:
    """The plots of the ok rows of a sweep into ``directory``; returns their paths."""
    ok = [r for r in rows if r.get("status") == "ok"]
    paths: list[Path] = []
    if not ok:
        return paths
    for metric in metrics:
        y = _numeric([r.get(metric) for r in ok])
        if y is None:
            continue
        y_label, y_factor = metric_label(metric)
        y = y * y_factor
        for parameter in parameters:
            x = _numeric([r.get(parameter) for r in ok])
            if x is None:
                continue
            x_label, x_factor = axis_label(parameter)
            x = x * x_factor
            fig, ax = new_figure((5.5, 4.0))
            ax.plot(x, y, "o", ms=4, alpha=0.6, label="runs")
            levels = np.unique(x[np.isfinite(x)])
            means = [
                np.nanmean(y[x == v]) if np.any(np.isfinite(y[x == v])) else math.nan
                for v in levels
            ]
            if len(levels) < len(x):
                ax.plot(levels, means, "-", lw=1.5, label="mean over the other columns")
            ax.set_xlabel(x_label)
            ax.set_ylabel(y_label)
            ax.legend(fontsize=8)
            path = directory / f"{_slug(metric)}__{_slug(parameter)}.png"
            save(fig, path)
            paths.append(path)
        if len(parameters) == 2:
            path = _map(ok, parameters, metric, y, directory)
            if path is not None:
                paths.append(path)
    return paths


def _map(
    rows: list[dict[str, Any]], parameters: list[str], metric: str, y: np.ndarray, directory: Path
) -> Path | None:
    """The metric's mean over replicates (``y``, in its plotted unit) on a two-parameter grid, or
    None if not a grid."""
    a = _numeric([r.get(parameters[0]) for r in rows])
    b = _numeric([r.get(parameters[1]) for r in rows])
    if a is None or b is None:
        return None
    (a_label, a_factor), (b_label, b_factor) = axis_label(parameters[0]), axis_label(parameters[1])
    a, b = a * a_factor, b * b_factor
    xs, ys = np.unique(a), np.unique(b)
    if len(xs) * len(ys) > len(rows) or len(xs) < 2 or len(ys) < 2:
        return None  # not a full grid (an lhs or sobol design)
    grid = np.full((len(ys), len(xs)), math.nan)
    for i, yv in enumerate(ys):
        for j, xv in enumerate(xs):
            cell = y[(a == xv) & (b == yv)]
            if np.any(np.isfinite(cell)):
                grid[i, j] = np.nanmean(cell)
    fig, ax = new_figure((6.0, 4.5))
    mesh = ax.pcolormesh(xs, ys, grid, shading="nearest", cmap="viridis")
    label = metric_label(metric)[0]
    fig.colorbar(mesh, ax=ax, label=label)
    ax.set_xlabel(a_label)
    ax.set_ylabel(b_label)
    ax.set_title(f"{label}: mean over replicates")
    path = directory / f"map__{_slug(metric)}.png"
    save(fig, path)
    return path
