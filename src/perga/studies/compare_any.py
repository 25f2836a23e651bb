"""``perga compare`` on any run: every recorded impact against the impact law with friction
(:mod:`perga.stats.impact_law`), every slide along a hammer face against the disc on a face
turning with the rotor (:mod:`perga.stats.slide_law`), every free flight between two
contacts against the flight over the floor (:mod:`perga.stats.flight_law`), the ledger's
contact dissipation
against the law's sum, and soft runs of one scene at two contact durations: how the
difference from the law falls with t_c."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from itertools import pairwise

import numpy as np

from perga.model.plan import contact_durations
from perga.stats.energy import all_impacts
from perga.stats.flight_law import check_flights, summarise_flights
from perga.stats.impact_law import ISOLATED, ImpactCheck, check_impacts, summarise
from perga.stats.slide_law import check_slides, contact_time, summarise_slides
from perga.stats.tables import Run
from perga.studies.compare_rows import AGREEMENT, Analysis, Row, missing_impacts


def _machine_dt(run: Run) -> float:
    """The run's machine step, s (summary.json), nan if it is not there."""
    steps = run.summary.get("time_step")
    return float(steps.get("machine", math.nan)) if isinstance(steps, dict) else math.nan


def impact_law_rows(run: Run, a: Analysis) -> list[ImpactCheck]:
    """Every recorded impact against the impact law with friction
    (:mod:`perga.stats.impact_law`): the share of isolated impacts whose velocity after agrees
    within 1 % and the energy they lost against the law's (rigid contacts: the same physics);
    soft contacts against the same instantaneous law, a regime that differs by the contact's
    duration."""
    try:
        checks = check_impacts(run)
    except ValueError as reason:
        statistic = "every impact against the impact law with friction"
        a.cannot(run, statistic, str(reason).split(": ", 1)[-1])
        return []
    a.series["impact_checks"] = checks
    summary = summarise(checks)
    isolated, others = summary.isolated, summary.others
    model = "coupled_impact (Coulomb friction, sticking cap, the hammer's effective mass)"
    rigid = run.case.contact_model.kind == "rigid"
    sample = isolated or summary.compared
    if not sample:
        a.cannot(
            run, "every impact against the impact law with friction", f"none compared: {others}"
        )
        return checks
    errors = np.array([c.velocity_error for c in sample])
    worst = sample[int(np.argmax(errors))]
    spread = (
        f"{len(isolated)} of {len(checks)} impacts isolated, "
        f"{summary.energy_share_isolated:.1%} of the energy lost in impacts; velocity error "
        f"median {np.median(errors):.2e}, 90th percentile {np.quantile(errors, 0.9):.2e}, 99th "
        f"{np.quantile(errors, 0.99):.2e}, worst {worst.velocity_error:.2e} (granule "
        f"{worst.granule} at {worst.time:.5g} s); not isolated: {others}"
    )
    which = "isolated" if isolated else "(none isolated: all)"
    if rigid and isolated:
        dt = _machine_dt(run)
        step = run.omega**2 * run.case.hammers.hinge_radius * dt
        a.rows.append(
            Row(
                run.name, "impacts",
                f"share of {len(isolated)} isolated impacts whose velocity after is within 1 %",
                float(np.mean(errors <= AGREEMENT)), 1.0, model, AGREEMENT,
                f"{spread}. The rigid step adds what the hammer's point gains in one step "
                f"(ω²·R·dt = {step:.2g} m/s at the hinge): first order in dt",
            )
        )  # fmt: skip
    else:
        speeds = np.array([c.speed_after for c in sample])
        a.rows.append(
            Row(
                run.name, "impacts", f"mean speed after the {which} impacts",
                float(speeds[:, 0].mean()), float(speeds[:, 1].mean()), model, None,
                f"{spread}; " + (_soft_split(sample) if not rigid else "no impact is isolated"),
                "m/s",
            )
        )  # fmt: skip
    a.rows.append(
        Row(
            run.name, "impacts", f"energy lost in the {which} impacts",
            sum(c.dissipated[0] for c in sample), sum(c.dissipated[1] for c in sample),
            model, AGREEMENT if rigid and isolated else None,
            "same physics: the law's loss per impact, summed" if rigid and isolated
            else "soft contacts last t_c; not isolated impacts share their impulse",
            "J",
        )
    )  # fmt: skip
    _energy_row(run, a, checks, isolated)
    _successive_row(run, a, isolated)
    return checks


