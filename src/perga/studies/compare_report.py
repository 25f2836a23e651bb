"""The ``perga compare`` report: Markdown with PNG figures (matplotlib, no pyplot), the same as
one self-contained HTML page, and JSON.

Figures follow the paper's numbering: Fig. 2 (trajectory in the fixed frame, time-coloured),
Fig. 3 (v_max over ω and f), Fig. 4a (efficiency against hammer mass), Fig. 4b (X, Y, r against
time), Fig. 5 (energy after successive impacts), and a histogram of impact speeds. Each draws
the simulation with the analytical curves over it; a figure whose runs are absent is skipped.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

import numpy as np

from perga.analytic.impact import impact_efficiencies
from perga.output.figures import new_figure, save
from perga.output.html_report import write_markdown_report
from perga.stats.impact_law import ISOLATED
from perga.stats.slide_law import ON_FACE
from perga.studies.compare_episodes import (
    flight_section,
    flight_summary,
    impact_section,
    impact_summary,
    slide_section,
    slide_summary,
)
from perga.studies.compare_rows import Analysis, Row, Unavailable
from perga.studies.paper_check import Params

Figure = Callable[[list[Analysis], Params | None, Path], bool]
FIGURES: dict[str, tuple[str, Figure]] = {}


class NotDrawn(Exception):  # noqa: N818 (not an error: a figure the runs cannot give, and why)
    """A figure whose runs are there but cannot give it; the message says why."""


def figure(key: str, title: str) -> Callable[[Figure], Figure]:
    """Register a figure writer under the paper's figure key."""

    def register(fn: Figure) -> Figure:
        FIGURES[key] = (title, fn)
        return fn

    return register


def _of(analyses: list[Analysis], kind: str) -> list[Analysis]:
    return [a for a in analyses if a.kind == kind]


def _trajectory_panels(analyses: list[Analysis], width: float, height: float):
    """A figure with one panel (width × height inches) per trajectory run (at most two), its
    axes and the runs; None without such runs."""
    panels = [a for a in analyses if a.kind == "decaying" or "flight_t" in a.series][:2]
    if not panels:
        return None
    fig, axes = new_figure((width * len(panels), height), 1, len(panels), squeeze=False)
    return fig, axes[0], panels


@figure("2", "Fig. 2: trajectory in the fixed frame, coloured by time")
def fig2(analyses: list[Analysis], _paper: Params | None, path: Path) -> bool:
    drawing = _trajectory_panels(analyses, 6, 5.2)
    if drawing is None:
        return False
    fig, axes, panels = drawing
    for ax, a in zip(axes, panels, strict=True):
        s = a.series
        if a.kind == "decaying":
            t, theta = s["t"], s["theta"]
            points = s["xy"]
            lines = {
                "closed form (BladeSlide)": s["exact"],
                "paper eq. (30)-(32), C1 = 0": s["paper"],
            }
            for label, x in lines.items():
                ax.plot(x * np.cos(theta), x * np.sin(theta), lw=1, label=label)
        else:
            t, points = s["t"], np.column_stack((s["x"], s["y"]))
            ax.plot(*s["flight"].T, "k--", lw=1, label="free flight (closed form)")
            r, phi = s["paper_r"], s["paper_phi"]
            ax.plot(r * np.cos(phi), r * np.sin(phi), lw=1, label="paper eq. (30)-(32), C1 = 0")
        sc = ax.scatter(points[:, 0], points[:, 1], c=t, s=6, cmap="viridis", label="simulated")
        fig.colorbar(sc, ax=ax, label="t, s")
        ax.set(title=a.name, xlabel="X, m", ylabel="Y, m", aspect="equal")
        ax.legend(fontsize=7)
    return save(fig, path)


