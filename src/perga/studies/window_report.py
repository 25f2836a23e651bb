"""The window study's maps (``window.png``: one panel per metric over the two keys, the operating
window hatched; ``trade-offs.png``: the Pareto front) and report (``report.md``: the grid, the
best setting, how sure, the trade-offs, the trends; ``report.html``: the same with the figures,
one self-contained page), in the user's units
(:mod:`perga.studies.user_units`)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.patches import Rectangle

from perga.output.figures import new_figure, save
from perga.output.html_report import write_markdown_report
from perga.run.summary import path_from
from perga.studies.user_units import axis_label, metric_label
from perga.studies.window import (
    DAMAGE,
    ENERGY,
    METRICS,
    RELEASE,
    THROUGHPUT,
    Point,
    Trend,
    in_window,
    shortfall,
)

if TYPE_CHECKING:
    from perga.studies.window import WindowResult


def cell_edges(values: list[float]) -> np.ndarray:
    """Cell edges around grid values (midpoints; the ends half a spacing out), as pcolormesh's
    ``shading="nearest"`` draws them."""
    v = np.asarray(values, dtype=float)
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = (v[1:] + v[:-1]) / 2
    return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])


def write_maps(result: WindowResult, directory: Path) -> Path:
    """``DIR/window.png``: each metric's mean over the grid, the window's cells hatched and
    outlined (release_mean ≥ target and damage_mean ≤ limit)."""
    window = result.window
    xs, ys = window.grid()
    (xl, xf), (yl, yf) = axis_label(window.axes[0]), axis_label(window.axes[1])
    ux, uy = [x * xf for x in xs], [y * yf for y in ys]
    xe, ye = cell_edges(ux), cell_edges(uy)
    fig, axes = new_figure((11.0, 8.5), 2, 2)
    for ax, metric in zip(axes.flat, METRICS, strict=True):
        label, factor = metric_label(metric)
        grid = np.full((len(ys), len(xs)), math.nan)
        for p in result.points:
            grid[ys.index(p.y), xs.index(p.x)] = p.mean[metric] * factor
        finite = np.isfinite(grid)
        mesh = ax.pcolormesh(ux, uy, np.ma.masked_invalid(grid), shading="nearest", cmap="viridis")
        if finite.any():
            fig.colorbar(mesh, ax=ax, label=label)
        for p in result.points:
            i, j = ys.index(p.y), xs.index(p.x)
            if in_window(p, window.release_target, window.damage_limit):
                ax.add_patch(
                    Rectangle(
                        (xe[j], ye[i]), xe[j + 1] - xe[j], ye[i + 1] - ye[i],
                        fill=False, hatch="//", edgecolor="red", linewidth=2.0,
                    )
                )  # fmt: skip
            text = "n/a" if math.isnan(p.mean[metric]) else f"{p.mean[metric] * factor:.3g}"
            ax.text(p.x * xf, p.y * yf, text, ha="center", va="center", fontsize=8, color="black",
                    bbox={"facecolor": "white", "alpha": 0.6, "lw": 0})  # fmt: skip
        if not any(in_window(p, window.release_target, window.damage_limit) for p in result.points):
            ax.text(0.5, 1.0, "no point in the window", transform=ax.transAxes, ha="center",
                    va="bottom", fontsize=8, color="red")  # fmt: skip
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.set_title(f"{label}: mean of {window.study.replicates} replicates")
    fig.suptitle(
        f"operating window (hatched): {metric_label(RELEASE)[0]} ≥ "
        f"{100 * window.release_target:g}, {metric_label(DAMAGE)[0]} ≤ "
        f"{100 * window.damage_limit:g}"
    )
    path = directory / "window.png"
    save(fig, path)
    return path


def write_trade_offs(result: WindowResult, directory: Path) -> Path:
    """``DIR/trade-offs.png``: every point's damage against its throughput, coloured by its
    energy per kg, the Pareto front (:func:`perga.studies.window.trade_offs`) ringed and
    labelled with its setting."""
    (tl, tf), (dl, df), (el, ef) = (metric_label(m) for m in (THROUGHPUT, DAMAGE, ENERGY))
    shown = [p for p in result.points if all(math.isfinite(p.mean[m]) for m in METRICS)]
    fig, ax = new_figure((7.5, 5.5))
    if shown:
        dots = ax.scatter(
            [p.mean[THROUGHPUT] * tf for p in shown], [p.mean[DAMAGE] * df for p in shown],
            c=[p.mean[ENERGY] * ef for p in shown], cmap="viridis", s=40, zorder=2,
        )  # fmt: skip
        fig.colorbar(dots, ax=ax, label=el)
    for p in result.front:
        ax.plot(p.mean[THROUGHPUT] * tf, p.mean[DAMAGE] * df, "o", ms=14, mfc="none", mec="red")
        ax.annotate(_short(result, p), (p.mean[THROUGHPUT] * tf, p.mean[DAMAGE] * df),
                    textcoords="offset points", xytext=(6, 6), fontsize=7)  # fmt: skip
    ax.set_xlabel(tl)
    ax.set_ylabel(dl)
    ax.set_title(f"trade-offs: {len(result.front)} settings no other beats on throughput, "
                 "damage and energy (ringed)", fontsize=9)  # fmt: skip
    path = directory / "trade-offs.png"
    save(fig, path)
    return path


def _short(result: WindowResult, point: Point) -> str:
    """A setting in the user's units, short: ``1300 rpm, 75 g``."""
    (al, af), (bl, bf) = (axis_label(k) for k in result.window.axes)
    return f"{point.x * af:.4g} {al.split('[')[1][:-1]}, {point.y * bf:.4g} {bl.split('[')[1][:-1]}"