def _soft_split(checks: list[ImpactCheck]) -> str:
    """The soft contacts' difference from the law, split where the law slides and sticks."""
    parts = []
    for sticks, what in ((False, "sliding at the cap"), (True, "sticking")):
        errors = [c.velocity_error for c in checks if c.sticks == sticks]
        if errors:
            parts.append(f"{what}, {len(errors)}: median {np.median(errors):.2e}")
    return (
        "; ".join(parts) + ". Soft contacts last t_c (the sliding impacts' difference falls with "
        "it); a sticking one's tangential spring gives the slip back, which the law stops"
    )


def _energy_row(
    run: Run, a: Analysis, checks: list[ImpactCheck], isolated: list[ImpactCheck]
) -> None:
    """The contacts' dissipation booked by the ledger against the law's losses in the isolated
    impacts, the difference named term by term (summary.json's energy, impacts.csv)."""
    energy = run.summary.get("energy")
    if not isinstance(energy, dict) or "contact_dissipation" not in energy:
        a.cannot(run, "the ledger's dissipation against the law's", "summary.json has no ledger")
        return
    booked = float(energy["contact_dissipation"])
    law = sum(c.dissipated[1] for c in isolated)
    recorded_isolated = sum(c.dissipated[0] for c in isolated)
    recorded_other = sum(c.dissipated[0] for c in checks if c.regime != ISOLATED)
    rest = booked - recorded_isolated - recorded_other
    a.rows.append(
        Row(
            run.name, "impacts", "energy lost in contacts: the ledger's, against the law's sum "
            "over the isolated impacts", booked, law,
            "coupled_impact per isolated impact, summed", None,
            f"the ledger's contact term is the isolated impacts' {recorded_isolated:.4g} J (the "
            f"law's {law:.4g} J) + the other impacts' {recorded_other:.4g} J + {rest:.4g} J in "
            "contacts the impact log does not hold (granule pairs, the wall, a contact's steps "
            "after its first, held granules' cells); apart from it the ledger books friction "
            f"{float(energy.get('friction', 0.0)):.4g} J (floor, hinges) and drag "
            f"{float(energy.get('drag', 0.0)):.4g} J, and closes to "
            f"{float(energy.get('closure', math.nan)):+.2e}",
            "J",
        )
    )  # fmt: skip


def analyse_other(run: Run) -> Analysis:
    """Any run: every impact against the impact law with friction."""
    a = Analysis(run.name, "other")
    a.series["impacts"] = all_impacts(run)
    if reason := missing_impacts(run):
        a.cannot(run, "every impact against the impact law with friction", reason)
        return a
    impact_law_rows(run, a)
    slide_rows(run, a)
    flight_rows(run, a)
    return a


