"""``perga compare``: recorded runs against the analytical model, row by row.

Every comparison is a :class:`Row`: a statistic of a run (:mod:`perga.stats`), the analytical
value it is compared with, the model that value comes from, the relative error and either a
tolerance (the physics is the same: the row must agree) or none (the regimes differ: the row
says by how much and why). Runs are recognised by their case:

- ``sliding``: one sliding point on a welded radial blade over a co-rotating floor. Launched
  inward on the trailing face it is the paper's eq. (8) (``paper-decaying-branch.toml``);
  outward on the leading face it is the blade-exit scene of Fig. 3 (``blade-exit.toml``).
- ``two-body``: a free hammer strikes a granule (``two-body-impact.toml``, Fig. 4a).
- ``hinged``: hinged hammers strike one granule, which then flies over a stationary floor
  (``single-granule.toml``, ``four-impacts.toml``, ``successive-impacts.toml``).
- anything else: impact statistics only (restitution, speeds).

:mod:`perga.studies.paper_runs` runs the bundled paper cases and sweeps;
:mod:`perga.studies.compare_report` writes the report.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Literal

import numpy as np

from perga.analytic.impact import impact_efficiencies
from perga.analytic.paper import PaperRadialMotion, paper_cumulative_loss, paper_roots
from perga.analytic.sliding import BladeSlide, LinearSlide
from perga.stats.energy import all_impacts, hinged_prediction, successive_energies
from perga.stats.sweeps import blade_exit, blade_tip, efficiency_point
from perga.stats.tables import Run
from perga.stats.trajectory import amplitude_left, blade_frame, fit_exponential, free_flight
from perga.studies.compare_any import (
    analyse_other,
    contact_duration_rows,
    flight_rows,
    impact_law_rows,
    slide_rows,
)
from perga.studies.compare_rows import AGREEMENT, Analysis, Row, missing_impacts
from perga.studies.paper_check import Params, successive_model, vmax_decaying

Kind = Literal["sliding", "two-body", "hinged", "other"]


# --- recognising a run -----------------------------------------------------------------------


def run_kind(run: Run) -> Kind:
    """What kind of scene a run is (module docstring)."""
    case = run.case
    floor = case.effects.floor_friction
    if case.hammers.mount == "free":
        return "two-body"
    if (
        case.hammers.mount == "welded"
        and case.hammers.count == 1
        and case.hammers.hinge_radius == 0
        and not case.granules.rolls
        and floor is not None
        and floor.floor == "corotating"
        and len(run.track(0)["time"])
    ):
        return "sliding"
    if case.hammers.mount == "hinged" and case.granules.count == 1:
        return "hinged"
    return "other"


def _slide(run: Run) -> tuple[BladeSlide, float, float, np.ndarray, np.ndarray]:
    """The blade model of a sliding run: (BladeSlide, x0, u0, t, x along the blade)."""
    case, track = run.case, run.track(0)
    along, across, u = blade_frame(
        track["x"], track["y"], track["vx"], track["vy"], run.rotor_angle(track["time"]), run.omega
    )
    face = "leading" if across[0] > 0 else "trailing"
    f = case.granule_hammer_contact.friction
    slide = BladeSlide(
        run.omega,
        f,
        case.effects.floor_friction.friction,
        "corotating",
        face,
        offset=float(across[0]),
        gravity=case.gravity,
        tip=blade_tip(run),
    )
    return slide, float(along[0]), float(u[0]), track["time"], along


# --- sliding: the paper's decaying branch (eq. 8) --------------------------------------------


def analyse_decaying(run: Run) -> Analysis:
    """The trailing-face inward slide against the closed form and the paper's eq. (27)."""
    slide, x0, u0, t, along = _slide(run)
    exact = slide.closed_form(x0, u0)
    times = list(run.case.paper.decay_times) if run.case.paper else [0.02, 0.05]
    w, f = run.omega, slide.face_friction
    lam1, lam2 = paper_roots(w, f)
    paper = PaperRadialMotion.decaying_branch(w, f, x0, run.case.gravity)
    a = Analysis(run.name, "decaying")
    track = run.track(0)
    a.series = {
        "t": t,
        "x": along,
        "xy": np.column_stack((track["x"], track["y"])),
        "theta": run.rotor_angle(t),
        "exact": exact.displacement(t),
        "paper": paper.displacement(t),
    }
    off_branch = LinearSlide(exact.b, exact.q, exact.c, x0, 0.99 * u0)
    sim_left = amplitude_left(t, along, times)
    exact_left = amplitude_left(t, exact.displacement(t), times)
    paper_left = amplitude_left(t, paper.displacement(t), times)
    offset = -slide.offset
    for tau, s, e, p in zip(times, sim_left, exact_left, paper_left, strict=True):
        a.rows.append(
            Row(
                run.name,
                "4b",
                f"x({tau:g} s)/x0",
                float(s),
                float(e),
                "BladeSlide trailing face, closed form",
                AGREEMENT,
                "same physics: inward sliding on the trailing face over a co-rotating floor",
            )
        )
        a.rows.append(
            Row(
                run.name,
                "4b",
                f"x({tau:g} s)/x0",
                float(s),
                float(p),
                "paper eq. (27), C1 = 0",
                None,
                f"the granule's centre runs {offset * 1e3:.1f} mm behind the radial line through "
                f"the axis, which adds −fω²h = {-f * w**2 * offset:.3f} m/s² to eq. (8)'s "
                f"forcing fg = {f * run.case.gravity:.3f} m/s² (eq. 8 is the limit h = 0)",
            )
        )
    fit = fit_exponential(t, along)
    a.rows.append(
        Row(
            run.name,
            "4b",
            "fitted decay rate λ (1/s)",
            fit.rate,
            lam2,
            "paper λ2 = −fω − ω√(1+f²) (eq. 11), also the closed form's",
            AGREEMENT,
            f"the decaying branch: x − x_eq ∝ e^(λ2 t); fit ± {fit.rate_error:.1e} 1/s "
            "(statistical; the step's first-order error dominates)",
            "1/s",
        )
    )
    a.rows.append(
        Row(
            run.name,
            "4b",
            "x(0.05 s) launched 1 % slower, m",
            float(off_branch.displacement(times[-1])),
            float(exact.displacement(times[-1])),
            "BladeSlide closed form on the branch",
            None,
            f"the branch is a saddle (λ1 = +{lam1:.1f} 1/s): a launch 1 % slower leaves the "
            "branch and the granule turns back outward",
            "m",
        )
    )
    return a


