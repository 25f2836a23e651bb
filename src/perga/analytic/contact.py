"""Normal contact laws of the DEM and their closed-form calibration (SI units).

Two soft-contact laws for the normal force F(δ, δ̇) between two bodies of reduced mass m_eff
(``perga.analytic.common.reduced_mass``: m/2 for two equal granules, m for a granule on a wall,
m·M/(m + M) for a granule on a hammer):

* linear spring-dashpot F = k δ + c δ̇ (Cundall & Strack 1979), solved in closed form;
* Hertz with Tsuji damping F = k_n δ^{3/2} + α √(m_eff k_n) δ^{1/4} δ̇ (Tsuji et al. 1992),
  whose coefficient of restitution is closed form (Antypov & Elliott, EPL 94 (2011) 50004) and
  whose duration and peaks come from one dimensionless integration per α.

A contact starts at t = 0 with δ = 0, δ̇ = v0 > 0. Two criteria for its end are supported
(argument ``end``):

* ``"overlap"``: the contact ends when δ returns to 0. Near the end δ̇ < 0 makes the viscous
  term dominate, so the force is slightly attractive (Luding 2008 Granular Matter).
* ``"force"``: the force is clamped at F ≥ 0 and the contact ends when F returns to 0; the
  bodies then separate with some overlap left (Schwager & Pöschel, Granular Matter 9 (2007)
  465). For the same damping, e is higher than with ``"overlap"``.

Also the DEM time step: a fraction of the contact duration, and the tunnelling bound for thin
walls and hammers.
"""

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Literal

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import gamma

End = Literal["overlap", "force"]
"""Contact-end criterion: overlap back to zero, or (clamped) force back to zero."""

FORCE_END_MIN_RESTITUTION = math.exp(-2.0)
"""Infimum of e with ``end="force"``: e → e^-2 ≈ 0.1353 as ζ → 1 (critical damping), dimensionless.

A lower e needs an overdamped contact (ζ ≥ 1), which the closed forms here do not cover
(Schwager & Pöschel 2007).
"""

TSUJI_MAX_ALPHA = math.sqrt(5.0)
"""Upper bound √5 of the Tsuji damping factor α: α = √5 ζ with ζ < 1 (Antypov & Elliott 2011)."""

HERTZ_DURATION_COEFFICIENT = (
    0.8 * math.sqrt(math.pi) * gamma(0.4) / gamma(0.9) * 1.25**0.4
)  # = 3.2180654597...
"""C in the undamped Hertz contact duration t_c = C·(m_eff²/(k_n² v0))^{1/5}, dimensionless.

C = (4/5)·√π·Γ(2/5)/Γ(9/10)·(5/4)^{2/5} ≈ 3.21807, from t_c = 2∫₀^δmax dδ/δ̇ (Johnson, Contact
Mechanics (1985) §11.4; Thornton, Granular Dynamics (2015)). With k_n = (4/3) E* √R_eff the
same law reads 2.86827·(m_eff²/(R_eff E*² v0))^{1/5}; 2.8683 is *not* the coefficient for k_n.
"""

_ZETA_BELOW_ONE = math.nextafter(1.0, 0.0)
_MERCURYDPM_FRACTION = 1.0 / 50.0


def _check_in(
    name: str,
    value: float,
    low: float,
    high: float,
    *,
    low_closed: bool = False,
    high_closed: bool = False,
    unit: str = "",
) -> None:
    """Raise ValueError naming ``name``, its value and the allowed interval (NaN is rejected)."""
    above = value >= low if low_closed else value > low
    below = value <= high if high_closed else value < high
    if not (above and below):
        interval = f"{'[' if low_closed else '('}{low:g}, {high:g}{']' if high_closed else ')'}"
        raise ValueError(f"{name} must be in {interval}{unit} (got {value})")


def _check_end(end: str) -> None:
    if end not in ("overlap", "force"):
        raise ValueError(f"end must be 'overlap' or 'force' (got {end!r})")


def _check_restitution(e: float, end: End) -> None:
    _check_end(end)
    _check_in("e", e, 0.0, 1.0, high_closed=True)
    if end == "force" and not math.log(e) > -2.0:
        raise ValueError(
            f"e must be in (exp(-2) = {FORCE_END_MIN_RESTITUTION:.6f}, 1] for end='force' "
            f"(got {e}); a lower e needs an overdamped contact (zeta >= 1); end='overlap' "
            "reaches any e > 0"
        )


