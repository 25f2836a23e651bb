"""Free two-body normal impact and exact per-pair restitution."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from tests.engine.helpers import plate, rectangle

from perga.analytic.impact import hinged_impact, normal_impact
from perga.engine import Simulation
from perga.machine import units
from perga.model import ContactSpec, GranuleSpec, HammerSpec, RotorSpec, System

# A single rigid impact is one impulse solve: Chipmunk's restitution target is exact, so the
# result is exact up to rounding (~1e-15, design §5). 1e-6 leaves room for iteration counts
# and unit conversions while still catching any modelling error (a wrong mass or e).
RTOL_IMPULSE = 1e-6


@pytest.mark.parametrize(
    ("m", "M", "e"),
    [(10e-6, 0.005, 0.6), (250e-6, 0.2, 0.3), (50e-6, 0.05, 1.0), (100e-6, 0.02, 0.0)],
)
def test_free_two_body_impact(m: float, M: float, e: float) -> None:
    V, r, length, width = 20.0, 0.002, 0.1, 0.01
    # hammer moving +y, its centre of mass, the contact point and the granule centre collinear
    hammer = plate(
        0.0, length, -width / 2, width / 2, M,
        hinge_radius=0.0, angle_on_rotor=0.0, mount="free", material="steel", velocity=(0.0, V),
    )  # fmt: skip
    granule = GranuleSpec(
        position=(length / 2, width / 2 + r + 1e-4), velocity=(0.0, 0.0),
        radius=r, mass=m, material="beebread",
    )  # fmt: skip
    spec = System(
        rotor=RotorSpec(angular_velocity=0.0, radius=0.2),
        hammers=(hammer,),
        granules=(granule,),
        contacts=(ContactSpec("beebread", "steel", restitution=e, friction=0.3),),
        granule_dt=1e-6,
    )
    sim = Simulation(spec)
    sim.run(2e-5)
    exact = normal_impact(m, M, 0.0, V, e)
    assert sim.frame().granules.velocities[0, 1] == pytest.approx(
        exact.granule_velocity, rel=RTOL_IMPULSE
    )
    assert sim.frame().machine.velocities[0, 1] == pytest.approx(
        exact.hammer_velocity, rel=RTOL_IMPULSE
    )
    (impact,) = sim.impacts
    assert (impact.granule, impact.hammer) == (0, 0)
    assert impact.normal_velocity_before == pytest.approx(-V, rel=RTOL_IMPULSE)
    assert impact.normal_velocity_after == pytest.approx(e * V, rel=RTOL_IMPULSE, abs=1e-12)
    assert impact.normal_impulse == pytest.approx(exact.impulse, rel=RTOL_IMPULSE)
    # the energy columns of the impacts table, against the same closed form; a central impact
    # has no tangential velocity (absolute 1e-12 m/s: round-off of a 20 m/s normal)
    assert impact.tangential_velocity_before == pytest.approx(0.0, abs=1e-12)
    assert impact.tangential_velocity_after == pytest.approx(0.0, abs=1e-12)
    assert impact.granule_energy_gain == pytest.approx(exact.granule_energy_gain, rel=RTOL_IMPULSE)
    assert impact.dissipated == pytest.approx(exact.dissipated, rel=RTOL_IMPULSE, abs=1e-15)
    assert impact.hammer_energy_before == pytest.approx(0.5 * M * V**2, rel=RTOL_IMPULSE)


def test_restitution_is_the_pairs_not_the_product() -> None:
    """Two granules of different materials fall onto one steel wall; each rebounds with its
    own pair's e (exact to rounding: 1e-12), not e_granule × e_wall."""
    wall = plate(
        -0.05, 0.05, -0.01, 0.0, 1.0,
        hinge_radius=0.0, angle_on_rotor=0.0, mount="welded", material="steel",
    )  # fmt: skip
    r, v = 0.002, -5.0
    granules = tuple(
        GranuleSpec(position=(x, r + 1e-4), velocity=(0.0, v), radius=r, mass=50e-6, material=mat)
        for x, mat in ((-0.02, "beebread"), (0.02, "wax"))
    )
    contacts = (
        ContactSpec("steel", "beebread", restitution=0.55, friction=0.4),
        ContactSpec("wax", "steel", restitution=0.8, friction=0.1),
    )
    spec = System(
        rotor=RotorSpec(angular_velocity=0.0, radius=0.2),
        hammers=(wall,),
        granules=granules,
        contacts=contacts,
        granule_dt=1e-5,
    )
    sim = Simulation(spec)
    sim.run(1e-4)
    after = sim.frame().granules.velocities[:, 1]
    assert after[0] == pytest.approx(-0.55 * v, rel=1e-12)
    assert after[1] == pytest.approx(-0.8 * v, rel=1e-12)
    by_granule = {i.granule: i for i in sim.impacts}
    assert by_granule[0].normal_velocity_after / -by_granule[0].normal_velocity_before == (
        pytest.approx(0.55, rel=1e-12)
    )


