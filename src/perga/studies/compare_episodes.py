"""The report's sections on a run's episodes, one by one: its impacts against the impact law
(:mod:`perga.stats.impact_law`), its slides along hammer faces against the disc on a face
(:mod:`perga.stats.slide_law`) and its flights between contacts against the flight over the
floor (:mod:`perga.stats.flight_law`): counts, shares, the spread of every statistic's error,
the worst episodes with their regime and a verdict in words."""

from __future__ import annotations

import numpy as np

from perga.stats.flight_law import summarise_flights
from perga.stats.impact_law import summarise
from perga.stats.slide_law import summarise_slides
from perga.studies.compare_rows import Analysis

WORST = 5
"""Episodes listed as the worst of a run."""


def impact_summary(analysis: Analysis) -> dict[str, object] | None:
    """The impacts of one analysed run against the law (:func:`~perga.stats.impact_law.
    summarise`): counts, shares, quantiles of the isolated impacts' velocity error and of every
    statistic's, the worst with their regime, and a verdict in words; None without checked
    impacts."""
    checks = analysis.series.get("impact_checks")
    if not checks:
        return None
    summary = summarise(checks)
    errors = np.array([c.velocity_error for c in summary.isolated])
    quantiles = (
        {q: float(np.quantile(errors, q)) for q in (0.5, 0.9, 0.99, 1.0)} if errors.size else {}
    )
    within = float(np.mean(errors <= 0.01)) if errors.size else None
    verdict = (
        f"{len(summary.isolated) / len(checks):.0%} of {len(checks)} impacts, carrying "
        f"{summary.energy_share_isolated:.0%} of the energy lost in impacts, are isolated"
        + (
            f"; on those the velocity after agrees with the law within 1 % in {within:.1%} "
            f"(median error {quantiles[0.5]:.2e}, worst {quantiles[1.0]:.2e})."
            if within is not None
            else "."
        )
    )
    return {
        "run": analysis.name,
        "statistics": summary.statistics(),
        "impacts": len(checks),
        "isolated": len(summary.isolated),
        "energy_share_isolated": summary.energy_share_isolated,
        "within_1_percent": within,
        "error_quantiles": {str(q): v for q, v in quantiles.items()},
        "worst": [
            {"granule": c.granule, "time": c.time, "regime": c.regime, "error": c.velocity_error}
            for c in summary.worst(WORST)
        ],
        "verdict": verdict,
    }


def slide_summary(analysis: Analysis) -> dict[str, object] | None:
    """The slides of one analysed run against the disc on a face (:func:`~perga.stats.
    slide_law.summarise_slides`): counts, every statistic's median and largest error on the
    face turning with the rotor and off it, the worst with their regime, and a verdict in
    words; None without checked slides."""
    checks = analysis.series.get("slide_checks")
    if not checks:
        return None
    summary = summarise_slides(checks)
    on_face = summary.on_face
    errors = np.array([c.velocity_error for c in on_face])
    within = float(np.mean(errors <= 0.01)) if errors.size else None
    lasted = sum(c.duration for c in checks)
    verdict = (
        f"{len(checks)} slides along a hammer face ({lasted * 1e3:.3g} ms in all), "
        f"{len(on_face)} of them on a face turning with the rotor"
        + (
            f"; on those the velocity at the end agrees with the disc on a face within 1 % in "
            f"{within:.0%} (median error {np.median(errors):.2e}, worst {errors.max():.2e})"
            if within is not None
            else ""
        )
        + f". Not in the model's regime: {summary.others}."
    )
    rest = [c for c in summary.checks if c not in on_face]
    return {
        "run": analysis.name,
        "slides": len(checks),
        "on_face": len(on_face),
        "within_1_percent": within,
        "statistics": summary.statistics(),
        "statistics_off_face": summary.statistics(rest),
        "worst": _episodes(summary.worst(WORST)),
        "verdict": verdict,
    }