def _end_phase(zeta: float, end: End) -> float:
    """Damped phase ω_d·t at the end of contact: π (δ = 0) or 2·arccos ζ (F = 0), rad."""
    return math.pi if end == "overlap" else 2.0 * math.acos(zeta)


def _log_decrement(zeta: float, end: End) -> float:
    """−ln e = ζ·θ_end/√(1 − ζ²), θ_end from ``_end_phase``; 0 ≤ ζ < 1."""
    return zeta * _end_phase(zeta, end) / math.sqrt((1.0 - zeta) * (1.0 + zeta))


def restitution(zeta: float, end: End = "overlap") -> float:
    """Coefficient of restitution e(ζ) of a linear spring-dashpot, dimensionless.

    e = exp(−ζ θ_end/√(1 − ζ²)) with θ_end = π for ``end="overlap"`` (Luding 2008 Granular
    Matter; Thornton, Granular Dynamics (2015)) and θ_end = 2 arccos ζ for ``end="force"``
    (Schwager & Pöschel, Granular Matter 9 (2007) 465). Derivation of the latter: with
    δ = (v0/ω_d) e^{−ζω_n t} sin(ω_d t) the force is F = (k v0/ω_d) e^{−ζω_n t} sin(2φ − ω_d t),
    φ = arccos ζ, so F = 0 at ω_d t = 2φ, where δ̇ = −v0 e^{−ζω_n t}.

    Valid for an underdamped contact, ζ in [0, 1); e does not depend on k, m_eff or v0.
    """
    _check_end(end)
    _check_in("zeta", zeta, 0.0, 1.0, low_closed=True)
    return math.exp(-_log_decrement(zeta, end))


def damping_ratio(e: float, end: End = "overlap") -> float:
    """Damping ratio ζ = c/(2√(k m_eff)) of a linear spring-dashpot giving restitution e.

    ``end="overlap"``: ζ = −ln e/√(π² + ln² e), closed form (Luding 2008 Granular Matter).
    ``end="force"``: root of e(ζ) = e from ``restitution`` (Schwager & Pöschel 2007), by brentq
    to 4 eps relative (≤ 1e-15); e = 0.7 needs ζ = 0.122215 instead of 0.112808.

    Valid for e in (0, 1] (overlap) or (e^-2, 1] ≈ (0.1353, 1] (force); e = 1 gives ζ = 0.
    """
    _check_restitution(e, end)
    log_e = abs(math.log(e))
    if end == "overlap":
        return log_e / math.hypot(math.pi, log_e)
    # xtol ≈ 0 leaves brentq's rtol (4 eps) in charge: full relative precision even for tiny ζ.
    return brentq(lambda z: _log_decrement(z, end) - log_e, 0.0, _ZETA_BELOW_ONE, xtol=1e-300)


def tsuji_alpha(e: float, end: End = "overlap") -> float:
    """Tsuji damping factor α giving restitution e for Hertz F = k_n δ^{3/2} + α√(m k_n) δ^{1/4} δ̇.

    α = √5·ζ(e), ζ from ``damping_ratio``; for ``end="overlap"`` α = √5|ln e|/√(π² + ln² e)
    (Antypov & Elliott, EPL 94 (2011) 50004). Exact, for both end criteria: in dimensionless form
    u'' = −u^{3/2} − α u^{1/4} u', the substitutions dσ = u^{1/4} dτ and u = w^{4/5} give the
    linear oscillator w_σσ + α w_σ + (5/4) w = 0, with u' = (4/5) w_σ and
    F ∝ w^{1/5}((5/4) w + α w_σ). Dimensionless, velocity independent; e in (0, 1] (overlap)
    or (e^-2, 1] (force).
    """
    return TSUJI_MAX_ALPHA * damping_ratio(e, end)


@dataclass(frozen=True)
class ImpactResponse:
    """One normal impact at speed v0 from first touch (t = 0, δ = 0, δ̇ = v0) to contact end.

    Times in s from first touch, overlap in m, force in N (repulsive > 0); the duration follows
    the contact law's end criterion.
    """

    v0: float
    duration: float
    peak_overlap: float
    peak_overlap_time: float
    peak_force: float
    peak_force_time: float


