"""The paper-check table as text, Markdown or JSON, and one PNG per claim."""

from __future__ import annotations

import json
import math
import textwrap
from collections.abc import Callable
from pathlib import Path

import numpy as np

from perga.analytic.hammer import contact_velocity_components
from perga.analytic.impact import oblique_impact
from perga.analytic.paper import (
    PaperRadialMotion,
    paper_impulse_law,
    paper_roots,
    paper_speed,
    paper_trajectory,
)
from perga.output.figures import new_figure, save
from perga.studies.paper_check import (
    ClaimRow,
    Params,
    successive_model,
    two_body_efficiency,
    vmax_blade,
    vmax_decaying,
    vmax_from_rest,
)


def format_text(rows: list[ClaimRow]) -> str:
    """A terminal report: one block per claim, the reason wrapped under it."""
    lines = []
    for row in rows:
        lines.append(f"[{row.key}] {row.claim}")
        lines.append(f"    paper:     {row.paper}")
        lines.append(f"    fitted:    {row.fitted.value}  -> reproduces: {row.fitted.verdict}")
        lines.append(
            f"    realistic: {row.realistic.value}  -> reproduces: {row.realistic.verdict}"
        )
        lines += textwrap.wrap(
            row.why, 96, initial_indent="    why: ", subsequent_indent="         "
        )
        lines.append("")
    return "\n".join(lines)


def format_markdown(rows: list[ClaimRow]) -> str:
    """A Markdown table: claim, paper value, model values, reproduces?, why."""
    head = (
        "| claim | paper | model (fitted) | reproduces? | model (realistic) | reproduces? | why |\n"
        "|---|---|---|---|---|---|---|"
    )

    def cell(text: str) -> str:
        return text.replace("|", "\\|")

    body = [
        f"| **{r.key}**: {cell(r.claim)} | {cell(r.paper)} | {cell(r.fitted.value)} | "
        f"{r.fitted.verdict} | {cell(r.realistic.value)} | {r.realistic.verdict} | {cell(r.why)} |"
        for r in rows
    ]
    return "\n".join([head, *body]) + "\n"


def format_json(rows: list[ClaimRow], fitted: Params, realistic: Params) -> str:
    """JSON: the parameter sets and every row with its raw numbers."""

    def params(p: Params) -> dict[str, object]:
        return {
            "omega": p.omega,
            "friction": p.f,
            "restitution": p.e,
            "granule_mass": p.m,
            "hinge_radius": p.R,
            "gravity": p.g,
            "hammers": p.hammers,
            "hammer_mass": p.hammer_mass,
            "strike_distance": p.strike_distance,
        }

    return json.dumps(
        {
            "parameters": {"fitted": params(fitted), "realistic": params(realistic)},
            "claims": [r.as_dict() for r in rows],
        },
        indent=2,
        ensure_ascii=False,
    )


# --- plots -------------------------------------------------------------------------------------

PlotFunction = Callable[["object", Params, Params], None]


def _decay(ax, fit: Params, real: Params) -> None:
    t = np.linspace(0, fit.study.decay_times[1] * 3, 300)
    for p, name in ((fit, "fitted"), (real, "realistic")):
        ax.plot(t * 1e3, p.decaying.displacement(t) / p.study.x0, label=f"C1 = 0 ({name})")
        off = PaperRadialMotion.from_launch_velocity(
            p.omega, p.f, p.study.x0, 0.99 * p.decaying.launch_velocity, p.g
        )
        ax.plot(
            t * 1e3, off.displacement(t) / p.study.x0, "--", label=f"launch speed −1 % ({name})"
        )
    for tq, fq in zip(fit.study.decay_times, fit.study.decay_fractions, strict=True):
        ax.plot([tq * 1e3], [1 - fq], "kv", ms=8)
    ax.set(xlabel="t, ms", ylabel="x(t)/x0", title="Eq. (27): decay needs C1 = 0 exactly")
    ax.set_ylim(-0.2, 1.5)


