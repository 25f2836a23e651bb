"""Restitution of simulated normal impacts against the target e (issue 4's "must show").

Tolerance 0.5 % relative (the issue's). The kernel's error is second order in dt (dashpot taken
as its exact impulse over the kick interval, velocities extrapolated to the force time): measured
at t_c/50 it is below 0.1 % for every case here and does not depend on where first touch falls
within a step, so 0.5 % leaves a 5× margin.
"""

import math

import pytest

from perga.analytic.contact import damping_ratio, restitution
from perga.contact.soft import contact_duration, contact_parameters, uniform_table
from perga.contact.soft.laws import (
    N_PARAMS,
    P_CLAMP,
    P_DAMP,
    P_DAMPT,
    P_KN,
    P_KT,
    P_MU,
    P_MUR,
    touching,
)

from .helpers import MASS, impact

E_VALUES = (0.3, 0.5, 0.6, 0.7, 0.8, 0.9)
SPEEDS = (1.0, 10.0, 30.0)


@pytest.mark.parametrize("model", ["linear", "hertz"])
@pytest.mark.parametrize("kind", ["wall", "pair"])
def test_restitution_matches_target(model, kind):
    worst = 0.0
    for e in E_VALUES:
        for v0 in SPEEDS:
            result = impact(model, e, v0, kind)
            err = result.e / e - 1.0
            assert abs(err) < 5e-3, f"{model} {kind} e={e} v0={v0}: got {result.e} ({err:+.2%})"
            worst = max(worst, abs(err))
    assert worst < 5e-3


@pytest.mark.parametrize("model", ["linear", "hertz"])
@pytest.mark.parametrize("phase", [0.0, 0.25, 0.5, 0.75, 0.999])
def test_restitution_independent_of_touch_phase(model, phase):
    # Before the dashpot-impulse correction e = 0.3 varied by ±1-2 % with the phase.
    result = impact(model, 0.3, 10.0, "wall", phase=phase)
    assert result.e == pytest.approx(0.3, rel=2e-3)


@pytest.mark.parametrize("model", ["linear", "hertz"])
def test_overlap_end_criterion(model):
    """end="overlap" (attractive force allowed until δ = 0) with its own calibration gives e."""
    for e in (0.3, 0.7, 0.9):
        result = impact(model, e, 10.0, "wall", end="overlap")
        assert result.e == pytest.approx(e, rel=5e-3)


def test_clamp_with_overlap_calibration_raises_e():
    """Clamping at F = 0 with ζ calibrated for δ = 0 raises e = 0.7 to 0.718 (design §4)."""
    row = contact_parameters("linear", 0.7, k_n=1e6, friction=0.0, end="overlap")
    row[P_CLAMP] = 1.0
    zeta = damping_ratio(0.7, "overlap")
    expected = restitution(zeta, "force")
    assert expected == pytest.approx(0.718, abs=1e-3)
    result = impact("linear", 0.7, 10.0, "wall", params=row)
    assert result.e == pytest.approx(expected, rel=2e-3)
    assert math.isclose(row[P_DAMP], 2.0 * zeta)


@pytest.mark.parametrize("model", ["linear", "hertz"])
@pytest.mark.parametrize("kind", ["wall", "pair"])
def test_dissipation_equals_kinetic_energy_lost(model, kind):
    """The energy the contact law dissipated (``SoftGranules.dissipated``) over a head-on impact
    equals the kinetic energy lost, ½ m_eff v0² (1 − e²) with the simulated e.

    The law's dissipation uses the rates extrapolated to the force time, the kinetic energy the
    mean velocity of each kick: they differ at O(dt²). Measured worst over e = 0.3-0.9 and
    1-30 m/s, as a fraction of ½ m_eff v0²: linear 8.4e-4 (wall), 1.7e-3 (pair), Hertz 5.3e-4,
    9.5e-4 at t_c/50 of a granule pair (a wall's t_c/71: the single granule's default step
    then), and 4× less at half of it. Asserted at t_c/50 and t_c/100 of each contact: 2e-3 and
    5e-4, and a fall of ≥ 3× (second order).
    """
    m_eff = MASS if kind == "wall" else 0.5 * MASS
    worst = {}
    for dt_fraction in (1.0 / 50.0, 1.0 / 100.0):
        errors = []
        for e in (0.3, 0.7, 0.9):
            for v0 in (1.0, 30.0):
                result = impact(model, e, v0, kind, dt_fraction=dt_fraction)
                lost = 0.5 * m_eff * v0**2 * (1.0 - result.e**2)
                errors.append(abs(result.granules.dissipated.sum() - lost) / (0.5 * m_eff * v0**2))
        worst[dt_fraction] = max(errors)
    assert worst[1.0 / 50.0] <= 2e-3
    assert worst[1.0 / 100.0] <= 5e-4
    assert worst[1.0 / 50.0] >= 3.0 * worst[1.0 / 100.0]


