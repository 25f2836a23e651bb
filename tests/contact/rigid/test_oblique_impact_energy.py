"""The rigid impact recorder's energy of an oblique frictional impact that spins the granule: a
disc thrown at the face of a welded hammer at rest. Its energy gain (impacts.csv's
granule_energy_gain) counts the spin after the impact as well as before, so that with e ≤ 1 and
friction it is never positive; it equals the closed form of
:func:`perga.analytic.impact.oblique_impact` (Coulomb friction with its sticking cap), as do the
spin after, the slip of the granule's rim before and after and the contact's dissipation
−J·v̄_rel (the relative velocity taken where the impulse acts)."""

from __future__ import annotations

import pytest
from tests.engine.helpers import plate

from perga.analytic.impact import oblique_impact
from perga.engine import Simulation
from perga.model import ContactSpec, GranuleSpec, RotorSpec, System

M, R = 100e-6, 0.002  # kg, m: the granule
F = 0.3  # friction
V_N = -4.0  # m/s: towards the face
RTOL = 1e-6
"""One impulse solve against an immovable face: exact to the solver's iterations and unit
conversions (as the normal impact's, tests/contact/rigid/test_impact.py)."""


def _impact(v_t: float, spin: float, e: float):
    """The impact row of a disc at (v_t, V_N) spinning at ``spin`` (rad/s) striking the top
    face (y = 0, normal +y, tangent +x) of a welded hammer on a rotor at rest."""
    face = plate(
        -0.05, 0.05, -0.01, 0.0, 1.0,
        hinge_radius=0.0, angle_on_rotor=0.0, mount="welded", material="steel",
    )  # fmt: skip
    granule = GranuleSpec(
        position=(0.0, R + 1e-4), velocity=(v_t, V_N), radius=R, mass=M, material="bb",
        angular_velocity=spin,
    )  # fmt: skip
    sim = Simulation(
        System(
            rotor=RotorSpec(angular_velocity=0.0, radius=0.2),
            hammers=(face,),
            granules=(granule,),
            contacts=(ContactSpec("bb", "steel", restitution=e, friction=F),),
            granule_dt=1e-5,
        )
    )
    sim.run(1e-4)
    (impact,) = sim.impacts
    return impact


@pytest.mark.parametrize(
    ("v_t", "spin", "e", "sticks"),
    [
        (2.0, 0.0, 0.7, True),  # slip stopped: rolls off
        (8.0, 0.0, 0.7, False),  # slides throughout
        (1.0, -5000.0, 1.0, False),  # back-spin, elastic in the normal: slides
        (3.0, 500.0, 0.5, True),  # top-spin
    ],
)
def test_an_oblique_frictional_impact_never_gains_energy(
    v_t: float, spin: float, e: float, sticks: bool
) -> None:
    """Spin after, slip, energy gain (≤ 0, the spin counted before and after) and dissipation
    (the gain's opposite: the face is at rest) equal the closed form's (RTOL; measured 2e-16);
    the case's regime (sticking or sliding) is the one named."""
    law = oblique_impact(M, R, V_N, v_t, e, F, shape="disc", omega_g=spin)
    assert law.sticks == sticks
    impact = _impact(v_t, spin, e)
    gain = law.energy_after - law.energy_before
    assert gain < 0.0
    assert impact.granule_spin_before == pytest.approx(spin, abs=1e-9)
    assert impact.granule_spin_after == pytest.approx(law.spin, rel=RTOL)
    # the row's tangent is the normal turned +90°: −x here; its slip is the granule's rim's
    slip = (impact.tangential_velocity_before, impact.tangential_velocity_after)
    assert slip == pytest.approx((-law.slip_before, -law.slip_after), abs=RTOL * abs(v_t))
    assert impact.granule_energy_gain == pytest.approx(gain, rel=RTOL)
    assert impact.granule_energy_gain <= 0.0
    assert impact.dissipated == pytest.approx(-gain, rel=RTOL)
