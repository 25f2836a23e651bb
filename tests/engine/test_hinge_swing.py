"""Hinged hammer swinging in the centrifugal field of a kinematic rotor."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perga.analytic.hammer import PlateHammer, swing_frequency, swing_period
from perga.engine import Simulation
from perga.model import RotorSpec, System
from tests.engine.helpers import plate

# Measured: the period matches the exact pendulum period (elliptic integral) to 2.0e-5 at
# dt = 1e-5 s, 6.0e-6 at 3e-6 s (first order in dt); the small-angle Ω differs from the
# finite-amplitude one by ~α0²/16 = 2.5e-5 at α0 = 0.02. 1e-3 (the requirement) is 50× above
# the measured error, so the test catches a wrong moment, centre of mass or hinge, not noise.
TOLERANCE = 1e-3
DT = 1e-5


def test_swing_frequency() -> None:
    ph = PlateHammer(length=0.1, width=0.02, thickness=0.005, density=7800, hinge_offset=0.01)
    omega, R, amplitude = 150.0, 0.12, 0.02
    l_cg = ph.hinge_to_centre_of_mass
    hammer = plate(
        -ph.hinge_offset, ph.length - ph.hinge_offset, -ph.width / 2, ph.width / 2, ph.mass,
        hinge_radius=R, angle_on_rotor=0.3, mount="hinged", material="steel",
        swing_angle=amplitude,
    )  # fmt: skip
    assert hammer.moment_about_hinge == pytest.approx(ph.inertia_about_hinge, rel=1e-12)
    spec = System(
        rotor=RotorSpec(angular_velocity=omega, radius=0.2), hammers=(hammer,), granules=(),
        contacts=(), granule_dt=DT,
    )  # fmt: skip
    sim = Simulation(spec, record_impacts=False)
    big_omega = swing_frequency(omega, ph.mass, R, l_cg, ph.inertia_about_hinge)
    period = swing_period(amplitude, omega, ph.mass, R, l_cg, ph.inertia_about_hinge)
    n = int(3.2 * period / DT)
    alpha = np.empty(n)
    for i in range(n):
        sim.step()
        alpha[i] = sim.frame().machine.swing_angles[0]
    t = DT * np.arange(1, n + 1)
    down = np.nonzero((alpha[:-1] > 0) & (alpha[1:] <= 0))[0]
    crossings = t[down] + DT * alpha[down] / (alpha[down] - alpha[down + 1])
    measured = float(np.mean(np.diff(crossings)))
    assert len(crossings) == 3
    assert measured == pytest.approx(period, rel=TOLERANCE)
    assert 2 * math.pi / measured == pytest.approx(big_omega, rel=TOLERANCE)
    assert alpha.max() == pytest.approx(amplitude, rel=TOLERANCE)
