"""Rolling resistance between two granules, applied by the kernel's pair pass
(``kernel.pair_force``; the law itself, ``laws.rolling_torque``, is checked in
``test_chung_ooi.py``)."""

import numpy as np
import pytest

from perga.contact.soft import SoftGranules, contact_parameters, uniform_table

R = 2e-3
MASS = 1e-4
OVERLAP = 1e-6
K_N = 1e6


def _torques(mu_r: float, friction: float = 0.0) -> np.ndarray:
    """One step of two discs (frictionless unless said) overlapping by OVERLAP at rest,
    spinning at +30 and −10 rad/s: the contact torques on them, N·m."""
    row = contact_parameters("linear", 0.5, k_n=K_N, friction=friction, rolling=mu_r)
    g = SoftGranules(
        [[0.0, 0.0], [2 * R - OVERLAP, 0.0]], [R, R], [MASS, MASS], uniform_table(row),
        w=[30.0, -10.0],
    )  # fmt: skip
    g.step(1)
    return g.tq.copy()


@pytest.mark.parametrize("mu_r", [0.05, 0.2])
def test_a_pair_resists_its_relative_rolling(mu_r: float) -> None:
    """The torques are ∓μ_r R* F_n, R* = r/2, F_n = k_n δ (no relative normal motion: no
    dashpot), opposing the relative rolling ω_1 − ω_2 = 40 rad/s on the first disc and equal
    and opposite on the second (the resistance is far below what stops 40 rad/s in one step).
    Tolerance 1e-12 relative: the same products in another order. Without μ_r: none."""
    tq = _torques(mu_r)
    resistance = mu_r * (R / 2) * K_N * OVERLAP
    assert tq[0] == pytest.approx(-resistance, rel=1e-12)
    assert tq[1] == -tq[0]
    assert np.all(_torques(0.0) == 0.0)


@pytest.mark.parametrize("mu_r", [0.0, 0.2])
def test_friction_leaves_the_rolling_resistance_as_it_is(mu_r: float) -> None:
    """With friction (the kernel's commonest table, compiled for one chunk on its own) the
    tangential force turns both discs alike (−arm F_t each, equal arms), so the rolling torque
    is half the torques' difference: ∓μ_r R* F_n as without friction, to 1e-12 relative (the
    same products in another order), and zero without μ_r."""
    tq = _torques(mu_r, friction=0.5)
    assert tq[0] + tq[1] != 0.0  # the tangential force does act
    assert 0.5 * (tq[0] - tq[1]) == pytest.approx(-mu_r * (R / 2) * K_N * OVERLAP, rel=1e-12)