# --- Added by the mutation run (docs/dev/testing.md) ---------------------------------------------


def test_a_contact_acts_from_half_a_step_before_first_touch():
    """``touching``: a contact is evaluated when its overlap, extrapolated over the kick
    interval [t − dt/2, t + dt/2], is positive somewhere in it: δ + ½dt|δ̇| > 0, approaching
    or separating; checked 1 % of the half step on either side of the limit."""
    dt = 1e-6
    for rate in (2.0, -2.0):
        half = 0.5 * dt * abs(rate)
        assert touching(-0.99 * half, rate, dt)
        assert not touching(-1.01 * half, rate, dt)


def test_contact_parameters_defaults_and_refusals():
    """The documented defaults (friction 0.5, k_t = 2/7 k_n as LAMMPS's, no rolling, no
    tangential damping; one material); k_n from a duration t_c: for end="overlap" the
    damped oscillator's half period π/ω_d with e = exp(−ζω0 t_c) gives
    k_n = m(π² + ln²e)/t_c², N/m (1e-12 relative: rounding). A soft spring (0.5 N/m) is
    valid; refused: t_c without model linear or m_ref, k_n ≤ 0 or infinite, negative
    friction, rolling or kt_ratio, ζ_t outside [0, 1)."""
    row = contact_parameters("linear", 0.5, k_n=0.5)
    assert row[P_KN] == 0.5
    assert row[P_KT] == pytest.approx(0.5 * 2.0 / 7.0, rel=1e-15)
    assert (row[P_MU], row[P_MUR], row[P_DAMPT]) == (0.5, 0.0, 0.0)
    assert uniform_table(row).shape == (1, 1, N_PARAMS)
    m, t_c, e = 1e-4, 2e-5, 0.5
    row = contact_parameters("linear", e, t_c=t_c, m_ref=m, end="overlap")
    assert row[P_KN] == pytest.approx(m * (math.pi**2 + math.log(e) ** 2) / t_c**2, rel=1e-12)
    refused = [
        {"model": "hertz", "t_c": t_c, "m_ref": m},
        {"t_c": t_c},
        {"k_n": 0.0},
        {"k_n": math.inf},
        {"k_n": 1e6, "friction": -0.5},
        {"k_n": 1e6, "rolling": -0.5},
        {"k_n": 1e6, "kt_ratio": -0.5},
        {"k_n": 1e6, "zeta_t": -0.5},
        {"k_n": 1e6, "zeta_t": 1.0},
    ]
    for kwargs in refused:
        model = kwargs.pop("model", "linear")
        with pytest.raises(ValueError):
            contact_parameters(model, e, **kwargs)


def test_contact_duration_closed_forms():
    """``contact_duration``, s: a linear row ending at δ = 0 (end="overlap", e = 0.5) lasts the
    damped half period π/(ω0√(1 − ζ²)), ω0 = √(k/m), ζ = −ln e/√(π² + ln²e) (1e-12 relative:
    rounding); an elastic Hertz row (e = 1) of effective radius R = 4 mm has stiffness
    K = k_n√R and lasts 2(δ_max/v)·(2/5)B(2/5, 1/2), δ_max = (5mv²/(4K))^{2/5} (m = 1 g,
    v = 3 m/s; 1e-6: the integration's accuracy, 1e-9)."""
    m, k, e = 1e-3, 1e6, 0.5
    row = contact_parameters("linear", e, k_n=k, end="overlap")
    zeta = -math.log(e) / math.hypot(math.pi, math.log(e))
    period = math.pi / (math.sqrt(k / m) * math.sqrt(1.0 - zeta**2))
    assert contact_duration(row, m, 1.0, 1.0) == pytest.approx(period, rel=1e-12)
    r_eff, v = 4e-3, 3.0
    row = contact_parameters("hertz", 1.0, k_n=1e10)
    stiffness = 1e10 * math.sqrt(r_eff)
    peak = (5.0 * m * v**2 / (4.0 * stiffness)) ** 0.4
    beta = math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)
    expected = 2.0 * peak / v * 0.4 * beta
    assert contact_duration(row, m, r_eff, v) == pytest.approx(expected, rel=1e-6)
