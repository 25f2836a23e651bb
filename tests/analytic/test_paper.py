"""The paper's model as published (perga.analytic.paper) against independent integrations."""

import math

import numpy as np
import pytest
import sympy as sp

from perga.analytic.paper import (
    PaperRadialMotion,
    PaperSuccessiveImpacts,
    fit_successive_decay,
    paper_cumulative_loss,
    paper_discriminant,
    paper_impulse_law,
    paper_particular_solution,
    paper_roots,
    paper_speed,
    paper_trajectory,
    paper_velocity_components,
    paper_wronskian,
)
from tests.conftest import RTOL_CLOSED_FORM, integrate

G = 9.80665


@pytest.mark.parametrize(("omega", "f"), [(30.0, 0.0), (34.1, 0.3), (100.0, 0.8), (300.0, 1.5)])
@pytest.mark.parametrize("v0", [0.0, -1.0, 2.5, None])  # None: the decaying branch C1 = 0
def test_eq27_solves_eq8_like_an_independent_integration(omega, f, v0):
    x0 = 0.08
    if v0 is None:
        motion = PaperRadialMotion.decaying_branch(omega, f, x0)
    else:
        motion = PaperRadialMotion.from_launch_velocity(omega, f, x0, v0)
    t = np.linspace(0, 0.05, 51)
    y = integrate(
        lambda _t, s: [s[1], f * G - 2 * f * omega * s[1] + omega**2 * s[0]],
        [x0, motion.launch_velocity],
        t,
    )
    scale = np.max(np.abs(y[0]))
    np.testing.assert_allclose(motion.displacement(t), y[0], rtol=0, atol=RTOL_CLOSED_FORM * scale)
    vscale = np.max(np.abs(y[1]))
    np.testing.assert_allclose(motion.velocity(t), y[1], rtol=0, atol=RTOL_CLOSED_FORM * vscale)
    # the ODE residual itself, relative to its largest term
    assert np.max(np.abs(motion.residual(t))) <= 1e-9 * omega**2 * scale


def test_decaying_branch_needs_the_exact_launch_speed():
    omega, f, x0 = 34.1, 0.3, 0.08
    lam1, lam2 = paper_roots(omega, f)
    assert lam1 > 0 > lam2  # a saddle: one growing and one decaying mode
    motion = PaperRadialMotion.decaying_branch(omega, f, x0)
    assert motion.launch_velocity == pytest.approx(lam2 * (x0 + f * G / omega**2), rel=1e-14)
    # 1 % off the launch speed and x grows again within 0.2 s
    off = PaperRadialMotion.from_launch_velocity(omega, f, x0, 0.99 * motion.launch_velocity)
    assert off.c1 > 0
    assert off.displacement(0.2) > x0


def test_f_to_zero_gives_cosh_sinh():
    omega, x0, v0 = 40.0, 0.05, 1.3
    motion = PaperRadialMotion.from_launch_velocity(omega, 0.0, x0, v0)
    t = np.linspace(0, 0.1, 11)
    expected = x0 * np.cosh(omega * t) + v0 / omega * np.sinh(omega * t)
    np.testing.assert_allclose(motion.displacement(t), expected, rtol=1e-13)


def test_roots_and_discriminant_are_real_for_every_input():
    for omega, f in [(1.0, 0.0), (10.0, 0.5), (500.0, 3.0)]:
        d = paper_discriminant(omega, f)
        lam1, lam2 = paper_roots(omega, f)
        assert d > 0
        assert lam1 * lam2 == pytest.approx(-(omega**2), rel=1e-13)  # Vieta: product −ω²
        assert lam1 + lam2 == pytest.approx(-2 * f * omega, rel=1e-13, abs=1e-12)


def test_printed_wronskian_has_the_wrong_sign_and_eq24_is_still_right():
    omega, f = 50.0, 0.4
    t = np.array([0.0, 0.01])
    lam1, lam2 = paper_roots(omega, f)
    e1, e2 = np.exp(lam1 * t), np.exp(lam2 * t)
    determinant = e1 * lam2 * e2 - lam1 * e1 * e2  # the 2x2 determinant of eq. (15)
    np.testing.assert_allclose(paper_wronskian(omega, f, t), determinant, rtol=1e-13)
    np.testing.assert_allclose(paper_wronskian(omega, f, t, printed=True), -determinant, rtol=1e-13)
    assert paper_particular_solution(omega, f) == pytest.approx(-f * G / omega**2, rel=1e-12)