# --- sliding: exit speed from the leading face (Fig. 3) --------------------------------------


def blade_model_exit(run: Run) -> tuple[float, float]:
    """(exit time in s, absolute exit speed in m/s) of the blade model for a sliding run."""
    slide, x0, u0, _, _ = _slide(run)
    result = slide.integrate(x0, u0, 10.0)
    if result.event != "tip":
        return math.nan, math.nan
    return float(result.t[-1]), result.absolute_exit_speed


def analyse_blade(runs: Sequence[Run], paper: Params | None = None) -> Analysis:
    """Exit speeds of a sweep of leading-face runs against BladeSlide; the paper's v_max."""
    a = Analysis("blade-exit sweep", "blade")
    points = []
    for run in runs:
        _, v_sim = blade_exit(run)
        t_model, v_model = blade_model_exit(run)
        f = run.case.granule_hammer_contact.friction
        if math.isnan(v_sim) and math.isnan(v_model):
            continue  # both stop on the blade: floor friction beats the centrifugal force
        end = float(run.track(0)["time"][-1])
        if math.isnan(v_sim) and end < t_model:
            a.cannot(
                run,
                "exit speed at the blade tip",
                f"the run ends at {end:.3g} s, before the model's granule leaves the blade "
                f"({t_model:.3g} s): run it longer",
            )
            continue
        v_paper = math.nan if paper is None else vmax_decaying(paper, run.omega, f)
        points.append((run.omega, f, v_sim, v_model, v_paper))
        a.rows.append(
            Row(
                run.name,
                "3",
                f"v_max at ω = {run.omega:.1f} rad/s, f = {f:g}",
                v_sim,
                v_model,
                "BladeSlide leading face (solve_ivp)",
                AGREEMENT,
                "same physics: outward sliding on the leading face over a co-rotating floor",
                "m/s",
            )
        )
    a.series["points"] = np.array(points)
    if paper is not None and points:
        grid = np.array(points)
        for f in np.unique(grid[:, 1]):
            sel = grid[grid[:, 1] == f]
            row = sel[np.argmax(sel[:, 0])]
            a.rows.append(
                Row(
                    "blade-exit sweep",
                    "3",
                    f"v_max at ω = {row[0]:.1f} rad/s, f = {f:g}",
                    float(row[2]),
                    float(row[4]),
                    "paper eq. (40) on the decaying branch, x0 = 80 mm",
                    None,
                    "the paper's v_max is the launch speed its decaying branch needs, which "
                    "grows with f; a granule pushed out by the blade leaves slower the higher f",
                    "m/s",
                )
            )
    return a


