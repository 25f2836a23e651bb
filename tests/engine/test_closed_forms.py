"""Closed forms of design §4 through the engine: friction on a blade face, rolling on it, the
co-rotating floor, and the oblique impact on a fixed wall (relative error <= 1e-3)."""

from __future__ import annotations

import pytest

from perga.analytic.impact import oblique_impact
from perga.analytic.sliding import BladeSlide
from perga.engine import Simulation
from perga.model import (
    ContactSpec,
    EffectsSpec,
    FloorFrictionSpec,
    GranuleSpec,
    RotorSpec,
    System,
)
from tests.engine.helpers import blade_exit, plate

TOLERANCE = 1e-3
X0, TIP, RADIUS = 0.05, 0.15, 0.002  # m
# dt = 5e-6 s for the blade runs. Measured relative errors (exit time / exit speed), first
# order in dt like the frictionless blade (test_blade.py):
#   face friction 0.3, ω = 100:   2.5e-4 / 1.8e-4 at 1e-5 s, 1.5e-4 / 2.7e-4 at 5e-6 s
#   rolling disc, ω = 100:        1.7e-4 / 4.4e-4 at 1e-5 s, 1.2e-4 / 2.5e-4 at 5e-6 s
#   co-rotating floor, ω = 20:    1.05e-4 / 1.3e-4 at 1e-5 s, 6.0e-5 / 7.4e-5 at 5e-6 s
DT = 5e-6


def _check_exit(slide: BladeSlide, omega: float, v0: float, **kwargs) -> None:
    exact = slide.closed_form(X0, v0)
    t_exact = exact.time_to_reach(TIP)
    t, v, _ = blade_exit(omega, X0, v0, TIP, DT, **kwargs)
    assert t == pytest.approx(t_exact, rel=TOLERANCE)
    assert v == pytest.approx(float(exact.velocity(t_exact)), rel=TOLERANCE)


def test_sliding_with_face_friction() -> None:
    """ẍ + 2fωẋ − ω²x = 0 (leading face, f = 0.3), from a small outward start (0.5 m/s)."""
    _check_exit(BladeSlide(100.0, face_friction=0.3), 100.0, 0.5, face_friction=0.3)


def test_rolling_disc() -> None:
    """ẍ = (2/3)ω²x. It starts rolling at 1 m/s (spin −v0/r relative to the blade): from rest
    the face's normal force 2mωẋ is zero and no friction can hold the rolling (the granule
    slips first: exit time off by 4.7e-3 at any dt). Friction needed: |F|/N = ωx/(6ẋ) <= 0.83
    at the start, falling after, so f = 1 holds it (the result is identical with f = 2)."""
    slide = BladeSlide(100.0, inertia_factor=0.5)
    assert slide.rolling_friction_ratio(X0, 1.0) < 1.0
    _check_exit(slide, 100.0, 1.0, face_friction=1.0, rolls=True, spin=-1.0 / RADIUS)


def test_corotating_floor() -> None:
    """ẍ + 2fωẋ − ω²x = −f_fl g with face and floor friction 0.3; ω = 20 rad/s so that the
    floor's 2.9 m/s² is 15 % of the centrifugal 20 m/s² at the start."""
    slide = BladeSlide(20.0, face_friction=0.3, floor="corotating", floor_friction=0.3)
    effects = EffectsSpec(floor_friction=FloorFrictionSpec("corotating", 0.3))
    _check_exit(slide, 20.0, 0.5, face_friction=0.3, effects=effects)


@pytest.mark.parametrize(
    ("v_t", "e", "f", "sticks"),
    [(1.0, 0.5, 0.4, True), (12.0, 0.6, 0.1, False)],
)
def test_oblique_impact_on_fixed_wall(v_t: float, e: float, f: float, sticks: bool) -> None:
    """A rolling disc granule hits the top face of a fixed wall (n = +y, t = +x) at v_n = −5
    m/s. One rigid impact is one impulse solve, so the result is exact to rounding (1e-3 is the
    requirement; dt = 1e-5 s does not enter a single impact)."""
    m, v_n = 50e-6, -5.0
    wall = plate(
        -0.05, 0.05, -0.01, 0.0, 1.0,
        hinge_radius=0.0, angle_on_rotor=0.0, mount="welded", material="steel",
    )  # fmt: skip
    granule = GranuleSpec(
        position=(0.0, RADIUS + 1e-5), velocity=(v_t, v_n), radius=RADIUS, mass=m, material="bb"
    )
    spec = System(
        rotor=RotorSpec(angular_velocity=0.0, radius=0.2),
        hammers=(wall,),
        granules=(granule,),
        contacts=(ContactSpec("bb", "steel", restitution=e, friction=f),),
        granule_dt=1e-5,
    )
    sim = Simulation(spec)
    sim.run(2e-5)
    exact = oblique_impact(m, RADIUS, v_n, v_t, e, f, shape="disc")
    assert exact.sticks is sticks
    (v_after,) = sim.frame().granules.velocities
    (spin,) = sim.frame().granules.angular_velocities
    assert v_after[0] == pytest.approx(exact.tangential_velocity, rel=TOLERANCE)
    assert v_after[1] == pytest.approx(exact.normal_velocity, rel=TOLERANCE)
    assert spin == pytest.approx(exact.spin, rel=TOLERANCE)
    # the ledger's per-contact dissipation includes friction: exact to rounding (measured 2e-16)
    assert sim.energy().contact_dissipation == pytest.approx(exact.dissipated, rel=1e-9)
