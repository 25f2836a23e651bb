"""Tests of perga.analytic.contact against direct numerical integration of the contact ODEs."""

import dataclasses
import math
import re
from collections.abc import Callable

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

from perga.analytic.contact import (
    HERTZ_DURATION_COEFFICIENT,
    HertzTsuji,
    ImpactResponse,
    LinearSpringDashpot,
    contact_time_step,
    damping_ratio,
    effective_modulus,
    hertz_stiffness,
    restitution,
    time_step,
    tsuji_alpha,
    tunnelling_time_step,
)

# solve_ivp at rtol 1e-12 leaves ~1e-9 relative error in the measured e, duration and peaks;
# 1e-6 is the requirement.
TOL = 1e-6
# The peak-force time sits on a flat maximum: a value error ε moves it by ~√ε, so 1e-5 of t_c.
PEAK_FORCE_TIME_TOL = 1e-5
E_MIN = {"overlap": 0.05, "force": 0.14}  # "force" needs e > e^-2 = 0.1353 (underdamped)
ENDS = ["overlap", "force"]

Force = Callable[[np.ndarray, np.ndarray], np.ndarray]


def log_uniform(low: float, high: float) -> st.SearchStrategy[float]:
    """Floats spread evenly in log10 over [low, high]."""
    return st.floats(math.log10(low), math.log10(high)).map(lambda x: 10.0**x)


MASSES = log_uniform(1e-6, 1.0)
SPEEDS = log_uniform(1e-3, 50.0)


def hertz_tsuji_force(k_n: float, eta: float) -> Force:
    """F = k_n δ^{3/2} + η δ^{1/4} δ̇, continued to δ < 0 as −k_n|δ|^{3/2} + η|δ|^{1/4} δ̇.

    The continuation keeps F < 0 after separation (δ̇ < 0), so the only F = 0 crossing is the end
    of contact and an integration step cannot straddle a pair of sign changes.
    """
    return lambda d, v: k_n * np.sign(d) * np.abs(d) ** 1.5 + eta * np.abs(d) ** 0.25 * v


def integrate_impact(
    force: Force, m_eff: float, v0: float, length: float, end: str
) -> tuple[float, ImpactResponse]:
    """Integrate m_eff δ'' = −F(δ, δ̇) from δ = 0, δ̇ = v0; return the measured e and response.

    length: overlap scale (m) for atol. The contact ends at δ = 0 or F = 0 (``end``); the peak
    force is the larger of F(0) (a jump for a dashpot) and the refined interior grid maximum.
    """

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        return [y[1], -force(y[0], y[1]) / m_eff]

    def contact_end(_t: float, y: np.ndarray) -> float:
        return y[0] if end == "overlap" else force(y[0], y[1])

    def overlap_peak(_t: float, y: np.ndarray) -> float:
        return y[1]

    contact_end.terminal = True
    contact_end.direction = -1.0
    overlap_peak.direction = -1.0
    sol = solve_ivp(
        rhs,
        (0.0, math.inf),
        [0.0, v0],
        method="DOP853",
        rtol=1e-12,
        atol=[1e-12 * length, 1e-12 * v0],
        events=[contact_end, overlap_peak],
        dense_output=True,
    )
    assert sol.status == 1, sol.message
    t_end = sol.t_events[0][0]
    grid = np.linspace(0.0, t_end, 2001)
    forces = force(*sol.sol(grid))
    i = int(np.argmax(forces))
    refined = minimize_scalar(
        lambda t: -force(*sol.sol(t)),
        bounds=(grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]),
        method="bounded",
        options={"xatol": 1e-14 * t_end},
    )
    peak_force, peak_force_time = max((float(forces[0]), 0.0), (-refined.fun, refined.x))
    response = ImpactResponse(
        v0=v0,
        duration=t_end,
        peak_overlap=sol.y_events[1][0][0],
        peak_overlap_time=sol.t_events[1][0],
        peak_force=peak_force,
        peak_force_time=peak_force_time,
    )
    return -sol.y_events[0][0][1] / v0, response


