"""An elastic contact that sticks loses its tangential spring when it separates.

A disc (2.5 mm, 0.16 g) strikes a plane wall at 5 m/s, e = 1 and μ = 1000 (it never slides).
The tangential spring, stretched while the disc sticks, still holds energy when the normal
force lets go; the contact ends and that energy is dropped (as LAMMPS's history contacts do)
and booked as the contact's dissipation (``SoftGranules.dissipated``, the ledger's
``contact_dissipation``). The kinetic energy lost is that dissipation but for the step's own
error of the tangential oscillation (at most 1.3e-3 of the impact's energy measured here, at
the step the granule takes by default); the share dropped grows with the incidence and with
k_t/k_n: at most 4.1 % for the linear law at LAMMPS's 2/7, 32 % for Hertz at k_t/k_n = 1
(docs/dev/validation.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perga.contact.soft import SoftGranules, contact_parameters, plane, uniform_table

RADIUS, MASS, SPEED = 0.0025, 1.6e-4, 5.0
STIFFNESS = {"linear": 1e5, "hertz": 1e9}
"""k_n: N/m, and (4/3)E*, Pa."""


def strike(degrees: float, law: str, ratio: float) -> tuple[float, float, float]:
    """(kinetic energy before, after, dissipated), J, of one strike ``degrees`` from the wall's
    normal, contact ``law``, k_t/k_n ``ratio``."""
    row = contact_parameters(law, 1.0, k_n=STIFFNESS[law], friction=1000.0, kt_ratio=ratio)
    angle = math.radians(degrees)
    v = SPEED * np.array([math.sin(angle), -math.cos(angle)])
    g = SoftGranules([[0.0, RADIUS + 1e-5]], [RADIUS], [MASS], uniform_table(row), v=[v],
                     walls=[plane((0.0, 0.0), (0.0, 1.0))], v_max=SPEED)  # fmt: skip
    before = g.kinetic_energy()
    for _ in range(400_000):
        g.step(1)
        if g.v[0, 1] > 0 and g.x[0, 1] > RADIUS + 1e-5:
            break
    return before, g.kinetic_energy(), float(g.dissipated.sum())


@pytest.mark.parametrize(("law", "ratio", "low", "high"),
                         [("linear", 2 / 7, 0.035, 0.045), ("hertz", 1.0, 0.28, 0.36)])  # fmt: skip
def test_the_dropped_spring_is_booked_as_the_contacts_dissipation(
    law: str, ratio: float, low: float, high: float
) -> None:
    """At every incidence 5-85° the kinetic energy lost is the contact's dissipation within
    2e-3 of the impact's energy (the tangential oscillation's step error, above); the largest
    share dropped lies in [low, high] (measured 4.1 % and 32 %, near grazing)."""
    shares = []
    for degrees in range(5, 90, 5):
        before, after, dissipated = strike(degrees, law, ratio)
        assert before - after == pytest.approx(dissipated, abs=2e-3 * before)
        shares.append(dissipated / before)
    assert low <= max(shares) <= high, shares
