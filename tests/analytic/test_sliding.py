"""The consistent sliding/rolling model against closed forms and independent integrations."""

import math

import numpy as np
import pytest

from perga.analytic.sliding import BladeSlide, frictionless_exit
from tests.conftest import RTOL_CLOSED_FORM, integrate

G = 9.80665


def force_balance_rhs(omega, f_face, f_floor, floor, side, h):
    """ẍ from the vector force balance in the rotating frame, written independently of the model."""

    def rhs(_t, s):
        x, v = s
        w = np.array([0.0, 0.0, omega])
        r, vel = np.array([x, h, 0.0]), np.array([v, 0.0, 0.0])
        inertial = -np.cross(w, np.cross(w, r)) - 2 * np.cross(w, vel)  # centrifugal + Coriolis
        if floor == "corotating":
            floor_force = -f_floor * G * np.sign(v) * np.array([1.0, 0.0, 0.0])
        elif floor == "stationary":
            u = vel + np.cross(w, r)
            floor_force = -f_floor * G * u / np.linalg.norm(u)
        else:
            floor_force = np.zeros(3)
        normal = side * -(inertial[1] + floor_force[1])  # the face cancels the y-components
        return [v, inertial[0] + floor_force[0] - f_face * normal * np.sign(v)]

    return rhs


def test_frictionless_exit_time_and_speed():
    omega, x0, tip = 50.0, 0.02, 0.1
    for v0 in (0.0, 0.7):
        t_exit, v_exit = frictionless_exit(omega, x0, v0, tip)
        result = BladeSlide(omega, tip=tip).integrate(x0, v0, 1.0)
        assert result.event == "tip"
        assert result.t[-1] == pytest.approx(t_exit, rel=RTOL_CLOSED_FORM)
        assert result.v[-1] == pytest.approx(v_exit, rel=RTOL_CLOSED_FORM)
        # Jacobi integral ẋ² − ω²x² is conserved along the whole path
        jacobi = result.v**2 - omega**2 * result.x**2
        np.testing.assert_allclose(jacobi, jacobi[0], rtol=0, atol=1e-8 * omega**2 * tip**2)


@pytest.mark.parametrize(
    ("face", "x0", "v0", "h"),
    [("leading", 0.02, 0.3, 0.0), ("leading", 0.03, 1.0, 0.004), ("trailing", 0.09, -4.0, 0.0)],
)
def test_closed_form_matches_independent_integration(face, x0, v0, h):
    omega, f = 45.0, 0.35
    slide = BladeSlide(omega, f, f, "corotating", face, offset=h, tip=0.12)
    closed = slide.closed_form(x0, v0)
    result = slide.integrate(x0, v0, 1.0)
    t = result.t[result.t > 0]
    y = integrate(
        force_balance_rhs(omega, f, f, "corotating", 1 if face == "leading" else -1, h), [x0, v0], t
    )
    scale = np.max(np.abs(y[0]))
    np.testing.assert_allclose(closed.displacement(t), y[0], rtol=0, atol=RTOL_CLOSED_FORM * scale)
    np.testing.assert_allclose(result.x[1:], y[0], rtol=0, atol=RTOL_CLOSED_FORM * scale)
    if face == "leading":
        assert result.event == "tip"
        t_tip = closed.time_to_reach(0.12)
        assert result.t[-1] == pytest.approx(t_tip, rel=RTOL_CLOSED_FORM)
    else:  # inward on the trailing face: stops, cannot stick (ω²x ≫ fg), turns out and leaves
        assert result.event == "separated"
        assert abs(result.v[-1]) < 1e-9 * abs(v0)


def test_trailing_inward_is_the_papers_equation_8():
    omega, f = 45.0, 0.35
    slide = BladeSlide(omega, f, f, "corotating", "trailing")
    closed = slide.closed_form(0.08, -3.0)
    # ẍ + 2fωẋ − ω²x = +fg: b = fω, q = ω², c = fg
    assert (closed.b, closed.q, closed.c) == pytest.approx((f * omega, omega**2, f * G))
    leading = BladeSlide(omega, f, f, "corotating", "leading").closed_form(0.08, 3.0)
    assert (leading.b, leading.c) == pytest.approx((f * omega, -f * G))  # the vane equation


def test_stationary_floor_matches_independent_integration():
    omega, f = 60.0, 0.4
    slide = BladeSlide(omega, f, f, "stationary", "leading", tip=0.1)
    result = slide.integrate(0.02, 0.0, 1.0)
    assert result.event == "tip"
    t = result.t[result.t > 0]
    y = integrate(force_balance_rhs(omega, f, f, "stationary", 1, 0.0), [0.02, 1e-300], t)
    np.testing.assert_allclose(result.x[1:], y[0], rtol=0, atol=RTOL_CLOSED_FORM * 0.1)
    assert np.all(result.normal >= 0)
    # the face also carries the floor's circumferential drag: N/m = 2ωẋ + f g ωx/|u|
    u = np.hypot(result.v, omega * result.x)
    expected = 2 * omega * result.v + f * G * omega * result.x / u
    np.testing.assert_allclose(result.normal, expected, rtol=1e-12)


def test_sticking_threshold_is_omega_squared_x_equals_fg():
    f, x0 = 0.3, 0.02
    omega_stick = math.sqrt(f * G / x0)
    below = BladeSlide(omega_stick * (1 - 1e-6), 0.3, f, "corotating", tip=0.1)
    above = BladeSlide(omega_stick * (1 + 1e-6), 0.3, f, "corotating", tip=0.1)
    assert below.integrate(x0, 0.0, 1.0).event == "stuck"
    assert above.integrate(x0, 0.0, 10.0).event == "tip"


@pytest.mark.parametrize("k", [0.5, 0.4])  # disc, sphere
def test_rolling_without_slip(k):
    omega, x0, v0 = 30.0, 0.02, 0.2
    slide = BladeSlide(omega, face_friction=0.5, inertia_factor=k, tip=0.1)
    kappa = omega / math.sqrt(1 + k)
    result = slide.integrate(x0, v0, 1.0)
    expected = x0 * np.cosh(kappa * result.t) + v0 / kappa * np.sinh(kappa * result.t)
    np.testing.assert_allclose(result.x, expected, rtol=RTOL_CLOSED_FORM)
    closed = slide.closed_form(x0, v0)
    np.testing.assert_allclose(closed.displacement(result.t), expected, rtol=1e-13)
    # the friction needed for no slip, over the Coriolis normal force, must stay below f
    ratio = [slide.rolling_friction_ratio(x, v) for x, v in zip(result.x, result.v, strict=True)]
    assert max(ratio) == pytest.approx(k * kappa**2 * x0 / (2 * omega * v0), rel=1e-6)


def test_bad_inputs_are_named():
    with pytest.raises(ValueError, match="omega must be > 0"):
        BladeSlide(0.0)
    with pytest.raises(ValueError, match="floor must be"):
        BladeSlide(10.0, floor="moving")
    with pytest.raises(ValueError, match="stationary floor has no closed form"):
        BladeSlide(10.0, floor="stationary").closed_form(0.01, 0.1)