def _radius(ax, fit: Params, real: Params) -> None:
    t = np.linspace(0, fit.study.decay_times[1], 300)
    for p, name in ((fit, "fitted"), (real, "realistic")):
        ax.plot(t * 1e3, (p.R + p.decaying.displacement(t)) * 1e3, label=f"r = R + x ({name})")
    ax.axhline(fit.study.final_radius * 1e3, color="k", ls=":", label="paper: < 20 mm")
    ax.set(xlabel="t, ms", ylabel="r, mm", title="Eq. (29): r(t) on the decaying branch")


def _efficiency(ax, fit: Params, real: Params) -> None:
    masses = np.geomspace(1e-4, 0.3, 200)
    s = fit.study
    for p, name in ((fit, "fitted"), (real, "realistic")):
        eta = [two_body_efficiency(p.m, M, p.e) for M in masses]
        ax.loglog(masses * 1e3, eta, label=f"(1+e)²mM/(M+m)², m = {p.m * 1e3:.2f} g ({name})")
    quoted = np.array(s.efficiency_values)
    ax.loglog(np.array(s.efficiency_hammer_masses) * 1e3, quoted, "ko", label="paper, as per cent")
    ax.loglog(
        np.array(s.efficiency_hammer_masses) * 1e3,
        100 * quoted,
        "ks",
        mfc="none",
        label="paper, read as fractions",
    )
    ax.set(
        xlabel="hammer mass M, g", ylabel="efficiency η", title="Fig. 4a: efficiency vs hammer mass"
    )


def _loss(ax, fit: Params, real: Params) -> None:
    e = np.linspace(0, 1, 101)
    ax.plot(e, 1 - e**2, label="normal impact, hammer frame: 1 − e²")
    for angle in (30, 45, 60):
        a = math.radians(angle)
        loss = [
            (lambda r: r.dissipated / r.energy_before)(
                oblique_impact(fit.m, 0.0, -math.cos(a), math.sin(a), ei, fit.f, shape="point")
            )
            for ei in e
        ]
        ax.plot(e, loss, label=f"{angle}° incidence, f = {fit.f}")
    ax.axhline(fit.study.loss_per_impact, color="k", ls=":", label="paper: > 20 %")
    ax.axvline(fit.e, color="grey", lw=0.5)
    ax.set(xlabel="restitution e", ylabel="fraction of KE lost", title="Energy lost in one impact")


def _successive_plot(ax, fit: Params, real: Params) -> None:
    model = successive_model(fit)
    radii = np.array(fit.study.successive_radii)
    for i in range(len(radii)):
        t0 = model.impact_times[i]
        t = np.linspace(t0, t0 + fit.impact_interval, 100)
        x, _, phi = model.segment(i, t)
        ax.plot(
            (fit.R + x) * np.cos(phi) * 1e3,
            (fit.R + x) * np.sin(phi) * 1e3,
            label=f"impact {i + 1}",
        )
    ax.set_aspect("equal")
    ax.set(
        xlabel="X, mm",
        ylabel="Y, mm",
        title=f"Fig. 5a: eq. (61)-(64), β = {model.beta:.1f}/s fitted (R = 0)",
    )


def _energy_plot(ax, fit: Params, real: Params) -> None:
    n = len(fit.study.successive_radii)
    idx = np.arange(1, n + 1)
    for p, name, shift in ((fit, "fitted", -0.2), (real, "realistic", 0.2)):
        energy = successive_model(p).energy_after_impact(p.m)
        ax.bar(idx + shift, energy / energy[0], width=0.4, label=f"eq. (65), {name}")
    ax.plot(
        idx, np.concatenate(([1.0], fit.e ** (2 * np.arange(1, n)))), "ko-", label="e² per impact"
    )
    ax.axhline(
        1 - fit.study.successive_loss_by_third, color="k", ls=":", label="paper: < 30 % left"
    )
    ax.set(
        xlabel="impact", ylabel="energy / energy after impact 1", title="Fig. 5b: energy per impact"
    )