def test_general_solution_matches_sympy_dsolve():
    t = sp.symbols("t", real=True)
    w, f, g, x0, v0 = sp.symbols("omega f g x0 v0", positive=True)
    x = sp.Function("x")
    ode = sp.Eq(x(t).diff(t, 2) + 2 * f * w * x(t).diff(t) - w**2 * x(t), f * g)
    sol = sp.dsolve(ode, x(t), ics={x(0): x0, x(t).diff(t).subs(t, 0): v0}).rhs
    values = {w: 37.0, f: 0.35, g: G, x0: 0.08, v0: -2.0}
    motion = PaperRadialMotion.from_launch_velocity(37.0, 0.35, 0.08, -2.0)
    for tv in (0.0, 0.013, 0.04):
        assert float(sol.subs(values).subs(t, tv)) == pytest.approx(
            float(motion.displacement(tv)), rel=1e-12
        )


def test_trajectory_and_velocity_are_consistent():
    motion = PaperRadialMotion.from_launch_velocity(60.0, 0.3, 0.04, 0.5)
    R, h = 0.1, 1e-6
    t = np.linspace(0.0, 0.03, 7)
    # central differences of eq. (30)-(31) against eq. (35): O(h²) ≈ 1e-12·ω³r, use 1e-7 rel
    xp, yp = paper_trajectory(motion, t + h, R)
    xm, ym = paper_trajectory(motion, t - h, R)
    vx, vy = paper_velocity_components(motion, t, R)
    np.testing.assert_allclose((xp - xm) / (2 * h), vx, rtol=1e-7)
    np.testing.assert_allclose((yp - ym) / (2 * h), vy, rtol=1e-7)
    np.testing.assert_allclose(np.hypot(vx, vy), paper_speed(motion, t, R), rtol=1e-13)
    printed = paper_speed(motion, t, R, printed=True)
    assert np.all(printed < paper_speed(motion, t, R))  # (38) drops R: too slow for R > 0


def test_printed_impulse_law_reverses_slow_slip():
    # |v0t| < f(1+e)|v0n|: the printed J_t overshoots and reverses the tangential velocity
    v1n, v1t, jn, jt = paper_impulse_law(m=1e-4, v0n=-5.0, v0t=0.5, e=0.7, f=0.4)
    assert v1n == pytest.approx(3.5)
    assert jn == pytest.approx(1e-4 * 1.7 * 5.0)
    assert v1t < 0 < 0.5
    assert jt == pytest.approx(-0.4 * jn)


def test_successive_impacts_continuous_rule_and_fit():
    radii = [0.080, 0.045, 0.028, 0.015]
    dt = 0.0123
    x01, beta = fit_successive_decay(radii, dt)
    model = PaperSuccessiveImpacts(beta, 40.0, 0.0, x01, tuple(dt * i for i in range(4)))
    offsets = model.initial_offsets
    ratio = offsets[1:] / offsets[:-1]
    np.testing.assert_allclose(ratio, math.exp(-beta * dt), rtol=1e-13)  # geometric
    # least squares on logs: residuals sum to zero
    assert np.sum(np.log(offsets / np.array(radii))) == pytest.approx(0.0, abs=1e-12)
    x, xd, phi = model.segment(2, [model.impact_times[2]])
    assert x[0] == pytest.approx(offsets[2], rel=1e-14)
    assert xd[0] == pytest.approx(-beta * offsets[2], rel=1e-14)
    assert phi[0] == pytest.approx(40.0 * 2 * dt, rel=1e-14)
    energy = model.energy_after_impact(1e-4)
    # R = 0 and ẋ = −βx: E ∝ x², so E3/E1 = (x3/x1)²
    assert energy[2] / energy[0] == pytest.approx((offsets[2] / offsets[0]) ** 2, rel=1e-12)
    scaled = PaperSuccessiveImpacts(beta, 40.0, 0.0, x01, model.impact_times, "scaled", 0.7)
    np.testing.assert_allclose(scaled.initial_offsets[1:] / offsets[1:], 0.7 ** np.arange(1, 4))


def test_cumulative_loss_is_e_squared_per_impact():
    np.testing.assert_allclose(paper_cumulative_loss(0.7, 3), [0.49, 0.2401, 0.117649])
    with pytest.raises(ValueError, match="e must be in"):
        paper_cumulative_loss(1.2, 3)