def assert_matches(measured: ImpactResponse, expected: ImpactResponse) -> None:
    t_c = expected.duration
    assert measured.duration == pytest.approx(t_c, rel=TOL)
    assert measured.peak_overlap == pytest.approx(expected.peak_overlap, rel=TOL)
    assert measured.peak_overlap_time == pytest.approx(expected.peak_overlap_time, abs=TOL * t_c)
    assert measured.peak_force == pytest.approx(expected.peak_force, rel=TOL)
    assert measured.peak_force_time == pytest.approx(
        expected.peak_force_time, abs=PEAK_FORCE_TIME_TOL * t_c
    )


# --- linear spring-dashpot ------------------------------------------------------------------


@pytest.mark.parametrize("end", ENDS)
@settings(max_examples=40, deadline=None)
@given(data=st.data(), m_eff=MASSES, k=log_uniform(1e2, 1e8), v0=SPEEDS)
def test_linear_matches_integration(
    end: str, data: st.DataObject, m_eff: float, k: float, v0: float
) -> None:
    e = data.draw(st.floats(E_MIN[end], 1.0), label="e")
    law = LinearSpringDashpot.from_stiffness(k, e, m_eff, end)
    c = law.c
    measured_e, measured = integrate_impact(
        lambda d, v: k * d + c * v, m_eff, v0, v0 / law.omega_n, end
    )
    assert measured_e == pytest.approx(e, abs=TOL)
    assert_matches(measured, law.impact(v0))


@pytest.mark.parametrize("end", ENDS)
@settings(max_examples=40, deadline=None)
@given(data=st.data(), t_c=log_uniform(1e-7, 1e-1), m_eff=MASSES)
def test_from_duration_round_trip(end: str, data: st.DataObject, t_c: float, m_eff: float) -> None:
    e = data.draw(st.floats(E_MIN[end], 1.0), label="e")
    law = LinearSpringDashpot.from_duration(t_c, e, m_eff, end)
    assert law.duration == pytest.approx(t_c, rel=1e-12)
    assert law.e == pytest.approx(e, rel=1e-12)


@pytest.mark.parametrize(("end", "zeta_max"), [("overlap", 0.99), ("force", 0.999999)])
@settings(max_examples=60, deadline=None)
@given(fraction=st.floats(0.0, 1.0))
def test_damping_ratio_inverts_restitution(end: str, zeta_max: float, fraction: float) -> None:
    zeta = fraction * zeta_max
    # abs 1e-14: e = 1 − πζ + … is stored to 1e-16, which bounds ζ to ~1e-16 absolute.
    assert damping_ratio(restitution(zeta, end), end) == pytest.approx(zeta, rel=1e-12, abs=1e-14)


def test_force_criterion_quoted_values() -> None:
    # 1e-5: the quoted values carry 4 (0.7182) and 6 (0.122215) significant digits.
    assert damping_ratio(0.7) == pytest.approx(0.1128, abs=1e-4)
    assert restitution(damping_ratio(0.7), "force") == pytest.approx(0.7182, abs=1e-5)
    assert damping_ratio(0.7, "force") == pytest.approx(0.122215, abs=1e-5)


def test_criteria_agree_for_weak_damping() -> None:
    # ζ_force − ζ_overlap = (2/π) ζ² + O(ζ³): 2e-10 relative at e = 1 − 1e-9.
    e = 1.0 - 1e-9
    assert damping_ratio(e, "force") == pytest.approx(damping_ratio(e), rel=1e-8)


