"""The window under a calibration's uncertainty, drawn and reported: ``odds.png`` (the
probability that each setting is inside the window, contours at 0.5 and 0.9), ``odds.parquet``
and ``odds.csv`` (per setting: probability, its interval, each metric's mean and variance
split), and ``report.md`` (the setting with the highest probability and that probability, the
map, what is calibrated and what is assumed, the variance split), with ``report.html`` (the
same, one self-contained page)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq

from perga.output.figures import new_figure, save
from perga.output.html_report import write_markdown_report
from perga.studies.user_units import axis_label, metric_label
from perga.studies.window import DAMAGE, METRICS, RELEASE
from perga.studies.window_report import cell_edges

if TYPE_CHECKING:
    from perga.studies.window_odds import OddsResult
    from perga.studies.window_posterior import SettingOdds


def write_odds_table(result: OddsResult, directory: Path) -> tuple[Path, Path]:
    """``DIR/odds.parquet`` and ``DIR/odds.csv``: a row per setting (SI, variances in the
    metrics' units squared)."""
    a, b = result.window.axes
    columns: dict[str, list[Any]] = {
        a: [o.x for o in result.odds],
        b: [o.y for o in result.odds],
        "probability": [o.probability for o in result.odds],
        "probability_low": [o.low for o in result.odds],
        "probability_high": [o.high for o in result.odds],
        "draws": [o.draws for o in result.odds],
        "seeds": [o.seeds for o in result.odds],
        "missing": [o.missing for o in result.odds],
    }
    for m in METRICS:
        columns[f"{m}_mean"] = [o.split[m].mean for o in result.odds]
        columns[f"{m}_var_parameters"] = [o.split[m].parameter for o in result.odds]
        columns[f"{m}_var_seeds"] = [o.split[m].seed for o in result.odds]
    table = pa.table(columns)
    parquet, csv = directory / "odds.parquet", directory / "odds.csv"
    pq.write_table(table, parquet)
    pacsv.write_csv(table, csv)
    return parquet, csv


def write_odds_map(result: OddsResult, directory: Path) -> Path:
    """``DIR/odds.png``: the probability of each setting being inside the window, tiles only
    over the settings simulated, contours at 0.5 and 0.9, the best setting ringed."""
    window = result.window
    xs, ys = window.grid()
    (xl, xf), (yl, yf) = axis_label(window.axes[0]), axis_label(window.axes[1])
    grid = np.full((len(ys), len(xs)), math.nan)
    for o in result.odds:
        grid[ys.index(o.y), xs.index(o.x)] = o.probability
    fig, ax = new_figure((7.5, 5.5))
    ux, uy = np.array(xs) * xf, np.array(ys) * yf
    mesh = ax.pcolormesh(
        cell_edges(list(ux)), cell_edges(list(uy)), np.ma.masked_invalid(grid), cmap="RdYlGn",
        vmin=0.0, vmax=1.0,
    )  # fmt: skip
    fig.colorbar(mesh, ax=ax, label="P(inside the window)")
    if len(xs) >= 2 and len(ys) >= 2 and np.isfinite(grid).all():
        lines = ax.contour(ux, uy, grid, levels=[0.5, 0.9], colors=["k", "k"],
                           linestyles=["--", "-"])  # fmt: skip
        ax.clabel(lines, fmt={0.5: "0.5", 0.9: "0.9"}, fontsize=8)
    for o in result.odds:
        ax.text(o.x * xf, o.y * yf, f"{o.probability:.2f}", ha="center", va="center", fontsize=8)
    if result.best is not None:
        ax.plot(result.best.x * xf, result.best.y * yf, "o", ms=22, mfc="none", mec="blue", mew=2)
    ax.set_xlabel(xl)
    ax.set_ylabel(yl)
    rl, _ = metric_label(RELEASE)
    dl, _ = metric_label(DAMAGE)
    ax.set_title(
        f"P({rl} ≥ {100 * window.release_target:g}, {dl} ≤ {100 * window.damage_limit:g}) "
        f"over {len(result.posterior.draws)} posterior draws × {result.seeds} seeds",
        fontsize=9,
    )
    path = directory / "odds.png"
    save(fig, path)
    return path


def _split(o: SettingOdds, metric: str) -> str:
    """A metric's mean and its sd split into parameters and seeds, in the user's unit."""
    s = o.split[metric]
    _, factor = metric_label(metric)
    if math.isnan(s.mean):
        return "n/a"
    sd_p = math.sqrt(s.parameter) * factor if math.isfinite(s.parameter) else math.nan
    sd_s = math.sqrt(s.seed) * factor if math.isfinite(s.seed) else math.nan
    return f"{s.mean * factor:.3g} (θ {sd_p:.2g}, seed {sd_s:.2g})"


def odds_report(result: OddsResult, assumed: list[str], numerics: list[str]) -> str:
    """The Markdown report (module doc); ``assumed``: the case's material and contact keys not
    fitted, each as ``KEY = VALUE``, which the map takes as known; ``numerics``: lines on the
    contacts and the release law (:func:`perga.studies.window.foundations`)."""
    window = result.window
    a, b = window.axes
    (al, af), (bl, bf) = axis_label(a), axis_label(b)
    rl, _ = metric_label(RELEASE)
    dl, _ = metric_label(DAMAGE)
    post = result.posterior
    lines = [
        "# Operating window under the calibration's uncertainty",
        "",
        f"Case `{Path(window.study.case).name}`; window: {rl} ≥ {100 * window.release_target:g}"
        f" and {dl} ≤ {100 * window.damage_limit:g}.",
        "",
        f"At every setting {len(post.draws)} parameter sets drawn from the posterior of "
        f"`{post.source}`, each run with {result.seeds} seeds of its own "
        f"({len(result.rows)} runs, {result.ran} run now, {result.failed} failed). "
        "P is the share of draws whose seed mean is inside the window (Wilson 95 % interval).",
        "",
        "## What the map rests on",
        "",
        *numerics,
        "- calibrated (drawn from the posterior): " + ", ".join(f"`{k}`" for k in post.keys),
        "- assumed (the case's values, taken as known): "
        + (", ".join(f"`{k}`" for k in assumed) if assumed else "none"),
        "",
        "## The decision",
        "",
    ]
    if result.best is None:
        lines.append("**No setting has a chance**: no draw at any setting is inside the window.")
    else:
        o = result.best
        lines.append(
            f"**{al} = {o.x * af:.4g}, {bl} = {o.y * bf:.4g}**: P = {o.probability:.2f} "
            f"({o.low:.2f}-{o.high:.2f}) that it is inside the window."
        )
    lines += [
        "",
        "![odds](odds.png)",
        "",
        "## Every setting",
        "",
        "Each metric's mean over the runs, and the sd of its per-run value split into the "
        "parameters' part (θ) and the seeds' part (law of total variance).",
        "",
        f"| {al} | {bl} | P | 95 % | " + " | ".join(metric_label(m)[0] for m in METRICS) + " |",
        "|" + "---|" * (len(METRICS) + 4),
    ]
    for o in result.odds:
        cells = " | ".join(_split(o, m) for m in METRICS)
        lines.append(
            f"| {o.x * af:.4g} | {o.y * bf:.4g} | {o.probability:.2f} | "
            f"{o.low:.2f}-{o.high:.2f} | {cells} |"
        )
    lines += ["", "Files: odds.parquet, odds.csv, odds.png, results.parquet, runs/.", ""]
    return "\n".join(lines)


def write_odds_report(
    result: OddsResult, assumed: list[str], numerics: list[str], directory: Path
) -> Path:
    """``DIR/report.md`` (:func:`odds_report`) and report.html, after odds.png
    (:func:`write_odds_map`)."""
    path = directory / "report.md"
    write_markdown_report(path, odds_report(result, assumed, numerics))
    return path
