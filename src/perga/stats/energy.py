"""Energy statistics of impacts: restitution, losses in the hammer and lab frames, every
efficiency of :func:`perga.analytic.impact.impact_efficiencies`, the hinged-hammer prediction,
successive impacts and impact-speed histograms (SI units).

An impact row (impacts.csv) gives the granule's velocity relative to the hammer's material point
at the contact, along the hammer's outward normal n (v_n < 0 approaching) and the tangent t,
before and after; the normal impulse J; the granule's KE change (lab frame); the energy the
contact dissipated; the hammer's KE before. From these alone: e = −v_n'/v_n and the reduced
mass μ = J/(v_n' − v_n), since the relative normal velocity changes by J(1/m + 1/M_eff).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perga.analytic.impact import HingedImpact, hinged_impact
from perga.stats.tables import Run, hammer_mount_angle

FloatArray = NDArray[np.float64]

HEAD_ON = 1e-6
"""|v_t|/|v_n| below which an impact is head-on and β = −v_t'/v_t is not defined."""

HAMMER_AT_REST = 1e-6
"""The hammer's kinetic energy before an impact over the impact's ½μv_n² below which the hammer
is at rest for it (e.g. a granule thrown at a standing hammer): a ratio to the hammer's energy
is not defined (it would be the granule's energy over round-off)."""


@dataclass(frozen=True)
class ImpactStats:
    """One impact's statistics, measured from the recorded tables."""

    time: float
    """s."""
    hammer: int
    approach_speed: float
    """−v_n before: normal speed of approach relative to the hammer's material point, m/s."""
    restitution: float
    """e = −v_n'/v_n, -."""
    tangential_restitution: float
    """β = −v_t'/v_t of the contact point, - (nan for a head-on impact, |v_t| <= HEAD_ON·|v_n|)."""
    rebound_angle: float
    """The contact point's relative velocity after the impact from the normal, atan2(±v_t',
    v_n'), positive on the side v_t had before (forward), rad."""
    tangential_restitution_centre: float
    """β_c = −u_t'/u_t of the granule's centre, u_t = v_t + ω r its tangential velocity relative
    to the hammer's material point at the contact (v_t taken at the granule's rim), - (nan
    head-on, or without the spins)."""
    rebound_angle_centre: float
    """The centre's relative velocity after the impact from the normal, atan2(±u_t', v_n'),
    positive on the side u_t had before (forward), rad (nan without the spins)."""
    rebound_speed: float
    """|(v_n', v_t')|, the relative speed after the impact, m/s."""
    reduced_mass: float
    """μ = J/(v_n' − v_n), kg."""
    normal_loss: float
    """Fraction of the normal relative-motion KE ½μv_n² lost, 1 − e², - (the analytic
    ``hammer_frame_loss``)."""
    hammer_frame_loss: float
    """Fraction of the granule's KE relative to the hammer's contact point lost,
    1 − (v_n'² + v_t'²)/(v_n² + v_t²), - (normal and friction)."""
    lab_energy_before: float
    """Granule KE (translation and spin) in the lab at the last frame before the impact, J."""
    lab_gain: float
    """Granule KE change in the lab frame, J (> 0: the hammer gave it energy)."""
    lab_loss: float
    """−lab_gain/lab_energy_before, - (nan for a granule at rest before)."""
    dissipated: float
    """Energy dissipated in the contact, J."""
    transfer: float
    """lab_gain / hammer KE before, - (analytic ``transfer``)."""
    dissipated_ratio: float
    """dissipated / hammer KE before, - (analytic ``dissipated``)."""
    relative: float
    """lab_gain / ½μv_n², - (analytic ``relative``)."""

    def as_dict(self) -> dict[str, float]:
        """Plain data for JSON."""
        return asdict(self)


def granule_radius(run: Run, granule: int) -> float:
    """A granule's radius, m: granules.csv's where recorded, else the case's."""
    g = run.granules
    if g and "radius" in g:
        rows = g["id"] == granule
        if rows.any():
            return float(g["radius"][rows][0])
    return run.case.granules.radius


def granule_energy(run: Run, granule: int, t: float, before: bool = True) -> float:
    """Granule KE (J) at the last frame before t (``before``) or the first frame after it."""
    track = run.track(granule)
    times = track["time"]
    i = (
        int(np.searchsorted(times, t, side="left")) - 1
        if before
        else int(np.searchsorted(times, t, side="right"))
    )
    i = min(max(i, 0), times.size - 1)
    if "mass" in track:  # each granule's own (granules.csv since sizes vary)
        m, r = float(track["mass"][i]), float(track["radius"][i])
    else:
        m, r = run.case.granule_mass, run.case.granules.radius
    spin_inertia = 0.5 * m * r**2 if run.case.granules.rolls else 0.0
    return 0.5 * m * float(track["speed"][i]) ** 2 + 0.5 * spin_inertia * float(
        track["angular_velocity"][i] ** 2
    )


def rebound_angle(tangential: float, tangential_after: float, normal_after: float) -> float:
    """The rebound's angle from the normal, rad: atan2 of the tangential velocity after and the
    normal one, positive on the side the tangential velocity had before (forward: a rebound
    test's convention; friction alone never turns a centre without spin back)."""
    forward = tangential_after if tangential >= 0.0 else -tangential_after
    return math.atan2(forward, normal_after)


def _ratio(a: float, b: float) -> float:
    """a/b, nan where b is 0 (a ratio the impact does not define)."""
    return a / b if b != 0.0 else math.nan