def slide_rows(run: Run, a: Analysis) -> None:
    """Every slide along a hammer face against the disc on a face turning with the rotor
    (:mod:`perga.stats.slide_law`): with rigid contacts the share of slides in the model's
    regime whose velocity at the end agrees within 1 % (the same physics); soft contacts, or no
    slide in the model's regime, as a regime that differs, with the errors' spread."""
    statistic = "slides along a hammer face against the disc on a face turning with the rotor"
    try:
        checks = check_slides(run)
    except ValueError as reason:
        a.cannot(run, statistic, str(reason).split(": ", 1)[-1])
        return
    if not checks:
        count = run.contacts["start"].size
        a.cannot(
            run, statistic,
            f"none of the {count} granule-hammer contacts lasted {contact_time(run):.3g} s or "
            "more (a slide outlasts a contact time)",
        )  # fmt: skip
        return
    a.series.setdefault("slide_checks", []).extend(checks)
    summary = summarise_slides(checks)
    inward = [c for c in checks if c.face == "trailing" and c.travel < 0]
    a.cannot(
        run, "slides on the paper's decaying branch against λ2 of eq. (11)",
        f"{len(inward)} of the {len(checks)} slides run inward on a trailing face (the branch), "
        "each from its own start, not on the branch's initial condition: the disc on a face "
        "above is their model (paper-decaying-branch.toml puts a granule on the branch)",
    )  # fmt: skip
    on_face = summary.on_face
    rigid = run.case.contact_model.kind == "rigid"
    model = "DiscOnFace (slips and rolls; Coulomb face and floor friction)"
    sample = on_face or [c for c in checks if math.isfinite(c.velocity_error)]
    if not sample:
        a.cannot(run, statistic, f"the model leaves the face before every slide ends: {checks}")
        return
    errors = np.array([c.velocity_error for c in sample])
    worst = sample[int(np.argmax(errors))]
    spread = (
        f"{len(checks)} slides ({sum(c.duration for c in checks) * 1e3:.3g} ms in all), "
        f"{len(on_face)} on a face turning with the rotor; velocity error there median "
        f"{np.median(errors):.2e}, worst {worst.velocity_error:.2e} (granule {worst.granule} at "
        f"{worst.start:.5g} s, {worst.duration * 1e3:.3g} ms); not in the model's regime: "
        f"{summary.others}"
    )
    if rigid and on_face:
        a.rows.append(
            Row(
                run.name, "slides",
                f"share of {len(on_face)} slides on a face turning with the rotor whose "
                "velocity at the end is within 1 %",
                float(np.mean(errors <= AGREEMENT)), 1.0, model, AGREEMENT,
                f"{spread}. The rigid step's first-order error grows with the slide's length",
            )
        )  # fmt: skip
        return
    speeds = np.array([c.exit_speed for c in sample])
    why = (
        "soft contacts: the granule rides on the contact's spring, the face's normal force is "
        "not the rigid constraint's"
        if not rigid
        else "no slide is on a face turning with the rotor"
    )
    a.rows.append(
        Row(
            run.name, "slides", f"mean speed at the end of {len(sample)} slides",
            float(speeds[:, 0].mean()), float(speeds[:, 1].mean()), model, None,
            f"{spread}; {why}", "m/s",
        )
    )  # fmt: skip


def _scene(run: Run) -> str:
    """A run's case with its contact duration and output left out: the scene it shares with
    runs that differ only in t_c."""
    data = run.case.model_dump(mode="json")
    data.pop("output", None)
    data.get("contact_model", {}).pop("duration", None)
    return json.dumps(data, sort_keys=True)


def contact_duration_rows(runs: Sequence[Run], analyses: Sequence[Analysis]) -> Analysis | None:
    """Soft runs of one scene at different contact durations t_c (their cases equal but for
    contact_model.duration and output): the order at which their isolated sliding impacts'
    median velocity error against the law falls with t_c, pair by pair; None without such
    runs."""
    checks = {a.name: a.series["impact_checks"] for a in analyses if a.series.get("impact_checks")}
    scenes: dict[str, list[tuple[float, Run]]] = {}
    for run in runs:
        if run.case.contact_model.kind != "rigid" and run.name in checks:
            t_c = contact_durations(run.case)["granule-hammer"]
            scenes.setdefault(_scene(run), []).append((t_c, run))
    pairs = [
        (a, b)
        for group in scenes.values()
        for a, b in pairwise(sorted(group, key=lambda item: -item[0]))
        if a[0] != b[0]
    ]
    if not pairs:
        return None
    out = Analysis("contact durations", "contact-duration")
    for (t_a, run_a), (t_b, run_b) in pairs:
        medians = []
        for run in (run_a, run_b):
            isolated = [c for c in checks[run.name] if c.regime == ISOLATED]
            medians.append(
                [float(np.median([c.velocity_error for c in isolated if c.sticks == sticks]
                                 or [math.nan])) for sticks in (False, True)]
            )  # fmt: skip
        (slide_a, stick_a), (slide_b, stick_b) = medians
        out.rows.append(
            Row(
                f"{run_a.name} / {run_b.name}", "impacts",
                f"order of the sliding impacts' error in t_c ({t_a * 1e3:.3g} → "
                f"{t_b * 1e3:.3g} ms)",
                math.log(slide_a / slide_b) / math.log(t_a / t_b), 1.0,
                "first order in t_c (the contact lasts t_c; the law is instantaneous)", None,
                f"median velocity error of the isolated impacts the law has sliding: "
                f"{slide_a:.2e} at {t_a * 1e3:.3g} ms, {slide_b:.2e} at {t_b * 1e3:.3g} ms; of "
                f"those it has sticking {stick_a:.2e} and {stick_b:.2e}, which do not fall: the "
                "tangential spring gives the slip back at separation, where the law stops it",
            )
        )  # fmt: skip
    return out