@pytest.mark.parametrize("end", ENDS)
def test_elastic_contact(end: str) -> None:
    k, m_eff, v0 = 1e4, 1e-3, 2.0
    law = LinearSpringDashpot.from_stiffness(k, 1.0, m_eff, end)
    assert damping_ratio(1.0, end) == 0.0
    assert law.zeta == 0.0
    assert law.c == 0.0
    assert restitution(0.0, end) == 1.0
    response = law.impact(v0)
    omega = math.sqrt(k / m_eff)
    assert response.duration == pytest.approx(math.pi / omega, rel=1e-15)
    assert response.peak_overlap == pytest.approx(v0 / omega, rel=1e-15)
    assert response.peak_force == pytest.approx(k * v0 / omega, rel=1e-15)
    assert response.peak_force_time == pytest.approx(response.duration / 2, rel=1e-15)
    assert tsuji_alpha(1.0, end) == 0.0


def test_strong_damping_peaks_at_first_touch() -> None:
    law = LinearSpringDashpot.from_stiffness(1e4, 0.1, 1e-3)  # ζ = 0.59 > 1/2
    response = law.impact(3.0)
    assert law.zeta > 0.5
    assert response.peak_force_time == 0.0
    assert response.peak_force == pytest.approx(law.c * 3.0, rel=1e-14)


def test_force_criterion_shortens_contact_and_halves_at_peak_overlap() -> None:
    law = LinearSpringDashpot.from_stiffness(1e4, 0.5, 1e-3, "force")
    overlap_law = dataclasses.replace(law, end="overlap")
    response = law.impact(1.0)
    assert law.duration < overlap_law.duration
    assert law.e > overlap_law.e
    assert response.peak_overlap_time == pytest.approx(response.duration / 2, rel=1e-14)


# --- Hertz with Tsuji damping -----------------------------------------------------------------


@pytest.mark.parametrize("end", ENDS)
@settings(max_examples=25, deadline=None)
@given(data=st.data(), m_eff=MASSES, k_n=log_uniform(1e3, 1e10), v0=SPEEDS)
def test_hertz_tsuji_matches_integration(
    end: str, data: st.DataObject, m_eff: float, k_n: float, v0: float
) -> None:
    e = data.draw(st.floats(E_MIN[end], 1.0), label="e")
    law = HertzTsuji.from_restitution(k_n, e, m_eff, end)
    measured_e, measured = integrate_impact(
        hertz_tsuji_force(k_n, law.eta),
        m_eff,
        v0,
        (m_eff * v0 * v0 / k_n) ** 0.4,
        end,
    )
    assert law.e == pytest.approx(e, rel=1e-12)
    assert measured_e == pytest.approx(e, abs=TOL)
    assert_matches(measured, law.impact(v0))


def test_hertz_undamped_closed_forms() -> None:
    k_n, m_eff, v0 = 3e6, 2e-4, 4.0
    response = HertzTsuji(k_n, 0.0, m_eff).impact(v0)
    peak_overlap = (5.0 * m_eff * v0**2 / (4.0 * k_n)) ** 0.4
    duration = HERTZ_DURATION_COEFFICIENT * (m_eff**2 / (k_n**2 * v0)) ** 0.2
    assert response.peak_overlap == pytest.approx(peak_overlap, rel=1e-14)
    assert response.duration == pytest.approx(duration, rel=1e-14)
    assert response.peak_force == pytest.approx(k_n * peak_overlap**1.5, rel=1e-14)
    assert response.peak_overlap_time == response.peak_force_time == response.duration / 2
    _, measured = integrate_impact(hertz_tsuji_force(k_n, 0.0), m_eff, v0, peak_overlap, "overlap")
    assert measured.duration == pytest.approx(duration, rel=1e-9)
    assert measured.peak_overlap == pytest.approx(peak_overlap, rel=1e-9)


def test_hertz_duration_coefficient() -> None:
    assert pytest.approx(3.2180654597, rel=1e-10) == HERTZ_DURATION_COEFFICIENT
    # The literature's 2.87 belongs to (m²/(R E*² v0))^{1/5}, i.e. k_n = (4/3) E* √R:
    assert pytest.approx(2.8683, abs=1e-4) == HERTZ_DURATION_COEFFICIENT * (9.0 / 16.0) ** 0.2