# --- impacts ------------------------------------------------------------------------------------


def analyse_two_body(runs: Sequence[Run], paper: Params | None = None) -> Analysis:
    """Every efficiency of the first impact of each run against impact_efficiencies."""
    a = Analysis("two-body sweep", "two-body")
    points = []
    for run in runs:
        if reason := missing_impacts(run):
            a.cannot(run, "efficiencies of the first impact", reason)
            continue
        p = efficiency_point(run)
        model = impact_efficiencies(p.granule_mass, p.hammer_mass, p.restitution)
        points.append((p.hammer_mass, p.granule_mass, p.transfer, model.transfer))
        for name in ("transfer", "relative", "dissipated", "hammer_frame_loss"):
            a.rows.append(
                Row(
                    run.name,
                    "4a",
                    f"{name} (M = {p.hammer_mass * 1e3:g} g, m = {p.granule_mass * 1e3:.3g} g)",
                    getattr(p, name),
                    getattr(model, name),
                    "impact_efficiencies (two-body)",
                    AGREEMENT,
                    "same physics: a free central impact on a granule at rest",
                )
            )
    a.series["points"] = np.array(points)
    a.series["restitution"] = runs[0].case.granule_hammer_contact.restitution
    if paper is not None and points:
        a.rows += _paper_efficiency_rows(np.array(points), paper)
    return a


def _paper_efficiency_rows(points: np.ndarray, paper: Params) -> list[Row]:
    """The quoted Fig. 4a values against the sweep: as per cents with the realistic granule,
    as fractions with the fitted one (cases/paper-fitted.toml)."""
    rows = []
    s = paper.study
    for M, quoted in zip(s.efficiency_hammer_masses, s.efficiency_values, strict=True):
        for m, scale, reading in ((0.00016, 1, "per cent"), (paper.m, 100, "fraction")):
            sel = points[np.isclose(points[:, 1], m) & np.isclose(points[:, 0], M)]
            if not sel.size:
                continue
            rows.append(
                Row(
                    "two-body sweep",
                    "4a",
                    f"transfer (M = {M * 1e3:g} g, m = {m * 1e3:.3g} g)",
                    float(sel[0, 2]),
                    quoted * scale,
                    f"paper Fig. 4a read as {reading}",
                    None,
                    "η = (1+e)²mM/(M+m)² falls as 1/M (×20 from 5 to 100 g, the paper's ×7.5); "
                    "read as fractions the quoted values need a granule 15-40× a real one",
                )
            )
    return rows