def flight_rows(run: Run, a: Analysis) -> None:
    """Every flight between two contacts of a granule against the flight over the floor
    (:mod:`perga.stats.flight_law`): the share of free flights whose velocity before the next
    impact agrees within 1 % (the same physics)."""
    statistic = "free flights between contacts against the flight over the floor"
    try:
        checks = check_flights(run)
    except ValueError as reason:
        a.cannot(run, statistic, str(reason).split(": ", 1)[-1])
        return
    summary = summarise_flights(checks)
    if not summary.free:
        why = f"{len(checks)} flights, none free: {summary.others}" if checks else "no flight"
        a.cannot(run, statistic, why)
        return
    a.series["flight_checks"] = checks
    errors = np.array([c.velocity_error for c in summary.free])
    worst = summary.worst(1)[0]
    a.rows.append(
        Row(
            run.name, "flights",
            f"share of {errors.size} free flights whose velocity before the next impact is "
            "within 1 %",
            float(np.mean(errors <= AGREEMENT)), 1.0,
            "FloorFlight (Coulomb floor friction against the floor's velocity, drag)", AGREEMENT,
            f"{len(checks)} flights between contacts, {errors.size} free; velocity error median "
            f"{np.median(errors):.2e}, worst {worst.velocity_error:.2e} (granule "
            f"{worst.granule} from {worst.start:.5g} s, {worst.duration * 1e3:.3g} ms); not "
            f"free: {summary.others}",
        )
    )  # fmt: skip


def _successive_row(run: Run, a: Analysis, isolated: list[ImpactCheck]) -> None:
    """Successive isolated impacts of each granule against the paper's e^{2i}: the energy of
    the normal approach to the next impact over the last rebound's, 1 where nothing feeds the
    granule between impacts (the paper's regime)."""
    u_n = run.impacts["normal_velocity_before"]
    e = run.case.granule_hammer_contact.restitution
    by_granule: dict[int, list[ImpactCheck]] = {}
    for c in isolated:
        by_granule.setdefault(c.granule, []).append(c)
    ratios = np.array([
        u_n[second.index] ** 2 / (e * u_n[first.index]) ** 2
        for impacts in by_granule.values()
        for first, second in pairwise(sorted(impacts, key=lambda c: c.time))
    ])  # fmt: skip
    if not ratios.size:
        a.cannot(run, "successive impacts against the paper's e^{2i}",
                 "no granule has two isolated impacts")  # fmt: skip
        return
    q10, q50, q90 = np.quantile(ratios, (0.1, 0.5, 0.9))
    a.rows.append(
        Row(
            run.name, "impacts",
            "a granule's next normal approach energy over its last rebound's (e^{2i}: 1)",
            float(q50), 1.0, "the paper's e^{2i}: each impact meets the last rebound", None,
            f"{ratios.size} pairs of successive isolated impacts of one granule; 10th, 50th, "
            f"90th percentiles {q10:.3g}, {q50:.3g}, {q90:.3g}. Between impacts the floor and the "
            "hammers feed the granule (a hammer meets it again at its own speed ωR): each impact "
            "starts afresh, and the energy after i impacts is not e^{2i} of the first",
        )
    )  # fmt: skip