def test_tsuji_alpha_closed_form() -> None:
    log_e = math.log(0.5)
    assert tsuji_alpha(0.5) == pytest.approx(
        math.sqrt(5.0) * -log_e / math.sqrt(math.pi**2 + log_e**2), rel=1e-15
    )
    assert tsuji_alpha(0.5, "force") == pytest.approx(
        math.sqrt(5.0) * damping_ratio(0.5, "force"), rel=1e-15
    )


def test_hertz_stiffness() -> None:
    E, nu, R = 5e7, 0.3, 2e-3
    assert effective_modulus((E, E), (nu, nu)) == pytest.approx(E / (2 * (1 - nu**2)), rel=1e-15)
    assert hertz_stiffness((E, math.inf), (nu, 0.25), R) == pytest.approx(
        4.0 / 3.0 * E / (1 - nu**2) * math.sqrt(R), rel=1e-15
    )


# --- time step --------------------------------------------------------------------------------


def test_time_steps() -> None:
    assert contact_time_step(1e-4) == pytest.approx(2e-6, rel=1e-15)
    assert contact_time_step(1e-4, fraction=0.1) == pytest.approx(1e-5, rel=1e-15)
    assert tunnelling_time_step(1e-3, 2e-3, 10.0) == pytest.approx(1e-4, rel=1e-15)
    slow = time_step(1e-4, 1e-3, 2e-3, 10.0)
    assert (slow.dt, slow.governed_by) == (slow.contact, "contact")
    fast = time_step(1e-4, 1e-3, 0.0, 1e3)
    assert fast.tunnelling == pytest.approx(5e-7, rel=1e-15)
    assert (fast.dt, fast.governed_by) == (fast.tunnelling, "tunnelling")


# --- input validation -------------------------------------------------------------------------

nan = math.nan
BAD_INPUTS: list[tuple[Callable[[], object], str]] = [
    (lambda: damping_ratio(0.0), "e must be in (0, 1] (got 0.0)"),
    (lambda: damping_ratio(1.5), "e must be in (0, 1] (got 1.5)"),
    (lambda: damping_ratio(nan), "e must be in (0, 1] (got nan)"),
    (lambda: damping_ratio(0.1, "force"), "e must be in (exp(-2) = 0.135335, 1] for end='force'"),
    (lambda: damping_ratio(0.5, "bounce"), "end must be 'overlap' or 'force' (got 'bounce')"),
    (lambda: restitution(1.0), "zeta must be in [0, 1) (got 1.0)"),
    (lambda: restitution(-0.1, "force"), "zeta must be in [0, 1) (got -0.1)"),
    (lambda: LinearSpringDashpot(-1.0, 0.1, 1.0), "k must be in (0, inf) N/m (got -1.0)"),
    (lambda: LinearSpringDashpot(math.inf, 0.1, 1.0), "k must be in (0, inf) N/m (got inf)"),
    (lambda: LinearSpringDashpot(1e3, 0.1, 1.0, "x"), "end must be 'overlap' or 'force'"),
    (lambda: LinearSpringDashpot.from_stiffness(1e3, 0.5, 0.0), "m_eff must be in (0, inf) kg"),
    (lambda: LinearSpringDashpot.from_duration(0.0, 0.5, 1.0), "t_c must be in (0, inf) s"),
    (lambda: LinearSpringDashpot(1e3, 0.1, 1.0).impact(0.0), "v0 must be in (0, inf) m/s"),
    (lambda: HertzTsuji(1e6, 3.0, 1e-3), "alpha must be in [0, 2.23607) (got 3.0)"),
    (lambda: HertzTsuji(0.0, 0.1, 1e-3), "k_n must be in (0, inf) N/m^1.5 (got 0.0)"),
    (lambda: HertzTsuji(1e6, 0.1, 1e-3).impact(-1.0), "v0 must be in (0, inf) m/s (got -1.0)"),
    (lambda: hertz_stiffness((1e7, 1e7), (0.3, 0.6), 1e-3), "nu[1] must be in (-1, 0.5]"),
    (lambda: hertz_stiffness((0.0, 1e7), (0.3, 0.3), 1e-3), "E[0] must be in (0, inf] Pa"),
    (lambda: hertz_stiffness((math.inf,) * 2, (0.3,) * 2, 1e-3), "E must not be infinite"),
    (lambda: hertz_stiffness((1e7, 1e7), (0.3, 0.3), 0.0), "R_eff must be in (0, inf) m"),
    (lambda: contact_time_step(1e-4, fraction=0.0), "fraction must be in (0, 1] (got 0.0)"),
    (lambda: contact_time_step(1e-4, fraction=2.0), "fraction must be in (0, 1] (got 2.0)"),
    (lambda: tunnelling_time_step(-1e-3, 0.0, 1.0), "radius must be in (0, inf) m"),
    (lambda: tunnelling_time_step(1e-3, -1.0, 1.0), "thickness must be in [0, inf) m"),
    (lambda: time_step(1e-4, 1e-3, 0.0, 0.0), "v_rel_max must be in (0, inf) m/s (got 0.0)"),
]


