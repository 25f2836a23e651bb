"""Hammer kinematics (eq. 43-54), plate mass properties, the swing in the centrifugal field."""

import math

import numpy as np
import pytest

from perga.analytic import hammer as hm
from tests.conftest import RTOL_CLOSED_FORM, integrate


def test_velocities_are_derivatives_of_positions():
    R, arm, w, a0, ad = 0.1, 0.05, 80.0, 0.3, 5.0
    t = np.linspace(0, 0.05, 9)
    h = 1e-7

    def pos(tt):
        return hm.point_on_hammer_position(R, arm, w * tt, a0 + ad * tt)

    xp, yp = pos(t + h)
    xm, ym = pos(t - h)
    vx, vy = hm.point_on_hammer_velocity(R, arm, w * t, a0 + ad * t, w, ad)
    # central differences: truncation ~h²·ω³·r ≈ 1e-9 m/s against speeds of ~10 m/s
    np.testing.assert_allclose((xp - xm) / (2 * h), vx, rtol=0, atol=1e-6)
    np.testing.assert_allclose((yp - ym) / (2 * h), vy, rtol=0, atol=1e-6)
    np.testing.assert_allclose(
        vx**2 + vy**2, hm.centre_of_mass_speed_squared(R, arm, a0 + ad * t, w, ad), rtol=1e-12
    )
    ax, ay = hm.pivot_acceleration(R, w * t, w, 0.0)
    np.testing.assert_allclose(np.hypot(ax, ay), R * w**2, rtol=1e-13)


def test_paper_normal_sees_no_impact_for_a_radial_hammer():
    R, a, w = 0.08, 0.05, 100.0
    vn, vt = hm.contact_velocity_components(R, a, 0.7, 0.0, w, 0.0, normal="paper")
    assert abs(vn) < 1e-12 * w * (R + a)
    assert vt == pytest.approx(w * (R + a), rel=1e-13)
    vn_face, _ = hm.contact_velocity_components(R, a, 0.7, 0.0, w, 0.0, normal="face")
    assert vn_face == pytest.approx(w * (R + a), rel=1e-13)


def test_plate_mass_properties():
    plate = hm.PlateHammer(0.06, 0.02, 0.003, 7850.0, 0.005)
    m = 7850.0 * 0.06 * 0.02 * 0.003
    assert plate.mass == pytest.approx(m, rel=1e-14)
    lcg = 0.025
    assert plate.inertia_about_hinge == pytest.approx(m * (0.06**2 + 0.02**2) / 12 + m * lcg**2)
    heavier = plate.with_mass(0.2)
    assert heavier.mass == pytest.approx(0.2, rel=1e-14)
    assert heavier.inertia_about_hinge / heavier.mass == pytest.approx(
        plate.inertia_about_hinge / plate.mass, rel=1e-14
    )


def lab_frame_swing_rhs(omega, M, R, lcg, I_A):
    """θ̈ from the torque about a pivot accelerating on a circle, in the fixed frame."""

    def rhs(t, s):
        theta, theta_dot = s
        pivot_acc = -(omega**2) * R * np.array([math.cos(omega * t), math.sin(omega * t)])
        arm = lcg * np.array([math.cos(theta), math.sin(theta)])
        # I_A θ̈ = −M (arm × a_pivot)_z (d'Alembert force −M a_pivot at the centre of mass)
        return [theta_dot, -M * (arm[0] * pivot_acc[1] - arm[1] * pivot_acc[0]) / I_A]

    return rhs


@pytest.mark.parametrize("amplitude", [1e-3, 0.5, 2.0])
def test_swing_period_matches_a_lab_frame_integration(amplitude):
    plate = hm.PlateHammer(0.06, 0.02, 0.003, 7850.0, 0.005)
    omega, R = 100.0, 0.08
    args = (omega, plate.mass, R, plate.hinge_to_centre_of_mass, plate.inertia_about_hinge)
    period = hm.swing_period(amplitude, *args)
    # start at rest relative to the rotor at α = amplitude; α returns to it after one period
    t = np.linspace(0, period, 2001)
    y = integrate(lab_frame_swing_rhs(*args), [amplitude, omega], t)
    alpha = y[0] - omega * t
    assert alpha[-1] == pytest.approx(amplitude, rel=1e-7)
    assert y[1][-1] - omega == pytest.approx(0.0, abs=RTOL_CLOSED_FORM * omega)
    assert np.min(alpha) == pytest.approx(-amplitude, rel=1e-6)
    if amplitude < 0.01:
        assert period == pytest.approx(2 * math.pi / hm.swing_frequency(*args), rel=1e-6)
