"""The peak normal force the kernel keeps per granule-polygon contact, and Hertz's peak pressure
from it, against the closed forms of a Hertz-Tsuji impact (``perga.analytic.contact``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perga.analytic.contact import HertzTsuji
from perga.contact.soft import SoftGranules, contact_parameters, uniform_table
from perga.contact.soft.impacts import hertz_peak_pressure
from perga.contact.soft.polygon_set import (
    HIST_ACTIVE,
    HIST_PEAK_FORCE,
    KINEMATIC,
    contact_table,
    polygon_set,
)

R = 2.5e-3  # m
M = 2.0e-4  # kg
E_STAR = 3.0e8  # Pa: a soft solid
K_N = 4.0 / 3.0 * E_STAR  # the Hertz law's k_n, Pa


@pytest.mark.parametrize(("v0", "e"), [(2.0, 1.0), (10.0, 0.7)])
def test_peak_force_and_pressure_of_a_head_on_hertz_impact(v0: float, e: float) -> None:
    """A granule strikes a kinematic plate head on at v0: the kernel's peak force is Hertz-
    Tsuji's (k_n√R, α(e), m) to 1e-3 (a sampled maximum at t_c/2000 steps: the force's
    relative change over one step near the peak is below that); the pressure equals
    (2E*/π)·√(δ/R) at the closed-form peak overlap δ for e = 1 (force and overlap peak
    together; 1e-3 likewise) and is exactly 3F/(2πRδ(F)) of the reported force always."""
    closed = HertzTsuji.from_restitution(K_N * math.sqrt(R), e, M, "force").impact(v0)
    plate = np.array([[-0.01, -0.002], [0.01, -0.002], [0.01, 0.0], [-0.01, 0.0]])
    polys = polygon_set(
        [plate], np.array([[0.0, -0.001]]), kind=[KINEMATIC], mass=[math.inf],
        inertia=[math.inf],
    )  # fmt: skip
    table = contact_table(K_N, 0.0, e, 0.0, "hertz", "force")
    row = contact_parameters("linear", 1.0, k_n=1.0)
    g = SoftGranules(
        np.array([[0.0, R + 1e-5]]), [R], [M], uniform_table(row),
        v=np.array([[0.0, -v0]]), polygons=polys, polygon_table=table,
        dt=closed.duration / 2000,
    )  # fmt: skip
    while True:
        g.step(1)
        if g.polygon_hist[0, 0, HIST_ACTIVE] == 0.0 and g.v[0, 1] > 0:
            break
    peak = g.polygon_hist[0, 0, HIST_PEAK_FORCE]
    assert peak == pytest.approx(closed.peak_force, rel=1e-3)
    pressure = hertz_peak_pressure(peak, K_N, R)
    delta = (peak / (K_N * math.sqrt(R))) ** (2 / 3)
    assert pressure == pytest.approx(3 * peak / (2 * math.pi * R * delta), rel=1e-14)
    if e == 1.0:
        expected = 2 * E_STAR / math.pi * math.sqrt(closed.peak_overlap / R)
        assert pressure == pytest.approx(expected, rel=1e-3)


def test_no_force_no_pressure() -> None:
    assert hertz_peak_pressure(0.0, K_N, R) == 0.0