def _pm(point: Point, metric: str, unit: bool = False) -> str:
    """``mean ± sd`` in the user's unit (and the unit), with the number of runs that gave it
    when some did not."""
    label, factor = metric_label(metric)
    mean, sd = point.mean[metric] * factor, point.sd[metric] * factor
    if math.isnan(mean):
        return "n/a"
    text = f"{mean:.4g} ± {sd:.2g}" if math.isfinite(sd) else f"{mean:.4g}"
    if unit:
        text += f" {label.split('[')[1][:-1]}"
    ok = point.runs - point.failed
    return text if point.count[metric] == ok else f"{text} (n = {point.count[metric]})"


def _setting(result: WindowResult, point: Point) -> str:
    (al, af), (bl, bf) = (axis_label(k) for k in result.window.axes)
    return f"{al} = {point.x * af:.6g}, {bl} = {point.y * bf:.6g}"


def _trend_line(t: Trend, speed: str, other: str, *, rising: bool) -> str:
    rho = "n/a" if math.isnan(t.rho) else f"{t.rho:+.2f}"
    if rising:
        holds = t.falling_clear == 0 and t.rising > 0
        verdict = "rises" if holds else "does not clearly rise"
    else:
        holds = t.falling_clear == 0
        verdict = "does not fall" if holds else "falls"
    return (
        f"| {t.metric} | {other} = {t.other:.6g} | {t.pairs} | {t.rising} ({t.rising_clear}) | "
        f"{t.falling} ({t.falling_clear}) | {t.equal} | {rho} | {verdict} with {speed} |"
    )