def _vmax(axis: int):
    def plot(ax, fit: Params, real: Params) -> None:
        omegas = np.linspace(0.5, 3.0, 26) * fit.omega
        fs = np.linspace(0.05, 0.8, 26)
        for fn, style in ((vmax_decaying, "-"), (vmax_from_rest, "--"), (vmax_blade, ":")):
            if axis == 0:
                ax.plot(
                    omegas,
                    [fn(fit, w, fit.f) for w in omegas],
                    style,
                    label=fn.__doc__.split(",")[0],
                )
            else:
                ax.plot(
                    fs, [fn(fit, fit.omega, f) for f in fs], style, label=fn.__doc__.split(",")[0]
                )
        ax.set(
            xlabel="ω, rad/s" if axis == 0 else "f",
            ylabel="v_max, m/s",
            title="Fig. 3: v_max against " + ("ω" if axis == 0 else "f") + " (fitted set)",
        )

    return plot


def _xyr(ax, fit: Params, real: Params) -> None:
    t = np.linspace(0, fit.study.decay_times[1], 300)
    X, Y = paper_trajectory(fit.decaying, t, fit.R)
    ax.plot(t * 1e3, X * 1e3, label="X(t)")
    ax.plot(t * 1e3, Y * 1e3, label="Y(t)")
    ax.plot(t * 1e3, np.hypot(X, Y) * 1e3, "k", label="r(t): never oscillates")
    lam1, lam2 = paper_roots(fit.omega, fit.f)
    ax.set(
        xlabel="t, ms",
        ylabel="mm",
        title=f"Fig. 4b: X, Y turn with the frame; roots λ = {lam1:+.1f}, {lam2:+.1f} 1/s are real",
    )


def _eq6(ax, fit: Params, real: Params) -> None:
    v = np.linspace(-3, 3, 100)
    x, w, f, g = fit.study.x0, fit.omega, fit.f, fit.g
    ax.plot(v, w**2 * x - 2 * w * v - f * g, label="(1) as written")
    ax.plot(v, 2 * f * w * v - w**2 * x, label="(6) as written")
    ax.plot(v, w**2 * x - 2 * f * w * v - f * g * np.sign(v), label="consistent (leading face)")
    ax.set(xlabel="ẋ, m/s", ylabel="ẍ at x = x0, m/s²", title="Eq. (1) vs (6)")


def _eq8(ax, fit: Params, real: Params) -> None:
    from perga.analytic.sliding import BladeSlide

    tip = 0.1
    for face, v0 in (("leading", 0.5), ("trailing", -2.0)):
        r = BladeSlide(
            fit.omega, fit.f, fit.f, "corotating", face, gravity=fit.g, tip=tip
        ).integrate(0.05, v0, 1.0)
        ax.plot(r.t * 1e3, r.x * 1e3, label=f"{face} face, ẋ(0) = {v0} m/s: ends '{r.event}'")
    ax.set(
        xlabel="t, ms",
        ylabel="x, mm",
        title="Consistent model: outward (−fg) and inward (+fg = eq. 8)",
    )


def _eq14(ax, fit: Params, real: Params) -> None:
    motion = fit.decaying
    t = np.linspace(0, 0.05, 200)
    ax.semilogy(t * 1e3, np.abs(motion.residual(t)) + 1e-300, label="|ẍ + 2fωẋ − ω²x − fg|")
    ax.set(
        xlabel="t, ms", ylabel="residual, m/s²", title="Eq. (24)/(27) solve eq. (8) to round-off"
    )


def _eq38(ax, fit: Params, real: Params) -> None:
    t = np.linspace(0, 0.05, 200)
    motion = real.decaying
    ax.plot(t * 1e3, paper_speed(motion, t, real.R), label="(40) with R")
    ax.plot(t * 1e3, paper_speed(motion, t, real.R, printed=True), "--", label="(38) as printed")
    ax.set(
        xlabel="t, ms",
        ylabel="V, m/s",
        title=f"Eq. (38) drops R (realistic R = {real.R * 1e3:g} mm)",
    )