@figure("3", "Fig. 3: v_max over ω and f")
def fig3(analyses: list[Analysis], _paper: Params | None, path: Path) -> bool:
    blade = _of(analyses, "blade")
    if not blade or not len(blade[0].series["points"]):
        return False
    pts = blade[0].series["points"]
    omegas, fs = np.unique(pts[:, 0]), np.unique(pts[:, 1])
    if omegas.size < 2 or fs.size < 2:
        raise NotDrawn(
            f"a map over ω and f needs blade runs at 2 or more of each (these give {omegas.size} "
            f"ω × {fs.size} f); `perga compare --paper` runs the grid"
        )
    grids = {}
    for col, label in ((2, "simulated"), (3, "BladeSlide (consistent)"), (4, "paper eq. (40)")):
        grid = np.full((fs.size, omegas.size), np.nan)
        for row in pts:
            grid[np.searchsorted(fs, row[1]), np.searchsorted(omegas, row[0])] = row[col]
        grids[label] = grid
    fig, axes = new_figure((15, 4.3), 1, 3)
    for ax, (label, grid) in zip(axes, grids.items(), strict=True):
        if np.all(np.isnan(grid)):
            ax.set_axis_off()
            continue
        cs = ax.contourf(omegas, fs, grid, levels=12, cmap="magma")
        fig.colorbar(cs, ax=ax, label="v_max, m/s")
        ax.plot(*np.meshgrid(omegas, fs), "w.", ms=3)
        ax.set(title=label, xlabel="ω, rad/s", ylabel="f")
    err = np.nanmax(np.abs(grids["simulated"] / grids["BladeSlide (consistent)"] - 1))
    fig.suptitle(f"simulated vs consistent model: largest relative difference {err:.1e}")
    return save(fig, path)


@figure("4a", "Fig. 4a: efficiency against hammer mass")
def fig4a(analyses: list[Analysis], paper: Params | None, path: Path) -> bool:
    two_body = [a for a in _of(analyses, "two-body") if len(a.series["points"])]
    hinged = [a for a in analyses if a.kind == "hinged" and a.name.startswith("hinged-M")]
    if not two_body and not hinged:
        return False
    fig, ax = new_figure((7, 5))
    masses = np.geomspace(0.004, 0.25, 100)
    if two_body:
        pts = two_body[0].series["points"]
        for m in np.unique(pts[:, 1]):
            sel = pts[pts[:, 1] == m]
            label = f"simulated two-body, m = {m * 1e3:.3g} g"
            ax.plot(sel[:, 0] * 1e3, sel[:, 2], "o", label=label)
            e = float(two_body[0].series["restitution"])
            eta = [impact_efficiencies(m, M, e).transfer for M in masses]
            ax.plot(masses * 1e3, eta, "-", lw=1, label=f"(1+e)²mM/(M+m)², m = {m * 1e3:.3g} g")
    if hinged:
        rows = [_first(a, "hinged_impact") for a in hinged]
        hm = [float(a.name.removeprefix("hinged-M").removesuffix("g")) for a in hinged]
        ax.plot(hm, [r.simulated for r in rows], "s", mfc="none", label="simulated hinged, 0.16 g")
        ax.plot(hm, [r.analytic for r in rows], "k+", label="hinged_impact (analytic)")
    if paper is not None:
        s = paper.study
        quoted = np.array(s.efficiency_values)
        ax.plot(np.array(s.efficiency_hammer_masses) * 1e3, quoted, "r*", ms=10, label="paper (%)")
        ax.plot(
            np.array(s.efficiency_hammer_masses) * 1e3,
            100 * quoted,
            "m*",
            ms=10,
            label="paper read as fractions",
        )
    ax.set(xscale="log", yscale="log", xlabel="hammer mass M, g", ylabel="transfer efficiency η")
    ax.legend(fontsize=7)
    return save(fig, path)


def _first(a: Analysis, model: str) -> Row:
    return next(r for r in a.rows if r.model.startswith(model))


@figure("4b", "Fig. 4b: X, Y and r against time")
def fig4b(analyses: list[Analysis], _paper: Params | None, path: Path) -> bool:
    drawing = _trajectory_panels(analyses, 6.5, 4.5)
    if drawing is None:
        return False
    fig, axes, panels = drawing
    for ax, a in zip(axes, panels, strict=True):
        s = a.series
        if a.kind == "decaying":
            t, xy = s["t"], s["xy"]
            ax.plot(t, s["exact"], "k--", lw=1, label="x: closed form")
            ax.plot(t, s["paper"], "r:", lw=1.5, label="x: paper eq. (27), C1 = 0")
            ax.plot(t, s["x"], lw=1, alpha=0.7, label="x along the blade: simulated")
        else:
            t, xy = s["t"], np.column_stack((s["x"], s["y"]))
            ax.plot(s["flight_t"], s["flight_r"], "k--", lw=1, label="r: free flight")
            ax.plot(s["paper_t"], s["paper_r"], "r:", lw=1.5, label="r: paper eq. (29), C1 = 0")
        ax.plot(t, xy[:, 0], lw=1, label="X simulated")
        ax.plot(t, xy[:, 1], lw=1, label="Y simulated")
        ax.plot(t, np.hypot(xy[:, 0], xy[:, 1]), lw=2, alpha=0.6, label="r simulated")
        ax.set(title=a.name, xlabel="t, s", ylabel="m")
        ax.legend(fontsize=7)
    return save(fig, path)