def impact_stats(run: Run, index: int) -> ImpactStats:
    """Statistics of impact ``index`` (row of impacts.csv); a ratio the impact does not define
    (a zero approach speed, a hammer at rest) is nan."""
    row = {k: float(v[index]) for k, v in run.impacts.items()}
    vn, vn1 = row["normal_velocity_before"], row["normal_velocity_after"]
    vt, vt1 = row["tangential_velocity_before"], row["tangential_velocity_after"]
    # the centre moves along t at the contact point's velocity plus its rim's, ω r
    r = granule_radius(run, int(row["granule"]))
    ut = vt + row.get("granule_spin_before", math.nan) * r
    ut1 = vt1 + row.get("granule_spin_after", math.nan) * r
    mu = _ratio(row["normal_impulse"], vn1 - vn)
    relative_energy = 0.5 * mu * vn**2
    before = granule_energy(run, int(row["granule"]), row["time"])
    gain, hammer = row["granule_energy_gain"], row["hammer_energy_before"]
    if hammer < HAMMER_AT_REST * relative_energy:
        hammer = 0.0
    return ImpactStats(
        time=row["time"],
        hammer=int(row["hammer"]),
        approach_speed=-vn,
        restitution=_ratio(-vn1, vn),
        tangential_restitution=_ratio(-vt1, vt) if abs(vt) > HEAD_ON * abs(vn) else math.nan,
        rebound_angle=rebound_angle(vt, vt1, vn1),
        tangential_restitution_centre=_ratio(-ut1, ut) if abs(ut) > HEAD_ON * abs(vn) else math.nan,
        rebound_angle_centre=rebound_angle(ut, ut1, vn1),
        rebound_speed=math.hypot(vn1, vt1),
        reduced_mass=mu,
        normal_loss=1 - _ratio(vn1, vn) ** 2,
        hammer_frame_loss=1 - _ratio(vn1**2 + vt1**2, vn**2 + vt**2),
        lab_energy_before=before,
        lab_gain=gain,
        lab_loss=-gain / before if before > 0 else math.nan,
        dissipated=row["dissipated"],
        transfer=_ratio(gain, hammer),
        dissipated_ratio=_ratio(row["dissipated"], hammer),
        relative=_ratio(gain, relative_energy),
    )


def all_impacts(run: Run) -> list[ImpactStats]:
    """:func:`impact_stats` of every recorded impact, in time order."""
    n = run.impacts["time"].size if run.impacts else 0
    return [impact_stats(run, i) for i in range(n)]


def hinged_prediction(run: Run, index: int) -> HingedImpact:
    """:func:`perga.analytic.impact.hinged_impact` for impact ``index`` of a plate hammer hinged
    on a rotor turning at constant ω, from the impact's row of impacts.csv: contact point and
    normal, the granule's velocity and the hammer's swing angle and Ω at the impact, and the
    hinge at the rotor angle of the impact (hammers.csv). Frictionless and instantaneous.
    """
    case = run.case
    if case.hammers.mount != "hinged" or case.hammers.shape.kind != "plate":
        raise ValueError(f"{run.name}: the hinged prediction needs hinged plate hammers")
    row = {k: float(v[index]) for k, v in run.impacts.items()}
    hammer, t = int(row["hammer"]), row["time"]
    plate = case.hammer_plate
    hinge_angle = float(run.rotor_angle(t)) + hammer_mount_angle(case, hammer)
    axis = hinge_angle + row["hammer_swing_angle_before"]
    hinge = case.hammers.hinge_radius * np.array([math.cos(hinge_angle), math.sin(hinge_angle)])
    normal = np.array([row["nx"], row["ny"]])
    return hinged_impact(
        M=case.hammers.mass,
        I_A=plate.inertia_about_hinge,
        r_c=plate.hinge_to_centre_of_mass * np.array([math.cos(axis), math.sin(axis)]),
        r_k=np.array([row["x"], row["y"]]) - hinge,
        n=normal / np.hypot(*normal),
        Omega=row["hammer_angular_velocity_before"],
        v_A=run.omega * np.array([-hinge[1], hinge[0]]),
        m=case.granule_mass,
        v_g=np.array([row["vx_before"], row["vy_before"]]),
        e=case.granule_hammer_contact.restitution,
    )


@dataclass(frozen=True)
class SuccessiveEnergies:
    """Energies after each impact of one granule, J, and as fractions of the first."""

    times: FloatArray
    lab: FloatArray
    """Granule KE in the lab after each impact (KE before + the recorded gain), J."""
    relative: FloatArray
    """½μv_n'², the normal relative-motion KE after each impact, J."""

    @property
    def lab_fraction(self) -> FloatArray:
        """lab / lab[0], -."""
        return self.lab / self.lab[0]

    @property
    def relative_fraction(self) -> FloatArray:
        """relative / relative[0], -."""
        return self.relative / self.relative[0]


def successive_energies(run: Run, granule: int = 0, count: int | None = None) -> SuccessiveEnergies:
    """Energies after the first ``count`` impacts of ``granule`` (all if None)."""
    rows = np.nonzero(run.impacts["granule"] == granule)[0][:count]
    stats = [impact_stats(run, int(i)) for i in rows]
    lab = np.array([s.lab_energy_before + s.lab_gain for s in stats])
    rel = np.array([0.5 * s.reduced_mass * (s.restitution * s.approach_speed) ** 2 for s in stats])
    return SuccessiveEnergies(np.array([s.time for s in stats]), lab, rel)


def impact_speed_histogram(
    speeds: ArrayLike, bins: int | ArrayLike = 20
) -> tuple[FloatArray, FloatArray]:
    """(counts, bin edges in m/s) of impact approach speeds."""
    counts, edges = np.histogram(np.asarray(speeds, dtype=float), bins=bins)
    return counts.astype(float), edges
