"""A disc that slips and rolls on a face turning with the rotor (perga.analytic.disc_on_face)
against closed forms: rolling, (1 + k)ẍ = ω²x − σ f_fl g, is linear; slipping, x(t) is the
sliding point's closed form and the spin follows from ∫N dt = s(2ω(x − x0) − ω²h t), so the
slip u(t) = ẋ + s a (Ω − ω) is known in closed form and its root is the start of rolling.
The integrator runs at rtol 1e-10 (DOP853): 1e-8 leaves two orders for the phase changes."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from perga.analytic.disc_on_face import DiscOnFace
from perga.analytic.sliding import BladeSlide, LinearSlide

W, A, K, G = 62.83, 0.0025, 0.5, 9.80665


def test_rolling_from_the_start_is_the_linear_closed_form() -> None:
    """Friction f = 5 holds the disc rolling (k|ẍ| ≤ f N all along); over a co-rotating floor
    of 0.35 moving outward: ẍ − ω²/(1 + k)·x = −f_fl g/(1 + k)."""
    face = BladeSlide(W, 5.0, 0.35, "corotating", "leading", tip=0.15, inner=0.05)
    x0, v0 = 0.09, 0.5
    result = DiscOnFace(face, A, K).integrate(x0, v0, W - v0 / A, 0.05)
    assert result.event == "tip" and result.rolling.all()
    exact = LinearSlide(0.0, W**2 / (1 + K), -0.35 * G / (1 + K), x0, v0)
    assert result.x == pytest.approx(exact.displacement(result.t), rel=1e-8)
    assert result.v == pytest.approx(exact.velocity(result.t), rel=1e-8)
    # the spin keeps the slip at zero
    slip = result.v + A * (result.spin - W)
    assert np.abs(slip).max() < 1e-8 * np.abs(result.v).max()


@pytest.mark.parametrize("face_side", ["leading", "trailing"])
def test_slipping_until_the_slip_vanishes_then_rolling(face_side: str) -> None:
    """A disc launched outward without spin relative to the face (u = ẋ > 0) slips; friction
    −fN spins it up; rolling starts where the closed-form slip reaches 0, found by brentq.
    On the trailing face N = −2ωẋ < 0 outward: the disc leaves the face at once."""
    f, x0, v0 = 0.35, 0.09, 0.05
    face = BladeSlide(W, f, 0.0, "none", face_side, tip=10.0, inner=0.0)
    disc = DiscOnFace(face, A, K)
    result = disc.integrate(x0, v0, W, 0.04)
    if face_side == "trailing":
        assert result.event == "separated" and result.t[-1] == 0.0
        return
    s = 1
    slide = face.closed_form(x0, v0)

    def slip(t: float) -> float:
        x, v = float(slide.displacement(t)), float(slide.velocity(t))
        spin = W - f * 2 * W * (x - x0) / (K * A)  # Ω̇ = s F/(k a), F = −f N, N = 2ωẋ
        return v + s * A * (spin - W)

    t_roll = brentq(slip, 0.01, 0.04, xtol=1e-15)
    first = int(np.argmax(result.rolling))
    assert result.rolling[first] and not result.rolling[1:first].any()
    assert result.t[first - 1] == pytest.approx(t_roll, rel=1e-8)
    slipping = result.t <= t_roll
    t = result.t[slipping]
    assert result.x[slipping] == pytest.approx(slide.displacement(t), rel=1e-9)
    assert result.v[slipping] == pytest.approx(slide.velocity(t), rel=1e-8)


def test_the_slip_reverses_friction() -> None:
    """A disc spun faster than rolling needs (u < 0 while ẋ > 0) is dragged back by friction:
    ẍ = ω²x + fN, faster than the sliding point (ẍ = ω²x − fN) or the rolling disc."""
    face = BladeSlide(W, 0.35, 0.0, "none", "leading", tip=0.2, inner=0.0)
    x0, v0 = 0.09, 0.5
    spun = DiscOnFace(face, A, K).integrate(x0, v0, W - 3 * v0 / A, 1e-3)
    point = face.integrate(x0, v0, 1e-3)
    assert spun.v[-1] > point.v[-1]
    assert (spun.v[1:] + A * (spun.spin[1:] - W) < 0).all()


def test_refusals() -> None:
    face = BladeSlide(W, 0.35)
    with pytest.raises(ValueError, match="sliding-point"):
        DiscOnFace(BladeSlide(W, 0.35, inertia_factor=0.5), A)
    with pytest.raises(ValueError, match="radius"):
        DiscOnFace(face, 0.0)
    with pytest.raises(ValueError, match="x0"):
        DiscOnFace(BladeSlide(W, 0.35, tip=0.1), A).integrate(0.2, 1.0, W, 1e-3)
    assert math.isfinite(DiscOnFace(face, A).integrate(0.09, 1.0, W, 1e-3).x[-1])
