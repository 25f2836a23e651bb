"""Named metrics of a run: numbers computed from a run directory's tables, for sweeps and
calibration (SI units; each metric's unit in :data:`METRICS`).

A metric is asked for by name, with an argument after a colon where it takes one:
``first_impact_restitution``, ``granule_speed_after_impact:2``, ``radius_at:0.02``. A metric
that a run cannot give raises :class:`MetricUnavailableError` with the reason (no impact recorded,
a table the run did not write, a time past the run's end). Metrics are the statistics of
:mod:`perga.stats.energy` and :mod:`perga.stats.trajectory`, the functions ``perga compare``
uses, read for one granule (granule 0 unless said otherwise). The process metrics
(``released_fraction``, ``damaged_fraction``, ``throughput``, ``energy_per_kg``) are of the whole
run: the comb at t = 0 and the granules at the end (granules.csv), releases.csv, the product
(outflow.csv), the drive's work (summary.json).

Impact conventions (impacts.csv, :class:`perga.model.records.Impact`): velocities relative to
the hammer's material point at the contact, normal v_n (< 0 approaching) and tangential, before
and after. The normal restitution is e = −v_n'/v_n. The tangential restitution and the rebound
angle are given at two points, as experiments report one or the other: at the granule's
**centre** (``_centre``: u_t = v_t + ω r, what oblique-impact tests that track the sphere's
centre report, e.g. Kharaz, Gorham & Salman 2001) and at the **contact point** (``_contact``:
v_t, the slip, what tests that also measure the spin report, e.g. Foerster et al. 1994).
β = −v'/v (−1: the tangential velocity kept, as in frictionless sliding; 0: stopped); the
rebound angle is the velocity after from the normal, rad, positive forward (on the side the
tangential velocity had before), as rebound tests report it. Each metric
states its convention and, where the physics bounds it, the range a measured value must lie in
(:class:`Metric`); ``perga metrics`` lists them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from perga.case.schema import ShotPlacement
from perga.model.placement import shot_face
from perga.stats.energy import HEAD_ON, impact_stats, rebound_angle
from perga.stats.tables import FloatArray, Run, read_table


class MetricUnavailableError(Exception):
    """The run cannot give this metric; the message says why."""


@dataclass(frozen=True)
class Metric:
    """A named metric: its unit, what it is, and how a run gives it (``argument``: what the
    text after the colon is, or None for a metric without one); ``bounds``: the closed range
    every value lies in where the physics bounds it, with ``convention`` saying why (a measured
    value outside it has another convention or is wrong)."""

    name: str
    unit: str
    description: str
    compute: Callable[[Run, float | None], float]
    argument: str | None = None
    bounds: tuple[float, float] | None = None
    convention: str = ""


RENAMED = {
    "first_impact_tangential_restitution": "first_impact_tangential_restitution_centre or "
    "first_impact_tangential_restitution_contact",
    "first_impact_rebound_angle": "first_impact_rebound_angle_centre or "
    "first_impact_rebound_angle_contact",
}
"""Metrics that are now two, one per point of the granule (the module docstring)."""


def _impact_rows(run: Run, granule: int = 0) -> np.ndarray:
    if "impacts.csv" not in _tables(run):
        raise MetricUnavailableError(
            "the run did not record impacts (output.record lacks 'impacts')"
        )
    rows = np.nonzero(run.impacts["granule"] == granule)[0] if run.impacts else np.zeros(0, int)
    if rows.size == 0:
        raise MetricUnavailableError(f"granule {granule} made no granule-hammer impact")
    return rows


def _tables(run: Run) -> set[str]:
    """The run's tables, as CSV names (a Parquet granule table counts as granules.csv)."""
    return {p.stem + ".csv" for p in run.directory.iterdir() if p.suffix in (".csv", ".parquet")}