@dataclass(frozen=True)
class LinearSpringDashpot:
    """Linear spring-dashpot normal contact F = k δ + c δ̇ (Cundall & Strack 1979).

    k: stiffness, N/m; zeta: damping ratio ζ = c/(2√(k m_eff)) in [0, 1); m_eff: reduced mass,
    kg; end: contact-end criterion. Closed forms (Luding 2008 Granular Matter; Thornton, Granular
    Dynamics (2015); Schwager & Pöschel 2007 for ``end="force"``): ω_n = √(k/m_eff),
    ω_d = ω_n√(1 − ζ²), δ(t) = (v0/ω_d) e^{−ζω_n t} sin(ω_d t). Valid for an underdamped contact.
    """

    k: float
    zeta: float
    m_eff: float
    end: End = "overlap"

    def __post_init__(self) -> None:
        _check_in("k", self.k, 0.0, math.inf, unit=" N/m")
        _check_in("zeta", self.zeta, 0.0, 1.0, low_closed=True)
        _check_in("m_eff", self.m_eff, 0.0, math.inf, unit=" kg")
        _check_end(self.end)

    @classmethod
    def from_stiffness(
        cls, k: float, e: float, m_eff: float, end: End = "overlap"
    ) -> "LinearSpringDashpot":
        """Contact of stiffness k (N/m) and restitution e on reduced mass m_eff (kg); ζ = ζ(e).

        Valid for e in (0, 1] (overlap) or (e^-2, 1] (force); see ``damping_ratio``.
        """
        return cls(k, damping_ratio(e, end), m_eff, end)

    @classmethod
    def from_duration(
        cls, t_c: float, e: float, m_eff: float, end: End = "overlap"
    ) -> "LinearSpringDashpot":
        """Contact lasting t_c (s, under ``end``) with restitution e on reduced mass m_eff (kg).

        k = m_eff ω_n² with ω_n = θ_end/(t_c √(1 − ζ²)), θ_end = π (overlap) or 2 arccos ζ
        (force) (Luding 2008 Granular Matter; Schwager & Pöschel 2007). Valid as ``from_stiffness``.
        """
        _check_in("t_c", t_c, 0.0, math.inf, unit=" s")
        zeta = damping_ratio(e, end)
        omega_n = _end_phase(zeta, end) / (t_c * math.sqrt((1.0 - zeta) * (1.0 + zeta)))
        return cls(m_eff * omega_n**2, zeta, m_eff, end)

    @property
    def c(self) -> float:
        """Damping coefficient c = 2ζ√(k m_eff), N·s/m."""
        return 2.0 * self.zeta * math.sqrt(self.k * self.m_eff)

    @property
    def omega_n(self) -> float:
        """Undamped angular frequency ω_n = √(k/m_eff), rad/s."""
        return math.sqrt(self.k / self.m_eff)

    @property
    def omega_d(self) -> float:
        """Damped angular frequency ω_d = ω_n √(1 − ζ²), rad/s."""
        return self.omega_n * math.sqrt((1.0 - self.zeta) * (1.0 + self.zeta))

    @property
    def e(self) -> float:
        """Coefficient of restitution under ``end`` (see ``restitution``), dimensionless."""
        return restitution(self.zeta, self.end)

    @property
    def duration(self) -> float:
        """Contact duration t_c = π/ω_d (overlap) or 2 arccos(ζ)/ω_d (force), s; v0-independent."""
        return _end_phase(self.zeta, self.end) / self.omega_d

    def impact(self, v0: float) -> ImpactResponse:
        """Closed-form response to a normal impact at speed v0 > 0 (m/s).

        With φ = arccos ζ and θ = ω_d t: δ = (v0/ω_d) e^{−ζθ/√(1−ζ²)} sin θ, maximal at θ = φ;
        F = k (v0/ω_d) e^{−ζθ/√(1−ζ²)} sin(2φ − θ), which jumps to F(0) = c v0 and has its interior
        maximum where sin(θ − 3φ) = 0, i.e. θ = 3φ − π: inside the contact only for ζ < 1/2; for
        ζ ≥ 1/2 the peak force is c v0 at t = 0 (Cundall & Strack 1979; Thornton, Granular
        Dynamics (2015)). All amplitudes scale with v0; the times do not depend on it.
        """
        _check_in("v0", v0, 0.0, math.inf, unit=" m/s")
        phi = math.acos(self.zeta)
        theta_force = max(3.0 * phi - math.pi, 0.0)

        def envelope(theta: float) -> float:
            return v0 / self.omega_d * math.exp(-self.zeta * theta / math.sin(phi))

        return ImpactResponse(
            v0=v0,
            duration=self.duration,
            peak_overlap=envelope(phi) * math.sin(phi),
            peak_overlap_time=phi / self.omega_d,
            peak_force=self.k * envelope(theta_force) * math.sin(2.0 * phi - theta_force),
            peak_force_time=theta_force / self.omega_d,
        )