def report_text(result: WindowResult, directory: Path) -> str:
    """The Markdown report of a window study, written in ``directory`` (the case is named from
    there)."""
    window = result.window
    study = window.study
    rt, dl = window.release_target, window.damage_limit
    xs, ys = window.grid()
    a, b = window.axes
    (al, af), (bl, bf) = axis_label(a), axis_label(b)
    fixed = {k: p.values[0] for k, p in study.parameters.items() if k not in window.axes}  # type: ignore[index]
    lines = [
        "# Operating window",
        "",
        f"Case `{path_from(directory, study.case)}`; "
        f"window: {RELEASE} ≥ {rt:g} and {DAMAGE} ≤ {dl:g}.",
        "",
        "## Grid",
        "",
        f"- {a}, {al}: {', '.join(f'{v * af:.6g}' for v in xs)}",
        f"- {b}, {bl}: {', '.join(f'{v * bf:.6g}' for v in ys)}",
        f"- replicates: {study.replicates} per point (each its own solver.seed; seed {study.seed})",
    ]
    if fixed:
        lines.append("- fixed: " + ", ".join(f"{k} = {v}" for k, v in fixed.items()))
    lines += [
        f"- runs: {len(result.rows)} ({result.ran} run now, {result.reused} found finished, "
        f"{result.failed} failed)",
        "",
        "Mean ± standard deviation over replicates; * inside the window.",
        "",
        f"| {al} | {bl} | " + " | ".join(metric_label(m)[0] for m in METRICS) + " | in |",
        "|" + "---|" * (len(METRICS) + 3),
    ]
    for p in result.points:
        mark = "*" if in_window(p, rt, dl) else ""
        cells = " | ".join(_pm(p, m) for m in METRICS)
        lines.append(f"| {p.x * af:.6g} | {p.y * bf:.6g} | {cells} | {mark} |")
    lines += [
        "",
        "![window](window.png)",
        "",
        "## What the map rests on",
        "",
        *result.foundations,
        "",
        "## Best setting",
        "",
    ]
    best = result.best
    if best.point is None:
        lines.append("No point gave both a release and a damage fraction: no setting to name.")
    elif best.inside:
        p = best.point
        lines.append(
            f"**{_setting(result, p)}**: inside the window with the highest throughput "
            f"({_pm(p, THROUGHPUT, True)}; energy {_pm(p, ENERGY, True)})."
        )
    else:
        p = best.point
        lines.append(
            f"**No setting meets both.** The nearest: {_setting(result, p)} "
            f"({RELEASE} {_pm(p, RELEASE)}, {DAMAGE} {_pm(p, DAMAGE)}; "
            f"{shortfall(p, rt, dl):.3g} short of the window)."
        )
    lines += ["", "## How sure", ""]
    if best.point is not None:
        p = best.point
        lines.append(
            "Replicate spread at that point (mean ± sd): "
            + "; ".join(f"{m} {_pm(p, m, True)}" for m in METRICS)
            + "."
        )
    nominal = {(p.x, p.y) for p in result.points if in_window(p, rt, dl)}
    low = {(p.x, p.y) for p in result.points if in_window(p, rt, dl, 1.0)}
    high = {(p.x, p.y) for p in result.points if in_window(p, rt, dl, -1.0)}
    lines += [
        "",
        f"- window: {len(nominal)} of {len(result.points)} points",
        f"- means moved 1 sd towards failing (release − sd, damage + sd): {len(low)} points"
        + ("" if low == nominal else " — the window shrinks"),
        f"- means moved 1 sd the other way (release + sd, damage − sd): {len(high)} points"
        + ("" if high == nominal else " — the window grows"),
    ]
    if low == nominal == high:
        lines.append("- the window does not change within ±1 sd")
    if best.point is not None and best.inside:
        kept = (best.point.x, best.point.y) in low
        lines.append(
            "- the best setting stays inside when its means move 1 sd towards failing"
            if kept
            else "- the best setting leaves the window when its means move 1 sd towards failing"
        )
    if study.replicates < 2:
        lines.append("- one replicate per point: no spread is known (sd n/a, taken as 0)")
    lines += [
        "",
        "## Trade-offs",
        "",
        "The settings no other beats on all of throughput (more), damage and energy per kg "
        "(less), the Pareto front (trade-offs.png): a designer trades among these.",
        "",
        "![trade-offs](trade-offs.png)",
        "",
        f"| setting | {metric_label(THROUGHPUT)[0]} | {metric_label(DAMAGE)[0]} | "
        f"{metric_label(ENERGY)[0]} | in |",
        "|---|---|---|---|---|",
    ]
    for p in result.front:
        mark = "*" if in_window(p, rt, dl) else ""
        lines.append(
            f"| {_short(result, p)} | {_pm(p, THROUGHPUT)} | {_pm(p, DAMAGE)} | "
            f"{_pm(p, ENERGY)} | {mark} |"
        )
    if not result.front:
        lines.append("| none: no point gave all three | | | | |")
    speed = window.speed_axis
    other = b if speed == a else a
    lines += [
        "",
        "## Trends along " + speed,
        "",
        f"Pairs of {speed} values (lower, higher) at each {other}: how many rose and fell "
        "(in brackets: by more than the replicates' spread √(sd₁² + sd₂²)), and Spearman's ρ.",
        "",
        "| metric | at | pairs | rising (clear) | falling (clear) | equal | ρ | verdict |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for t in result.trends:
        lines.append(_trend_line(t, speed, other, rising=t.metric == DAMAGE))
    ax, ay = result.window.axes
    noted = [p for p in result.points if p.notes]
    if noted:
        lines += ["", "## Notes", "", "Metrics some runs could not give, and runs that failed "
                  "or ended with their energy ledger off (left out of the means), by point:",
                  ""]  # fmt: skip
        lines += [f"- {ax} = {p.x:g}, {ay} = {p.y:g}: {'; '.join(p.notes)}" for p in noted]
    lines += [
        "",
        "Files: window.parquet, window.csv, window.png, trade-offs.png, results.parquet, runs/.",
        "",
    ]
    return "\n".join(lines)


def write_report(result: WindowResult, directory: Path) -> Path:
    """``DIR/report.md`` (:func:`report_text`) and report.html, after window.png and
    trade-offs.png (:func:`write_maps`, :func:`write_trade_offs`)."""
    path = directory / "report.md"
    write_markdown_report(path, report_text(result, directory))
    return path