@figure("5", "Fig. 5: energy after successive impacts")
def fig5(analyses: list[Analysis], _paper: Params | None, path: Path) -> bool:
    runs = [a for a in analyses if "energies" in a.series]
    if not runs:
        return False
    a = runs[0]
    en = a.series["energies"]
    n = np.arange(1, len(en.lab) + 1)
    fig, ax = new_figure((7, 4.5))
    ax.plot(n, en.lab_fraction, "o-", label="simulated: granule KE (lab) after impact")
    ax.plot(n, en.relative_fraction, "s-", label="simulated: ½μv_n'² (hammer frame)")
    ax.plot(n, [1, *a.series["paper_e2i"]], "r^--", label="paper: e^(2(i−1))")
    eq65 = a.series["paper_eq65"][: len(n)]
    ax.plot(np.arange(1, len(eq65) + 1), eq65, "mv--", label="paper eq. (65), fitted radii")
    ax.set(
        title=a.name,
        xlabel="impact",
        ylabel="energy / energy after impact 1",
        yscale="log",
        xticks=n,
    )
    ax.legend(fontsize=7)
    return save(fig, path)


@figure("hist", "Impact speeds")
def histogram(analyses: list[Analysis], _paper: Params | None, path: Path) -> bool:
    speeds = [s.approach_speed for a in analyses for s in a.series.get("impacts", [])]
    if not speeds:
        return False
    fig, ax = new_figure((6.5, 4))
    ax.hist(speeds, bins=min(30, max(5, len(speeds) // 2)))
    ax.set(xlabel="normal approach speed, m/s", ylabel="impacts", title=f"{len(speeds)} impacts")
    return save(fig, path)


@figure("slides", "Slides along hammer faces against the disc on a face")
def slide_errors(analyses: list[Analysis], _paper: Params | None, path: Path) -> bool:
    checks = [c for a in analyses for c in a.series.get("slide_checks", [])]
    drawn = [c for c in checks if np.isfinite(c.velocity_error)]
    if not drawn:
        return False
    fig, ax = new_figure((6.5, 4))
    for on, label, marker in ((True, ON_FACE, "o"), (False, "not in the model's regime", "x")):
        chosen = [c for c in drawn if (c.regime == ON_FACE) == on]
        if chosen:
            ax.scatter(
                [c.duration * 1e3 for c in chosen],
                [max(c.velocity_error, 1e-6) for c in chosen],
                marker=marker,
                label=label,
            )
    ax.axhline(0.01, color="k", lw=0.8, ls="--", label="1 %")
    ax.set(
        yscale="log",
        xlabel="length of the slide, ms",
        ylabel="|v − v_model| / |v_model| at the end",
        title=f"{len(drawn)} slides",
    )
    ax.legend(fontsize=7)
    return save(fig, path)  # fmt: skip


@figure("impacts", "Impacts against the impact law with friction")
def impact_errors(analyses: list[Analysis], _paper: Params | None, path: Path) -> bool:
    checks = [c for a in analyses for c in a.series.get("impact_checks", [])]
    errors = np.array([c.velocity_error for c in checks])
    isolated = np.array([c.regime == ISOLATED for c in checks], dtype=bool)
    finite = np.isfinite(errors) & (errors > 0)
    if not finite.any():
        return False
    fig, ax = new_figure((6.5, 4))
    bins = np.logspace(np.log10(errors[finite].min()), np.log10(errors[finite].max()), 40)
    for mask, label in ((isolated, "isolated"), (~isolated, "not isolated")):
        if (mask & finite).any():
            ax.hist(errors[mask & finite], bins=bins, alpha=0.6, label=label)
    ax.axvline(0.01, color="k", lw=0.8, ls="--", label="1 %")
    ax.set(xscale="log", xlabel="|v′ − v′_law| / |v′_law|", ylabel="impacts",
           title=f"velocity after, {finite.sum()} impacts")  # fmt: skip
    ax.legend(fontsize=7)
    return save(fig, path)


# --- the report ---------------------------------------------------------------------------------


def _number(x: float) -> str:
    return "n/a" if not math.isfinite(x) else f"{x:.5g}"


def _table(rows: list[Row]) -> str:
    head = (
        "| run | quantity | simulated | analytic | model | error | tolerance | agrees | reason |\n"
        "|---|---|---|---|---|---|---|---|---|"
    )
    body = [
        f"| {r.run} | {r.quantity} | {_number(r.simulated)} | {_number(r.analytic)} | {r.model} "
        f"| {r.error:+.2e} | {'—' if r.tolerance is None else f'{r.tolerance:.0%}'} | "
        f"{ {True: 'yes', False: '**NO**', None: 'differs'}[r.agrees] } | {r.reason} |"
        for r in rows
    ]
    return "\n".join([head, *body]) + "\n"


def _shown_above(rows: list[Row], shown: set[str]) -> str:
    """A line naming how many of ``rows`` are in the figures' sections above (not repeated)."""
    above = sum(r.figure in shown for r in rows)
    return f"\n{above} more in the figures' sections above.\n" if above else ""


def write_report(
    analyses: list[Analysis], out: Path, paper: Params | None = None, command: str = ""
) -> dict[str, object]:
    """Write OUT/report.md, report.html, report.json and figures/*.png; returns the JSON data."""
    figures_dir = out / "figures"
    figures_dir.mkdir(parents=True, exist_ok=True)
    rows = [r for a in analyses for r in a.rows]
    written = {}
    unavailable = [u for a in analyses for u in a.unavailable]
    for key, (title, fn) in FIGURES.items():
        path = figures_dir / f"fig{key}.png"
        try:
            if fn(analyses, paper, path):
                written[key] = (title, path)
        except NotDrawn as reason:
            unavailable.append(Unavailable("(all runs)", title, str(reason)))
    agree = [r for r in rows if r.tolerance is not None]
    differ = [r for r in rows if r.tolerance is None]
    worst = max((abs(r.error) for r in agree), default=math.nan)
    lines = [
        "# perga compare: simulation against the analytical model",
        "",
        f"Command: `{command}`" if command else "",
        "",
        f"{len(analyses)} analyses, {len(rows)} rows: "
        + (
            f"{sum(bool(r.agrees) for r in agree)} of {len(agree)} rows agree where the physics "
            f"is the same (largest |error| {worst:.2e}, tolerance 1 %); "
            if agree
            else "no row compares the same physics; "
        )
        + f"{len(differ)} rows compare regimes that differ; "
        f"{len(unavailable)} statistics could not be computed (the last section says why).",
        "",
    ]
    for key, (title, path) in written.items():
        lines += [f"## {title}", "", f"![{title}](figures/{path.name})", ""]
        section = [r for r in rows if r.figure == key]
        if section:
            lines.append(_table(section))
    impacts = [s for a in analyses if (s := impact_summary(a)) is not None]
    if impacts:
        lines += impact_section(impacts)
    slides = [s for a in analyses if (s := slide_summary(a)) is not None]
    if slides:
        lines += slide_section(slides)
    flights = [s for a in analyses if (s := flight_summary(a)) is not None]
    if flights:
        lines += flight_section(flights)
    shown = set(written)
    for heading, group in (
        ("Agreement where the physics is the same", agree),
        ("Regimes that cannot match, and by how much", differ),
    ):
        rest = [r for r in group if r.figure not in shown]
        lines += [f"## {heading}", "", (_table(rest) if rest else "") + _shown_above(group, shown)]
    if unavailable:
        lines += ["## Not computed, and why", "", "| run | statistic | reason |", "|---|---|---|"]
        lines += [f"| {u.run} | {u.statistic} | {u.reason} |" for u in unavailable]
        lines.append("")
    write_markdown_report(out / "report.md", "\n".join(lines))
    data = {
        "command": command,
        "figures": {k: str(p.relative_to(out)) for k, (_, p) in written.items()},
        "analyses": [{"name": a.name, "kind": a.kind} for a in analyses],
        "rows": [r.as_dict() for r in rows],
        "unavailable": [asdict(u) for u in unavailable],
        "impacts": impacts,
        "slides": slides,
        "flights": flights,
        "largest_agreement_error": worst if agree else None,
    }
    (out / "report.json").write_text(json.dumps(data, indent=2, default=float) + "\n")
    return data