def test_hinged_hammer_on_kinematic_rotor() -> None:
    """A hinged hammer swept by the rotor strikes a granule at rest: the granule leaves as
    :func:`hinged_impact` predicts from the pre-impact state (M → M_eff = I_A/d²).

    Tolerance 1e-5: measured 8.8e-7 at dt = 1e-5 s and 3.0e-8 at 1e-6 s, the same at 10 and
    50 iterations; the residual is the hinge's centripetal impulse within the impact step,
    which the instantaneous-impact law leaves out (first order in dt)."""
    omega, R, a, r, M, m, e = 100.0, 0.12, 0.06, 0.002, 0.078, 100e-6, 0.6
    hammer = plate(
        -0.01, 0.09, -0.01, 0.01, M,
        hinge_radius=R, angle_on_rotor=0.0, mount="hinged", material="steel",
    )  # fmt: skip
    granule = GranuleSpec(
        position=(R + a, 0.01 + r + 1e-4), velocity=(0.0, 0.0), radius=r, mass=m, material="bb"
    )
    spec = System(
        rotor=RotorSpec(angular_velocity=omega, radius=0.2),
        hammers=(hammer,),
        granules=(granule,),
        contacts=(ContactSpec("bb", "steel", restitution=e, friction=0.0),),
        granule_dt=1e-5,
    )
    sim = Simulation(spec)
    body = sim.machine.hammer_bodies[0]
    while not sim.impacts:
        spin_before = body.angular_velocity / units.TIME  # rad/s
        sim.step()
    (impact,) = sim.impacts
    # the impact row's pre-impact state: Ω before the impulses, α after the step's drift
    assert impact.hammer_angular_velocity_before == pytest.approx(spin_before, rel=1e-12)
    assert impact.hammer_swing_angle_before == pytest.approx(
        sim.frame().machine.swing_angles[0], rel=1e-12, abs=1e-15
    )
    assert impact.granule_velocity_before == (0.0, 0.0)
    # positions have already advanced in the impact step (step order), velocities have not
    hinge = np.array(body.position) * units.LENGTH
    centre = np.array(body.local_to_world(body.center_of_gravity)) * units.LENGTH
    exact = hinged_impact(
        M=M,
        I_A=hammer.moment_about_hinge,
        r_c=centre - hinge,
        r_k=np.array(impact.point) - hinge,
        n=impact.normal,
        Omega=spin_before,
        v_A=omega * np.array([-hinge[1], hinge[0]]),
        m=m,
        v_g=(0.0, 0.0),
        e=e,
    )
    np.testing.assert_allclose(
        sim.frame().granules.velocities[0], exact.granule_velocity, rtol=1e-5
    )
    assert impact.normal_impulse == pytest.approx(exact.impulse, rel=1e-5)


def _corner_hit(outline) -> Simulation:
    """A granule fired at 3 m/s at the corner (0, 0) of a welded hammer, from 225°."""
    r, m = 0.002, 100e-6
    hammer = HammerSpec(
        outline=outline, mass=0.1, moment_about_hinge=1e-3, centre_of_mass=(0.02, 0.02),
        hinge_radius=0.0, angle_on_rotor=0.0, mount="welded", material="steel",
    )  # fmt: skip
    away = np.array([-1.0, -1.0]) / np.sqrt(2.0)
    granule = GranuleSpec(
        position=tuple(away * (r + 1e-4)), velocity=tuple(-3.0 * away), radius=r, mass=m,
        material="bb",
    )  # fmt: skip
    spec = System(
        rotor=RotorSpec(angular_velocity=0.0, radius=0.2),
        hammers=(hammer,),
        granules=(granule,),
        contacts=(ContactSpec("bb", "steel", restitution=0.7, friction=0.0),),
        granule_dt=1e-5,
    )
    sim = Simulation(spec)
    sim.run(2e-4)
    return sim


def test_two_pieces_of_one_hammer_give_one_impact() -> None:
    """The L-shaped hammer's corner (0, 0) is split between its two convex pieces: Chipmunk
    makes a contact with each, the recorder one impact whose impulse is their sum. Against the
    square with that corner: the same impulse and rebound (to round-off of the solver's split,
    1e-9), one impact each."""
    side = 0.02
    square = rectangle(0.0, side, 0.0, side)
    ell = ((0.0, 0.0), (2 * side, 0.0), (2 * side, side), (side, side), (side, 2 * side),
           (0.0, 2 * side))  # fmt: skip
    whole, pieces = _corner_hit(square), _corner_hit(ell)
    assert len(pieces.machine.hammer_shapes[0]) == 2
    (one,) = whole.impacts
    (merged,) = pieces.impacts
    assert merged.normal_impulse == pytest.approx(one.normal_impulse, rel=1e-9)
    np.testing.assert_allclose(
        pieces.frame().granules.velocities, whole.frame().granules.velocities, rtol=1e-9, atol=1e-12
    )


def test_a_sliding_points_impact_is_taken_at_one_point() -> None:
    """A sliding point (rolls = false) struck by a welded hammer of a kinematic rotor, with
    friction: the hammer's material at the contact keeps its velocity, so the impact row's
    dissipated energy −J·v̄_rel equals ½m(|v_rel,before|² − |v_rel,after|²) exactly when both
    velocities are taken at one point (round-off: 1e-12). The contact moves onto the granule's
    centre in pre_solve; taken before the move (at its begin) the row mixed the surface point
    and the centre: 3.9e-3 off."""
    from perga.case import load_case
    from perga.model.compile import compile_case

    sets = ["granules.rolls=false", 'hammers.mount="welded"', "solver.duration=0.05"]
    case = load_case(Path(__file__).parents[3] / "cases" / "single-granule.toml", overrides=sets)
    sim = Simulation(compile_case(case))
    sim.run(0.05)
    (impact,) = sim.impacts
    m = case.granule_mass
    before = impact.normal_velocity_before**2 + impact.tangential_velocity_before**2
    after = impact.normal_velocity_after**2 + impact.tangential_velocity_after**2
    assert abs(impact.tangential_velocity_after - impact.tangential_velocity_before) > 0.1
    assert impact.dissipated == pytest.approx(0.5 * m * (before - after), rel=1e-12)