@pytest.mark.parametrize(("call", "message"), BAD_INPUTS)
def test_bad_input_raises(call: Callable[[], object], message: str) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        call()


def test_laws_are_frozen() -> None:
    law = LinearSpringDashpot(1e3, 0.1, 1.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        law.k = 2e3  # type: ignore[misc]


# --- added by the mutation run (docs/dev/testing.md) ------------------------------------------


def test_force_end_rejects_critical_damping() -> None:
    """e = e^-2 exactly is the critically damped limit (ζ = 1) of end="force": outside
    (e^-2, 1], so rejected, not handed to brentq (ln(e^-2) is -2.0 to the last bit)."""
    for call in (damping_ratio, tsuji_alpha):
        with pytest.raises(ValueError, match=re.escape("e must be in (exp(-2) = 0.135335, 1]")):
            call(math.exp(-2.0), "force")


def test_hertz_tsuji_rejects_a_non_positive_mass() -> None:
    for m_eff in (0.0, -0.5):
        with pytest.raises(
            ValueError, match=re.escape(f"m_eff must be in (0, inf) kg (got {m_eff})")
        ):
            HertzTsuji(1e6, 0.1, m_eff)


def test_contact_results_are_frozen() -> None:
    """The laws and their results are values: assigning to a field raises."""
    values = [
        HertzTsuji(1e6, 0.1, 1e-3),
        HertzTsuji(1e6, 0.1, 1e-3).impact(1.0),
        time_step(1e-4, 1e-3, 0.0, 1.0),
    ]
    for value in values:
        field = dataclasses.fields(value)[0].name
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(value, field, 2.0)


def test_non_positive_durations_and_negative_damping_are_rejected() -> None:
    for t_c in (0.0, -0.5):
        with pytest.raises(ValueError, match=re.escape(f"t_c must be in (0, inf) s (got {t_c})")):
            contact_time_step(t_c)
    for zeta in (-0.1, 1.0, 1.5):  # no negative damping; ζ >= 1 is overdamped
        with pytest.raises(ValueError, match=re.escape(f"zeta must be in [0, 1) (got {zeta})")):
            LinearSpringDashpot(1e3, zeta, 1.0)


def test_contact_bound_governs_a_tie() -> None:
    """Equal bounds, 0.5·1 ms both (the same product in both, so equal to the bit): the
    contact bound governs, as documented."""
    step = time_step(1e-3, 1e-3, 0.0, 1.0, fraction=0.5)
    assert step.contact == step.tunnelling == 5e-4
    assert step.governed_by == "contact"