@lru_cache(maxsize=512)
def _hertz_tsuji_unit_impact(alpha: float, end: End) -> ImpactResponse:
    """Dimensionless impact u'' = −u^{3/2} − α u^{1/4} u', u(0) = 0, u'(0) = 1 (Tsuji et al. 1992).

    Peak overlap closed form u_max = (√5/2)^{4/5} exp(−(4/5) ζφ/√(1 − ζ²)), ζ = α/√5,
    φ = arccos ζ (maximum of the linear oscillator w of ``tsuji_alpha``, u = w^{4/5}). For α = 0
    the undamped closed forms (τ_c = HERTZ_DURATION_COEFFICIENT, peaks at τ_c/2); otherwise the
    duration and the times and value of the peak force come from solve_ivp (DOP853, rtol 1e-12).
    """
    zeta = alpha / TSUJI_MAX_ALPHA
    phi = math.acos(zeta)
    u_max = (0.5 * math.sqrt(5.0)) ** 0.8 * math.exp(-0.8 * zeta * phi / math.sin(phi))
    if alpha == 0.0:
        half = 0.5 * HERTZ_DURATION_COEFFICIENT
        return ImpactResponse(1.0, 2.0 * half, u_max, half, u_max**1.5, half)

    def acceleration(u: float, du: float) -> float:
        return -(u**1.5) - alpha * u**0.25 * du

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        return [y[1], acceleration(max(y[0], 0.0), y[1])]

    def overlap_zero(_t: float, y: np.ndarray) -> float:
        return y[0]

    def force_zero(_t: float, y: np.ndarray) -> float:  # F/u^{1/4}; F = 0 while u > 0 if α > 0
        return max(y[0], 0.0) ** 1.25 + alpha * y[1]

    def overlap_peak(_t: float, y: np.ndarray) -> float:
        return y[1]

    def force_peak(_t: float, y: np.ndarray) -> float:  # u^{3/4}·dF/dτ
        u, du = max(y[0], 0.0), y[1]
        return 1.5 * u**1.25 * du + alpha * (0.25 * du * du + u * acceleration(u, du))

    end_event = overlap_zero if end == "overlap" else force_zero
    end_event.terminal = True
    for event in (end_event, overlap_peak, force_peak):
        event.direction = -1.0
    sol = solve_ivp(
        rhs,
        (0.0, math.inf),
        [0.0, 1.0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-15,
        events=[end_event, overlap_peak, force_peak],
    )
    if sol.status != 1:
        raise RuntimeError(f"Hertz-Tsuji integration did not reach contact end: {sol.message}")
    u_force, du_force = (float(x) for x in sol.y_events[2][0])
    return ImpactResponse(
        v0=1.0,
        duration=float(sol.t_events[0][0]),
        peak_overlap=u_max,
        peak_overlap_time=float(sol.t_events[1][0]),
        peak_force=-acceleration(u_force, du_force),
        peak_force_time=float(sol.t_events[2][0]),
    )


@dataclass(frozen=True)
class HertzTsuji:
    """Hertz contact with Tsuji damping, F = k_n δ^{3/2} + α √(m_eff k_n) δ^{1/4} δ̇.

    k_n: Hertz stiffness, N/m^{3/2} (``hertz_stiffness``); alpha: Tsuji damping factor in
    [0, √5), dimensionless; m_eff: reduced mass, kg; end: contact-end criterion (Tsuji et al.,
    Powder Technol. 71 (1992) 239; Antypov & Elliott, EPL 94 (2011) 50004). e depends on α only.
    Scales: δ* = (m_eff v0²/k_n)^{2/5}, t* = δ*/v0, F* = k_n δ*^{3/2}.
    """

    k_n: float
    alpha: float
    m_eff: float
    end: End = "overlap"

    def __post_init__(self) -> None:
        _check_in("k_n", self.k_n, 0.0, math.inf, unit=" N/m^1.5")
        _check_in("alpha", self.alpha, 0.0, TSUJI_MAX_ALPHA, low_closed=True)
        _check_in("m_eff", self.m_eff, 0.0, math.inf, unit=" kg")
        _check_end(self.end)

    @classmethod
    def from_restitution(
        cls, k_n: float, e: float, m_eff: float, end: End = "overlap"
    ) -> "HertzTsuji":
        """Contact of stiffness k_n (N/m^{3/2}), restitution e, reduced mass m_eff (kg); α = α(e).

        Valid for e in (0, 1] (overlap) or (e^-2, 1] (force).
        """
        return cls(k_n, tsuji_alpha(e, end), m_eff, end)

    @property
    def eta(self) -> float:
        """Damping coefficient η = α √(m_eff k_n), N·s/m^{5/4}."""
        return self.alpha * math.sqrt(self.m_eff * self.k_n)

    @property
    def e(self) -> float:
        """Coefficient of restitution e = restitution(α/√5, end) (see ``tsuji_alpha``), exact."""
        return restitution(self.alpha / TSUJI_MAX_ALPHA, self.end)

    def impact(self, v0: float) -> ImpactResponse:
        """Response to a normal impact at speed v0 > 0 (m/s), scaled from the dimensionless one.

        Undamped (α = 0, Hertz 1882; Johnson, Contact Mechanics (1985)): δ_max =
        (5 m_eff v0²/(4 k_n))^{2/5}, t_c = HERTZ_DURATION_COEFFICIENT·(m_eff²/(k_n² v0))^{1/5},
        F_max = k_n δ_max^{3/2} at t_c/2. Damped: the peak overlap is closed form, the duration and
        the peak force come from one integration per (α, end), cached (rtol 1e-12).
        """
        _check_in("v0", v0, 0.0, math.inf, unit=" m/s")
        length = (self.m_eff * v0 * v0 / self.k_n) ** 0.4
        time = length / v0
        force = self.k_n * length**1.5
        unit = _hertz_tsuji_unit_impact(self.alpha, self.end)
        return ImpactResponse(
            v0=v0,
            duration=unit.duration * time,
            peak_overlap=unit.peak_overlap * length,
            peak_overlap_time=unit.peak_overlap_time * time,
            peak_force=unit.peak_force * force,
            peak_force_time=unit.peak_force_time * time,
        )


def effective_modulus(E: tuple[float, float], nu: tuple[float, float]) -> float:
    """Contact modulus E* of two materials, 1/E* = (1 − ν1²)/E1 + (1 − ν2²)/E2, Pa.

    E: Young's moduli (Pa), each in (0, inf] (inf: a rigid body); nu: Poisson ratios, each in
    (−1, 0.5] (Johnson, Contact Mechanics (1985) §4.2). At most one body may be rigid.
    """
    for i, (E_i, nu_i) in enumerate(zip(E, nu, strict=True)):
        _check_in(f"E[{i}]", E_i, 0.0, math.inf, high_closed=True, unit=" Pa")
        _check_in(f"nu[{i}]", nu_i, -1.0, 0.5, high_closed=True)
    compliance = sum((1.0 - nu_i**2) / E_i for E_i, nu_i in zip(E, nu, strict=True))
    if compliance == 0.0:
        raise ValueError(f"E must not be infinite for both bodies (got {E})")
    return 1.0 / compliance


def hertz_stiffness(E: tuple[float, float], nu: tuple[float, float], R_eff: float) -> float:
    """Hertz normal stiffness k_n = (4/3) E* √R_eff, N/m^{3/2}, so that F = k_n δ^{3/2}.

    E*: ``effective_modulus`` of the two materials (Pa); R_eff = R1 R2/(R1 + R2) (m; R for a
    sphere on a flat wall). This is the sphere (3-D) Hertz law (Johnson, Contact Mechanics (1985);
    Thornton, Granular Dynamics (2015)); perga uses it in 2-D as a modelling choice (a true 2-D,
    cylinder contact is nearly linear in δ). Valid for small elastic overlaps, δ ≪ R_eff.
    """
    _check_in("R_eff", R_eff, 0.0, math.inf, unit=" m")
    return 4.0 / 3.0 * effective_modulus(E, nu) * math.sqrt(R_eff)


def contact_time_step(t_c: float, fraction: float = _MERCURYDPM_FRACTION) -> float:
    """Time step resolving a contact, dt = fraction·t_c, s (t_c: contact duration, s).

    Default fraction 1/50 (MercuryDPM convention; Thornton, Granular Dynamics (2015) discusses
    similar resolutions); fraction in (0, 1].
    """
    _check_in("t_c", t_c, 0.0, math.inf, unit=" s")
    _check_in("fraction", fraction, 0.0, 1.0, high_closed=True)
    return fraction * t_c


def tunnelling_time_step(radius: float, thickness: float, v_rel_max: float) -> float:
    """Largest step without tunnelling through a wall, dt = 0.5 (r + t/2)/v_rel,max, s.

    A granule of radius r (m) touching a wall or hammer of thickness t (m, 0 for a line wall)
    has its centre r + t/2 from the wall mid-line; if the centre crossed it in one step the
    contact normal would flip and push the granule through. The step is limited to half that
    distance at the largest relative normal speed v_rel,max (m/s). Kinematic bound, any law.
    """
    _check_in("radius", radius, 0.0, math.inf, unit=" m")
    _check_in("thickness", thickness, 0.0, math.inf, low_closed=True, unit=" m")
    _check_in("v_rel_max", v_rel_max, 0.0, math.inf, unit=" m/s")
    return 0.5 * (radius + 0.5 * thickness) / v_rel_max


@dataclass(frozen=True)
class TimeStep:
    """The two DEM time-step bounds, s: contact resolution and tunnelling (see ``time_step``)."""

    contact: float
    tunnelling: float

    @property
    def dt(self) -> float:
        """Time step to use, min(contact, tunnelling), s."""
        return min(self.contact, self.tunnelling)

    @property
    def governed_by(self) -> Literal["contact", "tunnelling"]:
        """Which bound sets dt ("contact" on a tie)."""
        return "contact" if self.contact <= self.tunnelling else "tunnelling"


def time_step(
    t_c: float,
    radius: float,
    thickness: float,
    v_rel_max: float,
    fraction: float = _MERCURYDPM_FRACTION,
) -> TimeStep:
    """Both time-step bounds: ``contact_time_step(t_c, fraction)`` and ``tunnelling_time_step``.

    t_c: contact duration, s; radius: smallest granule radius, m; thickness: thinnest wall or
    hammer, m; v_rel_max: largest relative normal speed, m/s (MercuryDPM convention for the
    contact bound). Use ``.dt`` and ``.governed_by``.
    """
    return TimeStep(
        contact=contact_time_step(t_c, fraction),
        tunnelling=tunnelling_time_step(radius, thickness, v_rel_max),
    )


def mindlin_ratio(E: tuple[float, float], nu: tuple[float, float]) -> float:
    """Mindlin's tangential over Hertz's secant normal stiffness, k_t/k_n = 6G*/E*, of two
    materials: the ratio on perga's Hertz k_n√(R*δ), whose k_t = 8G*√(R*δ) (Mindlin 1949;
    Johnson, Contact Mechanics (1985) §7.2), 1/G* = (2 − ν1)/G1 + (2 − ν2)/G2, G = E/(2(1 + ν)),
    E* as ``effective_modulus``. For one material (or one on a rigid body) 3(1 − ν)/(2 − ν):
    1 at ν = 0.5, 1.5 at ν = 0, → 2 as ν → −1; two materials weight theirs by (1 − ν²)/E.
    """
    shear = sum(2.0 * (2.0 - n) * (1.0 + n) / e for e, n in zip(E, nu, strict=True))
    return 6.0 / (effective_modulus(E, nu) * shear)