def _nth_impact(run: Run, n: int) -> int:
    rows = _impact_rows(run)
    if not 1 <= n <= rows.size:
        raise MetricUnavailableError(f"granule 0 made {rows.size} impacts, not {n}")
    return int(rows[n - 1])


def _first(run: Run, field: str, what: str) -> float:
    """A statistic of granule 0's first impact (:class:`perga.stats.energy.ImpactStats`)."""
    value = float(getattr(impact_stats(run, _nth_impact(run, 1)), field))
    if not math.isfinite(value):
        raise MetricUnavailableError(f"the first impact does not define {what}")
    return value


def first_impact_restitution(run: Run, _: float | None = None) -> float:
    """e = −v_n'/v_n of granule 0's first impact."""
    return _first(run, "restitution", "e (no normal approach)")


def first_impact_tangential_restitution_contact(run: Run, _: float | None = None) -> float:
    """β = −v_t'/v_t of the contact point, granule 0's first impact."""
    return _first(run, "tangential_restitution", "β (a head-on impact has no tangential motion)")


def first_impact_tangential_restitution_centre(run: Run, _: float | None = None) -> float:
    """β_c = −u_t'/u_t of the centre, granule 0's first impact."""
    return _first(
        run,
        "tangential_restitution_centre",
        "β at the centre (head-on, or an older run without the granule's spin)",
    )


def first_impact_rebound_angle_contact(run: Run, _: float | None = None) -> float:
    """The contact point's rebound angle, forward, granule 0's first impact, rad."""
    return _first(run, "rebound_angle", "a rebound angle")


def first_impact_rebound_angle_centre(run: Run, _: float | None = None) -> float:
    """The centre's rebound angle, forward, granule 0's first impact, rad."""
    return _first(run, "rebound_angle_centre", "a rebound angle (an older run without spins)")


def first_impact_rebound_speed(run: Run, _: float | None = None) -> float:
    """|(v_n', v_t')|: the relative speed after granule 0's first impact, m/s."""
    return _first(run, "rebound_speed", "a rebound speed")


@dataclass(frozen=True)
class ShotRebound:
    """A shot's velocities relative to its face at the start and at the end of the run, along
    the face's normal n and its tangent t = n turned +90° (the impact log's), m/s: of the centre
    and of the contact point (the centre's less the rim's ω r)."""

    normal: tuple[float, float]
    centre: tuple[float, float]
    contact: tuple[float, float]


def shot_rebound(run: Run) -> ShotRebound:
    """The rebound of the shot of ``run`` from its trajectory (granules.csv), as a rebound test
    measures it: the first frame's velocity and spin against the last frame's, relative to the
    face's velocity at the point aimed at (a wall at rest; a hammer face at t = 0). The flight
    must be free (no floor, drag or gravity in the plane) and over (the last two frames' velocity
    the same)."""
    case = run.case
    placement = case.granules.placement
    if not isinstance(placement, ShotPlacement):
        raise MetricUnavailableError("the case's granule is not a shot (granules.placement)")
    e = case.effects
    if e.floor_friction is not None or e.air_drag is not None or e.gravity_in_plane is not None:
        raise MetricUnavailableError(
            "the shot's flight is not free: floor friction, drag or gravity change its velocity"
        )
    track = run.track(0)
    if not track or track["time"].size < 3:
        raise MetricUnavailableError("the run did not record granules.csv (three frames at least)")
    v = np.column_stack((track["vx"], track["vy"]))
    if not np.allclose(v[-1], v[-2], rtol=1e-9, atol=0.0) or np.allclose(v[-1], v[0], rtol=1e-9):
        raise MetricUnavailableError(
            "the shot has not rebounded by the run's end (its last two frames' velocities "
            "differ, or equal its start's): run it longer"
        )
    face = shot_face(case, placement)
    n = face.normal
    t = np.array([-n[1], n[0]])
    r = float(track["radius"][0]) if "radius" in track else case.granules.radius
    u0, u1 = v[0] - face.velocity, v[-1] - face.velocity
    w0, w1 = (float(track["angular_velocity"][i]) for i in (0, -1))
    centre = (float(u0 @ t), float(u1 @ t))
    return ShotRebound(
        (float(u0 @ n), float(u1 @ n)), centre, (centre[0] - w0 * r, centre[1] - w1 * r)
    )