def _flight_rows(run: Run, a: Analysis, paper_label: str) -> None:
    """Free flight after the first impact against the closed form and the paper's decay."""
    case, track = run.case, run.track(0)
    floor = case.effects.floor_friction
    if floor is None or floor.floor != "stationary" or not run.impacts["time"].size:
        return
    t_hit = float(run.impacts["time"][0])
    t, x, y = track["time"], track["x"], track["y"]
    start = int(np.searchsorted(t, t_hit, side="left"))
    r = np.hypot(x, y)
    ends = [t.size]
    if run.impacts["time"].size > 1:
        ends.append(int(np.searchsorted(t, run.impacts["time"][1], side="left")))
    near_wall = np.nonzero(r[start:] + case.granules.radius >= case.chamber.radius - 1e-3)[0]
    if near_wall.size:
        ends.append(start + int(near_wall[0]))
    # any collision between frames (the wall between two frames, an impact not finished when
    # the run ended): a change of speed beyond the floor's f g Δt
    speed = np.hypot(track["vx"][start:], track["vy"][start:])
    floor_change = floor.friction * case.gravity * np.diff(t[start:])
    jumps = np.nonzero(np.abs(np.diff(speed)) > 2.0 * floor_change + 1e-9)[0]
    if jumps.size:
        ends.append(start + int(jumps[0]) + 1)
    stop = min(ends)
    if stop - start < 5:
        return
    window = slice(start, stop)
    p0 = (x[start], y[start])
    v0 = (track["vx"][start], track["vy"][start])
    flight = free_flight(t[window] - t[start], p0, v0, floor.friction * case.gravity)
    r_model = np.hypot(flight[:, 0], flight[:, 1])
    worst = int(np.argmax(np.abs(r[window] / r_model - 1)))
    a.series |= {"t_hit": t_hit, "flight_t": t[window], "flight_r": r_model, "flight": flight}
    a.rows.append(
        Row(
            run.name,
            "4b",
            f"r(t) in free flight, worst of {stop - start} frames "
            f"({t[window][worst] - t_hit:.4f} s after the impact)",
            float(r[window][worst]),
            float(r_model[worst]),
            "free flight over a Coulomb floor (straight line, a = f g)",
            AGREEMENT,
            "same physics: after a restitutive impact the granule flies free until the wall",
            "m",
        )
    )
    R = case.hammers.hinge_radius
    x0 = float(r[start] - R)
    p = Params.from_case(case)
    paper = PaperRadialMotion.decaying_branch(p.omega, p.f, x0, p.g)
    times = [tau for tau in p.study.decay_times if t[start] + tau <= t[-1]]
    sim_left = amplitude_left(t, r - R, times, start=t[start])
    paper_left = amplitude_left(t, R + paper.displacement(t - t[start]) - R, times, start=t[start])
    a.series |= {
        "paper_t": t[start:],
        "paper_r": R + paper.displacement(t[start:] - t[start]),
        "paper_phi": math.atan2(y[start], x[start]) + p.omega * (t[start:] - t[start]),
    }
    for tau, s, q in zip(times, sim_left, paper_left, strict=True):
        a.rows.append(
            Row(
                run.name,
                "4b",
                f"(r − R) {tau:g} s after the impact / at the impact",
                float(s),
                float(q),
                f"paper eq. (27), C1 = 0 ({paper_label})",
                None,
                "after a restitutive impact the granule leaves the face and flies free (then "
                "meets the wall): r grows; eq. (27) is a slide on the face on a saddle's "
                "decaying branch",
            )
        )


def analyse_hinged(run: Run) -> Analysis:
    """Impacts of hinged hammers on one granule, its free flight and successive energies."""
    a = Analysis(run.name, "hinged")
    case = run.case
    e = case.granule_hammer_contact.restitution
    stats = all_impacts(run)
    track = run.track(0)
    a.series |= {"t": track["time"], "x": track["x"], "y": track["y"], "impacts": stats}
    for i, s in enumerate(stats[:4]):
        a.rows.append(
            Row(
                run.name,
                "5",
                f"restitution of impact {i + 1}",
                s.restitution,
                e,
                "Newton's restitution (case)",
                AGREEMENT,
                "same physics: rigid impulse contacts hold e exactly",
            )
        )
        a.rows.append(
            Row(
                run.name,
                "5",
                f"normal relative KE lost in impact {i + 1}",
                s.normal_loss,
                impact_efficiencies(case.granule_mass, math.inf, e).hammer_frame_loss,
                "1 − e² (impact_efficiencies.hammer_frame_loss)",
                AGREEMENT,
                "same physics: ½μv_n² keeps e² in every impact",
            )
        )
    if reason := missing_impacts(run):
        a.cannot(run, "restitution, losses and energy transfer of the impacts", reason)
        a.cannot(run, "the granule's flight after its first impact", reason)
        return a
    impact_law_rows(run, a)
    slide_rows(run, a)
    flight_rows(run, a)
    if case.hammers.shape.kind == "plate":
        _hinged_rows(run, a, stats)
    _flight_rows(run, a, "realistic ω, f; x0 = r − R at the impact")
    if reason := missing_impacts(run, 2):
        a.cannot(run, "energies after successive impacts", reason)
    else:
        _successive_rows(run, a)
    return a


