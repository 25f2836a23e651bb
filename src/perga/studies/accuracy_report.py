"""Output of ``perga accuracy``: the table (CSV and Markdown, with the Markdown as one
self-contained HTML page), the recommended settings, and one log-log work-precision plot per
reference (matplotlib)."""

from __future__ import annotations

import csv
import itertools
import math
from collections.abc import Sequence
from dataclasses import asdict, fields
from pathlib import Path

from perga.contact.laws import LAWS
from perga.output.figures import new_figure, save
from perga.output.html_report import write_markdown_report
from perga.studies.accuracy import LEVELS, REFERENCES, Row, StudyResult, recommend

ERROR_FLOOR = 1e-16
"""Errors below this (exact to rounding: rigid restitution) are drawn at this value."""

STYLES = ("o-", "s--", "^:", "d-.", "v-")
"""Line styles of the families, rigid first, then each contact law in the registry's order
(again from the first past the last)."""


def write_csv(rows: Sequence[Row], path: Path) -> None:
    """All rows, one per (reference, setting), columns as :class:`Row` (SI units)."""
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=[fl.name for fl in fields(Row)])
        writer.writeheader()
        for row in rows:
            writer.writerow(asdict(row))


def _g(value: float, digits: int = 3) -> str:
    return "–" if not math.isfinite(value) else f"{value:.{digits}g}"


def _cost(row: Row) -> str:
    return _g(row.wall_per_sim) if row.status == "ok" else row.status.split(":")[0]


def markdown_table(rows: Sequence[Row]) -> str:
    """One Markdown table per reference (setting, steps, error, wall s per simulated s) under
    its figure (``REFERENCE.png``, :func:`plot_reference`)."""
    out = []
    for reference in dict.fromkeys(r.reference for r in rows):
        out += [
            f"### {reference}: {REFERENCES.get(reference, '')}",
            "",
            f"![{reference}]({reference}.png)",
            "",
            "| model | setting | granule dt, s | Pymunk dt, s | dt/t_c | error | "
            "wall s per simulated s | steps |",
            "|---|---|---:|---:|---:|---:|---:|---:|",
        ]
        for r in (r for r in rows if r.reference == reference):
            ratio = r.dt / r.t_c if math.isfinite(r.t_c) else math.nan
            out.append(
                f"| {r.model} | {r.setting} | {_g(r.dt)} | {_g(r.machine_dt)} | {_g(ratio)} | "
                f"{_g(r.error)} | {_cost(r)} | {r.steps} |"
            )
        out.append("")
    return "\n".join(out)


def _level(level: float) -> str:
    return f"{100 * level:g} %"


def recommended_table(rows: Sequence[Row], levels: Sequence[float] = LEVELS) -> str:
    """Markdown: for each reference and level the cheapest setting reaching it, or 'not
    reached' (with the smallest error any setting reached)."""
    out = [
        "| reference | error ≤ | cheapest setting | error | wall s per simulated s |",
        "|---|---:|---|---:|---:|",
    ]
    best_error = {
        ref: min(
            (r.error for r in rows if r.reference == ref and math.isfinite(r.error)),
            default=math.nan,
        )
        for ref in dict.fromkeys(r.reference for r in rows)
    }
    for item in recommend(rows, levels):
        ref, level, row = item["reference"], item["level"], item["row"]
        if row is None:
            out.append(
                f"| {ref} | {_level(level)} | not reached (best error {_g(best_error[ref])}) "
                "| – | – |"
            )
        else:
            out.append(
                f"| {ref} | {_level(level)} | {row.setting} | {_g(row.error)} | "
                f"{_g(row.wall_per_sim)} |"
            )
    return "\n".join(out) + "\n"


def markdown_report(result: StudyResult) -> str:
    """The whole report: run facts, recommended settings, the table."""
    return "\n".join(
        [
            "# perga accuracy",
            "",
            f"Study wall time {result.wall:.0f} s; load average {result.load[0]:.2f} at the "
            f"start, {result.load[1]:.2f} at the end. Wall times are medians of up to 3 runs "
            "(noisy, shared machine); errors are deterministic.",
            "",
            "## Recommended settings",
            "",
            recommended_table(result.rows),
            "## Table",
            "",
            markdown_table(result.rows),
        ]
    )


def plot_reference(rows: Sequence[Row], reference: str, path: Path) -> None:
    """Log-log error against wall time per simulated second, one line per family."""
    fig, ax = new_figure((7.5, 5.0))
    chosen = [r for r in rows if r.reference == reference and r.status == "ok"]
    styles = dict(zip(("rigid", *LAWS), itertools.cycle(STYLES)))
    for family in dict.fromkeys(r.family for r in chosen):
        line = sorted((r for r in chosen if r.family == family), key=lambda r: r.wall_per_sim)
        ax.plot(
            [r.wall_per_sim for r in line],
            [max(r.error, ERROR_FLOOR) for r in line],
            styles[line[0].model],
            label=family,
            markersize=4,
        )
    for level in LEVELS:
        ax.axhline(level, color="0.8", linewidth=0.8, zorder=0)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time per simulated second (s/s)")
    ax.set_ylabel("error")
    ax.set_title(REFERENCES.get(reference, reference), fontsize=10)
    ax.legend(fontsize=7, loc="best")
    ax.grid(True, which="major", alpha=0.3)
    save(fig, path)


def write_outputs(result: StudyResult, directory: Path) -> list[Path]:
    """accuracy.csv, one PNG per reference, accuracy.md and accuracy.html into ``directory``."""
    directory.mkdir(parents=True, exist_ok=True)
    paths = [directory / "accuracy.csv"]
    write_csv(result.rows, paths[0])
    for reference in dict.fromkeys(r.reference for r in result.rows):
        path = directory / f"{reference}.png"
        plot_reference(result.rows, reference, path)
        paths.append(path)
    report = directory / "accuracy.md"
    return [*paths, report, write_markdown_report(report, markdown_report(result))]