def _shot(run: Run, what: str, point: str) -> float:
    """Restitution (e), tangential restitution (β) or rebound angle of the shot at ``point``."""
    rebound = shot_rebound(run)
    (vn, vn1), (vt, vt1) = rebound.normal, getattr(rebound, point)
    if what == "restitution":
        return -vn1 / vn
    if what == "angle":
        return rebound_angle(vt, vt1, vn1)
    if abs(vt) <= HEAD_ON * abs(vn):
        raise MetricUnavailableError("a head-on shot has no tangential motion")
    return -vt1 / vt


def shot_restitution(run: Run, _: float | None = None) -> float:
    """e = −v_n'/v_n of the shot, from its trajectory."""
    return _shot(run, "restitution", "centre")


def shot_tangential_restitution_centre(run: Run, _: float | None = None) -> float:
    """β = −u_t'/u_t of the shot's centre, from its trajectory."""
    return _shot(run, "beta", "centre")


def shot_tangential_restitution_contact(run: Run, _: float | None = None) -> float:
    """β = −v_t'/v_t of the shot's contact point, from its trajectory and spin."""
    return _shot(run, "beta", "contact")


def shot_rebound_angle_centre(run: Run, _: float | None = None) -> float:
    """The shot's centre's rebound angle, forward, rad."""
    return _shot(run, "angle", "centre")


def shot_rebound_angle_contact(run: Run, _: float | None = None) -> float:
    """The shot's contact point's rebound angle, forward, rad."""
    return _shot(run, "angle", "contact")


def granule_speed_after_impact(run: Run, n: float | None) -> float:
    """Granule 0's speed in the fixed frame at the first frame after its n-th impact, m/s."""
    if n is None or n != int(n) or n < 1:
        raise MetricUnavailableError(
            "granule_speed_after_impact needs a whole impact number n >= 1"
        )
    row = _nth_impact(run, int(n))
    t = float(run.impacts["time"][row])
    track = run.track(0)
    if not track or track["time"].size == 0:
        raise MetricUnavailableError("the run did not record granules.csv")
    after = np.nonzero(track["time"] >= t)[0]
    if after.size == 0:
        raise MetricUnavailableError(f"no frame after the impact at t = {t:g} s")
    return float(track["speed"][after[0]])


def energy_gain_per_impact(run: Run, _: float | None = None) -> float:
    """The granules' mean kinetic-energy gain per granule-hammer impact (lab frame), J."""
    if not run.impacts or run.impacts["time"].size == 0:
        raise MetricUnavailableError("the run recorded no impact")
    return float(np.mean(run.impacts["granule_energy_gain"]))


def transfer_efficiency(run: Run, _: float | None = None) -> float:
    """Mean over granule 0's impacts of the granule's energy gain over the hammer's kinetic
    energy before the impact (:attr:`perga.stats.energy.ImpactStats.transfer`), -."""
    values = [impact_stats(run, int(i)).transfer for i in _impact_rows(run)]
    finite = [v for v in values if math.isfinite(v)]
    if not finite:
        raise MetricUnavailableError("no impact with a moving hammer")
    return float(np.mean(finite))


def radius_at(run: Run, t: float | None) -> float:
    """Granule 0's distance from the rotor axis at time t (interpolated between frames), m."""
    track = run.track(0)
    if t is None or not track or track["time"].size == 0:
        raise MetricUnavailableError("radius_at needs a time and granules.csv")
    if not track["time"][0] <= t <= track["time"][-1]:
        raise MetricUnavailableError(
            f"t = {t:g} s is outside the run (0 to {track['time'][-1]:g} s)"
        )
    r = np.hypot(track["x"], track["y"])
    return float(np.interp(t, track["time"], r))