def _hinged_rows(run: Run, a: Analysis, stats: list) -> None:
    case = run.case
    for i, s in enumerate(stats[:4]):
        model = hinged_prediction(run, i)
        first = i == 0
        a.rows.append(
            Row(
                run.name,
                "4a",
                f"transfer efficiency of impact {i + 1}",
                s.transfer,
                model.granule_energy_gain / model.hammer_energy_before,
                "hinged_impact (frictionless, hinge on the rotor)",
                AGREEMENT if first else None,
                "same physics: a hammer turning with the rotor strikes a granule at rest; the "
                "frictionless law leaves out the tangential impulse (≈ 0.3 % of the energy)"
                if first
                else f"tangential slip {abs(run.impacts['tangential_velocity_before'][i]):.2f} m/s "
                f"against {s.approach_speed:.2f} m/s normal: friction, which the frictionless "
                "law leaves out (the state at the impact is the recorded one)",
            )
        )
        if first:
            two_body = impact_efficiencies(
                case.granule_mass, case.hammers.mass, case.granule_hammer_contact.restitution
            )
            a.rows.append(
                Row(
                    run.name,
                    "4a",
                    "transfer efficiency of impact 1",
                    s.transfer,
                    two_body.transfer,
                    "impact_efficiencies (free hammer of mass M)",
                    None,
                    "a hinged hammer strikes with M_eff = I_A/d² = "
                    f"{model.effective_mass * 1e3:.1f} g, not M = {case.hammers.mass * 1e3:.1f} g; "
                    "its KE includes rotation; the rotor feeds the hinge",
                )
            )


def _successive_rows(run: Run, a: Analysis) -> None:
    case = run.case
    energies = successive_energies(run, count=4)
    n = len(energies.lab)
    e = case.granule_hammer_contact.restitution
    paper = paper_cumulative_loss(e, n - 1)
    p = Params.from_case(case)
    eq65 = successive_model(p).energy_after_impact(p.m)
    eq65 = eq65 / eq65[0]
    a.series |= {"energies": energies, "paper_e2i": paper, "paper_eq65": eq65}
    for i in range(1, n):
        a.rows.append(
            Row(
                run.name,
                "5",
                f"lab KE after impact {i + 1} / after impact 1",
                float(energies.lab_fraction[i]),
                float(paper[i - 1]),
                "paper e^(2i) (energy left after i impacts)",
                None,
                "every impact is fed by the hammer (the rotor): the granule's lab energy after an "
                "impact is set by the hammer's speed, not by the energy it kept",
            )
        )
        if i < len(eq65):
            a.rows.append(
                Row(
                    run.name,
                    "5",
                    f"lab KE after impact {i + 1} / after impact 1",
                    float(energies.lab_fraction[i]),
                    float(eq65[i]),
                    "paper eq. (61)-(65), radii 80/45/28/15 mm",
                    None,
                    "eq. (61)'s β is fitted to the quoted radii, not derived; a struck granule's "
                    "radius does not decay between impacts",
                )
            )


def analyse(runs: Iterable[Run], paper: Params | None = None) -> list[Analysis]:
    """Analyses of runs: sliding and hinged runs one by one, two-body and blade-exit runs as
    sweeps (one analysis each), soft runs of one scene at several contact durations as one
    more (:func:`~perga.studies.compare_any.contact_duration_rows`)."""
    runs = list(runs)
    by_kind: dict[str, list[Run]] = {}
    analyses = []
    for run in runs:
        kind = run_kind(run)
        if kind == "sliding":
            _, _, u0, _, _ = _slide(run)
            kind = "blade" if u0 > 0 else "decaying"
        if kind in ("two-body", "blade"):
            by_kind.setdefault(kind, []).append(run)
        elif kind == "decaying":
            analyses.append(analyse_decaying(run))
        elif kind == "hinged":
            analyses.append(analyse_hinged(run))
        else:
            analyses.append(analyse_other(run))
    if "blade" in by_kind:
        analyses.append(analyse_blade(by_kind["blade"], paper))
    if "two-body" in by_kind:
        analyses.append(analyse_two_body(by_kind["two-body"], paper))
    durations = contact_duration_rows(runs, analyses)
    return analyses if durations is None else [*analyses, durations]