def _eq54(ax, fit: Params, real: Params) -> None:
    alpha = np.linspace(-0.6, 0.6, 200)
    for normal in ("paper", "face"):
        vn, _ = contact_velocity_components(
            real.R, real.strike_distance, 0.0, alpha, real.omega, 0.0, normal=normal
        )
        ax.plot(np.degrees(alpha), vn, label=f"normal = {normal}")
    ax.set(
        xlabel="hammer angle α, deg", ylabel="v_Kn, m/s", title="Eq. (53)-(54): normal impact speed"
    )


def _eq57(ax, fit: Params, real: Params) -> None:
    masses = np.geomspace(1e-4, 0.3, 100)
    p = real
    ax.semilogx(masses * 1e3, np.full_like(masses, 1 + p.e), label="(57): fixed wall, (1+e)")
    ax.semilogx(masses * 1e3, (1 + p.e) * masses / (masses + p.m), label="two-body (1+e)M/(M+m)")
    ax.set(
        xlabel="hammer mass, g",
        ylabel="u_granule / V_hammer",
        title="Eq. (57) ignores the hammer mass",
    )


def _eq59(ax, fit: Params, real: Params) -> None:
    vt = np.linspace(0.01, 5, 200)
    p = fit
    ax.plot(vt, [paper_impulse_law(p.m, -5.0, v, p.e, p.f)[1] for v in vt], label="(59) as printed")
    ax.plot(
        vt,
        [
            oblique_impact(p.m, 0.0, -5.0, v, p.e, p.f, shape="point").tangential_velocity
            for v in vt
        ],
        "--",
        label="Coulomb with sticking cap",
    )
    ax.axhline(0, color="k", lw=0.5)
    ax.set(
        xlabel="v_t before, m/s (v_n = −5 m/s)",
        ylabel="v_t after, m/s",
        title="Eq. (59) reverses slow slip",
    )


def _trajectory(ax, fit: Params, real: Params) -> None:
    t = np.linspace(0, 0.1, 400)
    X, Y = paper_trajectory(fit.decaying, t, fit.R)
    sc = ax.scatter(X * 1e3, Y * 1e3, c=t * 1e3, s=4)
    ax.figure.colorbar(sc, ax=ax, label="t, ms")
    ax.set_aspect("equal")
    ax.set(xlabel="X, mm", ylabel="Y, mm", title="Fig. 2b: eq. (30)-(31), fitted set")


PLOTS: dict[str, PlotFunction] = {
    "decay-0.02s": _decay,
    "decay-0.05s": _trajectory,
    "radius-0.05s": _radius,
    "efficiency-5g": _efficiency,
    "efficiency-100g": _efficiency,
    "efficiency-200g": _efficiency,
    "efficiency-optimum": _efficiency,
    "loss-per-impact": _loss,
    "successive-radii": _successive_plot,
    "energy-by-third": _energy_plot,
    "vmax-omega": _vmax(0),
    "vmax-friction": _vmax(1),
    "damped-oscillation": _xyr,
    "eq1-6-7": _eq6,
    "eq8": _eq8,
    "eq14-24": _eq14,
    "eq38-40": _eq38,
    "eq53-54": _eq54,
    "eq57": _eq57,
    "eq59": _eq59,
}


def write_plots(
    rows: list[ClaimRow], fitted: Params, realistic: Params, directory: Path
) -> list[Path]:
    """One PNG per row (``<key>.png``) in ``directory``; returns the paths written."""
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for row in rows:
        fig, ax = new_figure((7, 4.5), layout="constrained")
        PLOTS[row.key](ax, fitted, realistic)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7)
        fig.suptitle(
            f"{row.key}: fitted {row.fitted.verdict}, realistic {row.realistic.verdict}", fontsize=9
        )
        path = directory / f"{row.key}.png"
        save(fig, path)
        written.append(path)
    return written