def impact_count(run: Run, _: float | None = None) -> float:
    """The number of granule-hammer impacts the run recorded, -."""
    if "impacts.csv" not in _tables(run):
        raise MetricUnavailableError("the run did not record impacts")
    return float(run.impacts["time"].size if run.impacts else 0)


def ledger_closure(run: Run, _: float | None = None) -> float:
    """The energy ledger's closure at the end of the run (summary.json), -."""
    energy = run.summary.get("energy") or {}
    if "closure" not in energy:
        raise MetricUnavailableError("the run did not track energy (output.record lacks 'energy')")
    if energy["closure"] is None:  # summary.json writes a non-finite closure as null
        raise MetricUnavailableError("the ledger's closure is not finite (no energy in play)")
    return float(energy["closure"])


def dissipated_fraction(run: Run, _: float | None = None) -> float:
    """The energy the contacts dissipated (restitution and friction, summary.json's ledger)
    over all the run had: the bodies' kinetic and elastic energy at the start and the energy
    put in play since (the drive's work, gravity's, the inflow's), -."""
    energy = run.summary.get("energy") or {}
    if "contact_dissipation" not in energy:
        raise MetricUnavailableError("the run did not track energy (output.record lacks 'energy')")
    total = sum(float(energy[k] or 0.0) for k in ("kinetic_initial", "elastic_initial",
                                                   "energy_in_play"))  # fmt: skip
    if not total > 0.0:
        raise MetricUnavailableError("the run had no energy to dissipate")
    return float(energy["contact_dissipation"]) / total


def mean_speed_at_end(run: Run, _: float | None = None) -> float:
    """The granules' mean speed in the fixed frame at the run's end (summary.json), m/s."""
    speeds = run.summary.get("speeds") or {}
    if speeds.get("mean") is None:
        raise MetricUnavailableError("the run ended without granules (no speeds in summary.json)")
    return float(speeds["mean"])


def _outflow(run: Run) -> dict[str, FloatArray]:
    """outflow.csv: each granule that left through the outlet (mass, kg; survival, -; ...)."""
    if "outflow.csv" not in _tables(run):
        raise MetricUnavailableError(
            "the run did not record its outflow (no [outlet], or output.record lacks 'outflow')"
        )
    return read_table(run.directory / "outflow.csv")


def _outflow_mass(run: Run) -> FloatArray:
    """outflow.csv's ``mass`` column, kg."""
    return _outflow(run)["mass"]


def released_fraction(run: Run, _: float | None = None) -> float:
    """Of the granules held in their comb cells at t = 0 (granules.csv's first frame), the share
    released during the run (releases.csv), -. The comb at the start is the same for every
    setting of a study, whatever the feed adds later."""
    tables = _tables(run)
    if "granules.csv" not in tables or "releases.csv" not in tables:
        raise MetricUnavailableError(
            "the run did not record granules and releases (output.record needs both)"
        )
    granules = run.granules
    if "held" not in granules:
        raise MetricUnavailableError("no granule was held in a comb cell (no detachment_force)")
    first = granules["time"] == granules["time"][0]
    held = set(granules["id"][first & (granules["held"] == 1)].astype(int).tolist())
    if not held:
        raise MetricUnavailableError("no granule was held in a comb cell at t = 0")
    released = set(read_table(run.directory / "releases.csv")["granule"].astype(int).tolist())
    return len(held & released) / len(held)


