"""Restitution of simulated normal impacts against the target e (issue 4's "must show").

Tolerance 0.5 % relative (the issue's). The kernel's error is second order in dt (dashpot taken
as its exact impulse over the kick interval, velocities extrapolated to the force time): measured
at t_c/50 it is below 0.1 % for every case here and does not depend on where first touch falls
within a step, so 0.5 % leaves a 5× margin.
"""

import math

import pytest

from perga.analytic.contact import damping_ratio, restitution
from perga.contact.soft import contact_parameters
from perga.contact.soft.laws import P_CLAMP, P_DAMP

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
