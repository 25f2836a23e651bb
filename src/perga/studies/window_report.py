"""The window study's maps (``window.png``: one panel per metric over the two keys, the operating
window hatched) and report (``report.md``: the grid, the best setting, how sure, the trends)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.patches import Rectangle

from perga.output.figures import new_figure, save
from perga.stats.metrics import METRICS as REGISTRY
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


def _edges(values: list[float]) -> np.ndarray:
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
    xe, ye = _edges(xs), _edges(ys)
    fig, axes = new_figure((11.0, 8.5), 2, 2)
    for ax, metric in zip(axes.flat, METRICS, strict=True):
        grid = np.full((len(ys), len(xs)), math.nan)
        for p in result.points:
            grid[ys.index(p.y), xs.index(p.x)] = p.mean[metric]
        finite = np.isfinite(grid)
        mesh = ax.pcolormesh(xs, ys, np.ma.masked_invalid(grid), shading="nearest", cmap="viridis")
        if finite.any():
            fig.colorbar(mesh, ax=ax, label=f"{metric} [{REGISTRY[metric].unit}]")
        for p in result.points:
            i, j = ys.index(p.y), xs.index(p.x)
            if in_window(p, window.release_target, window.damage_limit):
                ax.add_patch(
                    Rectangle(
                        (xe[j], ye[i]), xe[j + 1] - xe[j], ye[i + 1] - ye[i],
                        fill=False, hatch="//", edgecolor="red", linewidth=2.0,
                    )
                )  # fmt: skip
            text = "n/a" if math.isnan(p.mean[metric]) else f"{p.mean[metric]:.3g}"
            ax.text(p.x, p.y, text, ha="center", va="center", fontsize=8, color="black",
                    bbox={"facecolor": "white", "alpha": 0.6, "lw": 0})  # fmt: skip
        if not any(in_window(p, window.release_target, window.damage_limit) for p in result.points):
            ax.text(0.5, 1.0, "no point in the window", transform=ax.transAxes, ha="center",
                    va="bottom", fontsize=8, color="red")  # fmt: skip
        ax.set_xlabel(window.axes[0])
        ax.set_ylabel(window.axes[1])
        ax.set_title(f"{metric}: mean of {window.study.replicates} replicates")
    fig.suptitle(
        f"operating window (hatched): {RELEASE} ≥ {window.release_target:g}, "
        f"{DAMAGE} ≤ {window.damage_limit:g}"
    )
    path = directory / "window.png"
    save(fig, path)
    return path


def _pm(point: Point, metric: str, unit: bool = False) -> str:
    """``mean ± sd`` (and the unit), with the number of runs that gave it when some did not."""
    mean, sd = point.mean[metric], point.sd[metric]
    if math.isnan(mean):
        return "n/a"
    text = f"{mean:.4g} ± {sd:.2g}" if math.isfinite(sd) else f"{mean:.4g}"
    if unit and REGISTRY[metric].unit != "-":
        text += f" {REGISTRY[metric].unit}"
    ok = point.runs - point.failed
    return text if point.count[metric] == ok else f"{text} (n = {point.count[metric]})"


def _setting(result: WindowResult, point: Point) -> str:
    a, b = result.window.axes
    return f"{a} = {point.x:.6g}, {b} = {point.y:.6g}"


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


def report_text(result: WindowResult) -> str:
    """The Markdown report of a window study."""
    window = result.window
    study = window.study
    rt, dl = window.release_target, window.damage_limit
    xs, ys = window.grid()
    a, b = window.axes
    fixed = {k: p.values[0] for k, p in study.parameters.items() if k not in window.axes}  # type: ignore[index]
    lines = [
        "# Operating window",
        "",
        f"Case `{study.case}`; window: {RELEASE} ≥ {rt:g} and {DAMAGE} ≤ {dl:g}.",
        "",
        "## Grid",
        "",
        f"- {a}: {', '.join(f'{v:.6g}' for v in xs)}",
        f"- {b}: {', '.join(f'{v:.6g}' for v in ys)}",
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
        f"| {a} | {b} | " + " | ".join(f"{m} [{REGISTRY[m].unit}]" for m in METRICS) + " | in |",
        "|" + "---|" * (len(METRICS) + 3),
    ]
    for p in result.points:
        mark = "*" if in_window(p, rt, dl) else ""
        cells = " | ".join(_pm(p, m) for m in METRICS)
        lines.append(f"| {p.x:.6g} | {p.y:.6g} | {cells} | {mark} |")
    lines += ["", "## Best setting", ""]
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
    lines += ["", "Files: window.parquet, window.csv, window.png, results.parquet, runs/.", ""]
    return "\n".join(lines)


def write_report(result: WindowResult, directory: Path) -> Path:
    """``DIR/report.md`` (:func:`report_text`)."""
    path = directory / "report.md"
    path.write_text(report_text(result), encoding="utf-8")
    return path