def damaged_fraction(run: Run, _: float | None = None) -> float:
    """Expected damage of the granules out of the comb: 1 − the mean expected survival of the
    granules that left through the outlet (outflow.csv) and of those free in the chamber at the
    end (granules.csv's last frame, held = 0), -."""
    if run.case.damage is None:
        raise MetricUnavailableError("the case has no [damage]")
    gone = _outflow(run)["survival"]
    granules = run.granules
    if not granules or "survival" not in granules:
        raise MetricUnavailableError("the run did not record granules (output.record)")
    last = granules["time"] == granules["time"][-1]
    free = last & (granules["held"] == 0) if "held" in granules else last
    survival = np.concatenate([gone, granules["survival"][free]])
    if survival.size == 0:
        raise MetricUnavailableError("no granule came out of the comb")
    return float(1.0 - np.mean(survival))


def throughput(run: Run, _: float | None = None) -> float:
    """Mass through the outlet per second of simulated time (outflow.csv), kg/s."""
    mass = _outflow_mass(run)
    t = float(run.summary.get("simulated_time") or 0.0)
    if not t > 0:
        raise MetricUnavailableError("the run simulated no time (summary.json: simulated_time)")
    return float(np.sum(mass)) / t


def energy_per_kg(run: Run, _: float | None = None) -> float:
    """The rotor drive's work over the mass of product that left through the outlet, J/kg."""
    energy = run.summary.get("energy") or {}
    if not isinstance(energy, dict) or "drive_work" not in energy:
        raise MetricUnavailableError("the run did not track energy (output.record lacks 'energy')")
    out = float(np.sum(_outflow_mass(run)))
    if not out > 0:
        raise MetricUnavailableError("no product left through the outlet")
    return float(energy["drive_work"]) / out


