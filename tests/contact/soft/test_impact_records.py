"""A soft impact's record against the granule's own motion (``perga.contact.soft.impacts``): an
oblique frictional strike on a welded plate, the granule in free flight before and after."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from perga.case import load_case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case

CASE = Path(__file__).resolve().parents[2] / "cases/closed-form/oblique-impact-slide.toml"
OMEGA = 1e-6
"""rad/s: the case's rotor, which carries the plate (the schema needs omega > 0)."""
AFTER = 1e-7
"""Relative tolerance of the values after the impact, read from the granule at the run's end:
between the impact's end and then the face's velocity at the contact point (ω × point) changes
by at most ω·|Δx| ≈ 1e-6 rad/s × 5 mm = 5e-9 m/s, and its normal turns by ω·Δt ≈ 1e-9 rad,
against speeds of 3-12 m/s: ≤ 1e-9 relative; 1e-7 leaves room and still shows any term left
out or a sign flipped (their size is that of the velocities)."""


def _face(point: np.ndarray) -> np.ndarray:
    """The plate's velocity at ``point``, m/s: it turns with the rotor about the origin."""
    return OMEGA * np.array([-point[1], point[0]])


def test_a_soft_impact_record_is_the_granules_motion() -> None:
    """The granule starts at (12, −5) m/s, not spinning, and moves freely until it touches the
    face and after it leaves. The record's values before are those of that flight relative to
    the face's material point (rounding: 1e-12), with t = n turned +90° and the spin's share
    −w·r; its values after and the energy gain are those of the granule at the run's end
    (``AFTER``; the energy, read from the same state, to rounding)."""
    case = load_case(
        CASE,
        overrides=["contact_model.kind=linear", "contact_model.duration=1e-4", "solver.dt=2e-6"],
    )
    sim = Simulation(compile_case(case))
    sim.run(1e-3)
    (impact,) = sim.impacts
    granules = sim.frame().granules
    m, inertia, r = granules.masses[0], granules.inertia[0], granules.radii[0]
    v0 = np.array([12.0, -5.0])
    n = np.array(impact.normal)
    t = np.array([-n[1], n[0]])
    before = v0 - _face(np.array(impact.point))
    assert impact.granule_velocity_before == (12.0, -5.0)
    assert impact.normal_velocity_before == pytest.approx(before @ n, rel=1e-12)
    assert impact.tangential_velocity_before == pytest.approx(before @ t, rel=1e-12)

    v, (w,) = sim.frame().granules.velocities[0], sim.frame().granules.angular_velocities
    after = v - _face(sim.frame().granules.positions[0] - r * n)
    assert abs(w) > 100.0  # the friction set it spinning: the spin terms below count
    assert impact.normal_velocity_after == pytest.approx(after @ n, rel=AFTER)
    assert impact.tangential_velocity_after == pytest.approx(after @ t - w * r, rel=AFTER)
    gain = 0.5 * m * (v @ v) + 0.5 * inertia * w * w - 0.5 * m * (v0 @ v0)
    assert impact.granule_energy_gain == pytest.approx(gain, rel=1e-12)
