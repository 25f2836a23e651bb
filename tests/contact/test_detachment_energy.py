"""The comb bond's energy (``detachment_energy``): a force above detachment_force begins a blow,
in which the held granule moves freely, of its own mass; after it the bond breaks if the
granule's kinetic energy E exceeds the bond's E_c, leaving it E − E_c, else it stops the granule.
The outcome is the impact law's, whatever the contact's stiffness (soft) or the step (rigid);
the force law's (no energy) is set by both. Each on both sides of its threshold, both models."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perga.contact.soft import SoftGranules, contact_parameters, uniform_table
from perga.engine import Simulation
from perga.model import ContactSpec, GranuleSpec, RotorSpec, System

G = 9.81  # m/s²
M = 2.0e-4  # kg, a granule
R = 2.5e-3  # m
E = 0.7  # restitution
V = 1.0  # m/s, the striking granule's speed
START = 1e-9  # N: the force that begins a blow (any contact)


FREE = 0.1 * M  # kg: a light granule strikes the held one and bounces back: one blow
V_STRUCK = (1 + E) * FREE / (FREE + M) * V  # m/s: the struck granule's speed, impulse law


def _pair(k_n: float, energy: float, held: bool = True) -> SoftGranules:
    """Granule 0 (held with ``energy``, J, unless not ``held``) struck head-on at V by granule 1
    of FREE kg, which bounces back; linear contact of stiffness k_n (N/m), 200 steps per
    contact (t_c = π√(m_eff/k_n) as e → 1)."""
    row = contact_parameters("linear", E, k_n=k_n, friction=0.3)
    t_c = math.pi * math.sqrt(FREE * M / (FREE + M) / k_n)
    return SoftGranules(
        np.array([[0.0, 0.0], [2 * R + 1e-6, 0.0]]), np.full(2, R), np.array([M, FREE]),
        uniform_table(row), v=np.array([[0.0, 0.0], [-V, 0.0]]), held=[held, False],
        bond_force=[START, math.inf], bond_energy=[energy, math.inf], dt=t_c / 200,
    )  # fmt: skip


def _blow(g: SoftGranules) -> SoftGranules:
    """Steps until the granules have parted (3 contact durations)."""
    g.step(600)
    return g


def _struck_energy(k_n: float) -> float:
    """½M|v|² of granule 0 struck free, J (the kernel's own impact)."""
    free = _blow(_pair(k_n, math.inf, held=False))
    return 0.5 * M * float(free.v[0] @ free.v[0])


def test_soft_blow_breaks_exactly_above_the_energy_it_leaves() -> None:
    """Held, the struck granule moves exactly as a free one (the same floats) until the blow
    ends; a bond 1e-9 below its kinetic energy E then breaks, one 1e-9 above stops it where it
    was pushed to, held again; a bond of E/2 leaves it 1/√2 of the free granule's velocity
    (1e-12: one square root)."""
    free = _blow(_pair(1e6, math.inf, held=False))
    energy = 0.5 * M * float(free.v[0] @ free.v[0])
    weak = _blow(_pair(1e6, energy * (1 - 1e-9)))
    assert weak.held[0] == 0 and weak.released_step[0] > 0
    strong = _blow(_pair(1e6, energy * (1 + 1e-9)))
    assert strong.held[0] == 1 and strong.released_step[0] == -1
    assert np.all(strong.v[0] == 0.0) and strong.x[0, 0] < 0.0  # pushed, then stopped
    half = _blow(_pair(1e6, 0.5 * energy))
    assert half.v[0] == pytest.approx(free.v[0] / math.sqrt(2), rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("side", [0.98, 1.02])
def test_soft_blow_outcome_does_not_depend_on_the_stiffness(side: float) -> None:
    """Three stiffnesses (contact durations ×1, ½, ¼): the struck granule's energy is the same
    to 1e-3 (the linear law's restitution does not depend on k_n; the impact law's ½M·V_STRUCK²
    to 1 %), so a bond of side × it breaks at all three below (0.98) and holds at all three
    above (1.02). With the force law the same blow's release is set by the stiffness: a bond
    at the middle one's peak force (the granule held throughout) holds at the softest and the
    middle one and breaks at the stiffest."""
    stiffnesses = (1e6, 4e6, 1.6e7)
    energies = [_struck_energy(k) for k in stiffnesses]
    assert max(energies) / min(energies) - 1 < 1e-3
    assert energies[1] == pytest.approx(0.5 * M * V_STRUCK**2, rel=1e-2)
    for k_n in stiffnesses:
        g = _blow(_pair(k_n, side * energies[1]))
        assert (g.held[0] == 0) == (side < 1.0), k_n
    peaks = []
    for k_n in stiffnesses:
        g = _pair(k_n, math.inf)
        g.bond_force[0] = math.inf
        peak = 0.0
        for _ in range(300):
            g.step(1)
            peak = max(peak, float(np.hypot(*g.f[0])))
        peaks.append(peak)
    outcomes = []
    for k_n in stiffnesses:
        g = _pair(k_n, math.inf)
        g.bond_force[0] = peaks[1]
        outcomes.append(bool(_blow(g).held[0] == 0))
    assert outcomes == [False, False, True]


def _soft_under_gravity(bond: float) -> SoftGranules:
    row = contact_parameters("linear", E, k_n=1e6, friction=0.3)
    return SoftGranules(
        np.array([[0.0, 0.0]]), np.full(1, R), np.full(1, M), uniform_table(row),
        held=[True], bond_force=[bond], bond_energy=[1.0], dt=1e-5, gravity=(0.0, -G),
    )  # fmt: skip


@pytest.mark.parametrize("side", [1.0 - 1e-6, 1.0 + 1e-6])
def test_soft_bond_weaker_than_the_weight_lets_go_at_once(side: float) -> None:
    """A bond with an energy still carries a static load by its force: 1e-6 below m·g it lets
    the granule fall at the first step; 1e-6 above it holds it at rest for 100 steps."""
    g = _soft_under_gravity(side * M * G)
    g.step(100)
    if side < 1.0:
        assert g.released_step[0] == 0 and g.v[0, 1] < 0.0
    else:
        assert g.held[0] == 1 and np.all(g.x[0] == 0.0)


def _rigid(granules: tuple[GranuleSpec, ...], dt: float, gravity: float = 0.0) -> Simulation:
    return Simulation(
        System(
            rotor=RotorSpec(angular_velocity=0.0, radius=0.001),
            hammers=(),
            granules=granules,
            contacts=(ContactSpec("bb", "bb", E, 0.0),),
            granule_dt=dt,
            gravity=(0.0, -gravity),
            granule_collisions=True,
        )
    )


def _rigid_blow(energy: float, dt: float) -> Simulation:
    """A granule of FREE kg striking a held one head-on at V (Chipmunk's impulse)."""
    held = GranuleSpec(
        position=(0.0, 0.0), velocity=(0.0, 0.0), radius=R, mass=M, material="bb",
        bond_force=START, bond_energy=energy,
    )  # fmt: skip
    free = GranuleSpec(
        position=(2 * R + 5e-4, 0.0), velocity=(-V, 0.0), radius=R, mass=FREE, material="bb"
    )
    sim = _rigid((held, free), dt)
    sim.run(2e-3)
    return sim


@pytest.mark.parametrize("side", [1.0 - 1e-6, 1.0 + 1e-6])
def test_rigid_blow_outcome_does_not_depend_on_the_step(side: float) -> None:
    """At three steps (1e-4, 5e-5, 2.5e-5 s) the struck granule takes ½M·V_STRUCK² from the
    impulse law; a bond 1e-6 below that breaks and leaves it √(1 − E_c/E) of V_STRUCK (1e-6:
    Chipmunk's impulse in its units), one 1e-6 above stops it, held."""
    law = 0.5 * M * V_STRUCK**2
    for dt in (1e-4, 5e-5, 2.5e-5):
        sim = _rigid_blow(side * law, dt)
        state = sim.contacts.granule_state()
        assert bool(sim.contacts.releases) == (side < 1.0), dt
        speed = float(np.hypot(*state.velocities[0]))
        if side < 1.0:
            assert speed == pytest.approx(V_STRUCK * math.sqrt(1 - side), rel=1e-3), dt
        else:
            assert state.held[0] and speed < 1e-12


@pytest.mark.parametrize("side", [1.0 - 1e-6, 1.0 + 1e-6])
def test_rigid_bond_weaker_than_the_weight_lets_go_at_once(side: float) -> None:
    """As the soft one: a bond with an energy 1e-6 below m·g lets go at the first step, one
    1e-6 above holds the granule for 100 steps."""
    granule = GranuleSpec(
        position=(0.0, 0.1), velocity=(0.0, 0.0), radius=R, mass=M, material="bb",
        bond_force=side * M * G, bond_energy=1.0,
    )  # fmt: skip
    sim = _rigid((granule,), 1e-4, G)
    sim.run(100 * 1e-4)
    releases = sim.contacts.releases
    if side < 1.0:
        assert len(releases) == 1 and releases[0].time == pytest.approx(1e-4, rel=1e-9)
    else:
        assert not releases and sim.contacts.granule_state().held[0]