def flight_summary(analysis: Analysis) -> dict[str, object] | None:
    """The flights of one analysed run against the flight over the floor
    (:func:`~perga.stats.flight_law.summarise_flights`): counts, every statistic's median and
    largest error over the free flights, the worst, and a verdict in words; None without
    checked flights."""
    checks = analysis.series.get("flight_checks")
    if not checks:
        return None
    summary = summarise_flights(checks)
    errors = np.array([c.velocity_error for c in summary.free])
    within = float(np.mean(errors <= 0.01))
    verdict = (
        f"{len(checks)} flights between contacts with the hammers, {len(summary.free)} free; on "
        f"those the velocity before the next impact agrees with the flight over the floor "
        f"within 1 % in {within:.0%} (median error {np.median(errors):.2e}, worst "
        f"{errors.max():.2e}). Not free: {summary.others}."
    )
    return {
        "run": analysis.name,
        "flights": len(checks),
        "free": len(summary.free),
        "within_1_percent": within,
        "statistics": summary.statistics(),
        "worst": _episodes(summary.worst(WORST)),
        "verdict": verdict,
    }


def _episodes(checks: list) -> list[dict[str, object]]:
    """Slides or flights (their granule, start, duration, regime, velocity error) as plain
    data."""
    return [
        {"granule": c.granule, "time": c.start, "duration": c.duration, "regime": c.regime,
         "error": c.velocity_error}
        for c in checks
    ]  # fmt: skip


def _statistics_table(heading: str, stats: dict[str, dict[str, float]], columns: str) -> list:
    if not stats:
        return []
    keys = list(next(iter(stats.values())))
    lines = [f"| {heading}: error of | {columns} |", "|---" * (len(keys) + 1) + "|"]
    lines += [
        f"| {name} | " + " | ".join(f"{v[k]:.2e}" for k in keys) + " |" for name, v in stats.items()
    ]
    return [*lines, ""]


def impact_section(summaries: list[dict]) -> list[str]:
    """Markdown lines: each run's impacts (:func:`impact_summary`)."""
    lines = ["## Impacts, one by one", ""]
    for s in summaries:
        lines += [f"**{s['run']}**: {s['verdict']}", ""]
        lines += _statistics_table("isolated impacts", s["statistics"], "median | 99th percentile")
        lines += [
            "| worst | granule | time, s | regime | velocity error |",
            "|---|---|---|---|---|",
        ]
        lines += [
            f"| {k + 1} | {w['granule']} | {w['time']:.6g} | {w['regime']} | {w['error']:.3e} |"
            for k, w in enumerate(s["worst"])
        ]
        lines.append("")
    return lines


def slide_section(summaries: list[dict]) -> list[str]:
    """Markdown lines: each run's slides (:func:`slide_summary`)."""
    lines = ["## Slides along hammer faces, one by one", ""]
    for s in summaries:
        lines += [f"**{s['run']}**: {s['verdict']}", ""]
        lines += _statistics_table("on a face turning with the rotor", s["statistics"],
                                   "median | largest")  # fmt: skip
        lines += _statistics_table("the others", s["statistics_off_face"], "median | largest")
        lines += _worst_table(s["worst"])
    return lines


def _worst_table(worst: list[dict]) -> list[str]:
    """Markdown lines: the worst episodes with their start, length and regime."""
    lines = [
        "| worst | granule | start, s | length, ms | regime | velocity error |",
        "|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {k + 1} | {w['granule']} | {w['time']:.6g} | {w['duration'] * 1e3:.3g} | "
        f"{w['regime']} | {w['error']:.3e} |"
        for k, w in enumerate(worst)
    ]
    return [*lines, ""]


def flight_section(summaries: list[dict]) -> list[str]:
    """Markdown lines: each run's flights (:func:`flight_summary`)."""
    lines = ["## Flights between contacts, one by one", ""]
    for s in summaries:
        lines += [f"**{s['run']}**: {s['verdict']}", ""]
        lines += _statistics_table("free flights", s["statistics"], "median | largest")
        lines += _worst_table(s["worst"])
    return lines