METRICS: dict[str, Metric] = {
    m.name: m
    for m in (
        Metric("impact_count", "-", "granule-hammer impacts recorded", impact_count),
        Metric("first_impact_restitution", "-", "e = −v_n'/v_n, first impact of granule 0",
               first_impact_restitution, bounds=(0.0, 1.0),
               convention="the normal rebound over the approach, both positive: 0 plastic, "
               "1 elastic"),
        Metric("first_impact_tangential_restitution_centre", "-",
               "β = −u_t'/u_t of the granule's centre, first impact of granule 0",
               first_impact_tangential_restitution_centre, bounds=(-1.0, 0.0),
               convention="−1: the centre keeps its tangential velocity; friction only slows "
               "it (a granule without spin before: a ratio u_t'/u_t > 0 has the other sign)"),
        Metric("first_impact_tangential_restitution_contact", "-",
               "β = −v_t'/v_t of the contact point (the slip), first impact of granule 0",
               first_impact_tangential_restitution_contact, bounds=(-1.0, 1.0),
               convention="−1: the slip kept; 0: stopped (sticking); > 0: reversed by a "
               "tangential spring"),
        Metric("first_impact_rebound_angle_centre", "rad",
               "the centre's rebound from the normal, atan2(u_t', v_n') forward, first "
               "impact of granule 0", first_impact_rebound_angle_centre, bounds=(0.0, math.pi / 2),
               convention="from the normal, positive forward (on the side the tangential "
               "velocity had before): a granule without spin is never turned back"),
        Metric("first_impact_rebound_angle_contact", "rad",
               "the contact point's rebound from the normal, atan2(v_t', v_n') forward, "
               "first impact of granule 0", first_impact_rebound_angle_contact,
               bounds=(-math.pi / 2, math.pi / 2),
               convention="from the normal, positive forward (on the side the slip had "
               "before), negative where the slip reversed"),
        Metric("first_impact_rebound_speed", "m/s",
               "relative speed after the first impact of granule 0", first_impact_rebound_speed),
        Metric("shot_restitution", "-", "e of the shot (hammer face or wall) from its trajectory",
               shot_restitution, bounds=(0.0, 1.0),
               convention="the normal rebound over the approach, both positive"),
        Metric("shot_tangential_restitution_centre", "-",
               "β = −u_t'/u_t of the shot's centre, from its trajectory",
               shot_tangential_restitution_centre, bounds=(-1.0, 0.0),
               convention="−1: the centre keeps its tangential velocity (a shot without spin)"),
        Metric("shot_tangential_restitution_contact", "-",
               "β = −v_t'/v_t of the shot's contact point, from its trajectory and spin",
               shot_tangential_restitution_contact, bounds=(-1.0, 1.0),
               convention="−1: the slip kept; 0: stopped; > 0: reversed"),
        Metric("shot_rebound_angle_centre", "rad",
               "the shot's centre's rebound from the normal, atan2(u_t', v_n') forward",
               shot_rebound_angle_centre, bounds=(0.0, math.pi / 2),
               convention="from the normal, positive forward (on the side the tangential "
               "velocity had before): a granule without spin is never turned back"),
        Metric("shot_rebound_angle_contact", "rad",
               "the shot's contact point's rebound from the normal, atan2(v_t', v_n') forward",
               shot_rebound_angle_contact, bounds=(-math.pi / 2, math.pi / 2),
               convention="from the normal, positive forward (on the side the slip had "
               "before), negative where the slip reversed"),
        Metric("granule_speed_after_impact", "m/s",
               "speed of granule 0 in the fixed frame after its n-th impact",
               granule_speed_after_impact, argument="n, the impact number (1, 2, ...)"),
        Metric("energy_gain_per_impact", "J", "mean granule energy gain per impact",
               energy_gain_per_impact),
        Metric("transfer_efficiency", "-",
               "mean granule gain / hammer energy before, impacts of granule 0",
               transfer_efficiency),
        Metric("radius_at", "m", "distance of granule 0 from the axis at time t", radius_at,
               argument="t, s"),
        Metric("ledger_closure", "-", "energy-ledger closure at the end", ledger_closure),
        Metric("dissipated_fraction", "-",
               "energy dissipated in contacts over the energy at the start and put in play",
               dissipated_fraction, bounds=(0.0, 1.0),
               convention="a share of the energy in play: contacts only take energy"),
        Metric("mean_speed_at_end", "m/s", "the granules' mean speed at the end",
               mean_speed_at_end, bounds=(0.0, math.inf),
               convention="a speed, never negative"),
        Metric("released_fraction", "-",
               "share of the granules held in comb cells at t = 0 released", released_fraction),
        Metric("damaged_fraction", "-",
               "expected damage of the granules out of the comb: 1 − their mean survival",
               damaged_fraction),
        Metric("throughput", "kg/s", "mass through the outlet per simulated second", throughput),
        Metric("energy_per_kg", "J/kg", "drive work / mass through the outlet", energy_per_kg),
    )
}  # fmt: skip
"""Every metric by name."""


def parse_metric(name: str) -> tuple[Metric, float | None]:
    """``NAME`` or ``NAME:ARG`` -> the metric and its argument (ValueError naming the allowed
    names or the argument it needs)."""
    base, sep, arg = name.partition(":")
    if base in RENAMED:
        raise ValueError(
            f"metric {name!r} is now two: {RENAMED[base]} (the granule's centre, which "
            "oblique-impact tests tracking the sphere report, or its contact point)"
        )
    metric = METRICS.get(base)
    if metric is None:
        raise ValueError(f"unknown metric {name!r}; metrics: {', '.join(METRICS)}")
    if (metric.argument is None) != (not sep):
        need = f"{base}:ARG with ARG = {metric.argument}" if metric.argument else base
        raise ValueError(f"metric {name!r}: write it as {need}")
    if not sep:
        return metric, None
    try:
        value = float(arg)
    except ValueError:
        raise ValueError(f"metric {name!r}: {arg!r} is not a number ({metric.argument})") from None
    return metric, value


def evaluate(run: Run, name: str) -> float:
    """Metric ``name`` of ``run`` (MetricUnavailableError with the reason if it cannot be given)."""
    metric, argument = parse_metric(name)
    return metric.compute(run, argument)
