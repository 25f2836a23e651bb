"""A comb bond weaker than its granule's weight lets go at once: a vertical rotor (gravity in the
plane), one granule held in a comb cell far from the hammers, a case run through the whole path
(case -> system -> simulation), rigid and soft contacts, with and without a bond energy. Below
m·g the granule is released in the first machine step by a reaction of its weight; above it,
it stays in its cell."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from perga.case import load_case
from perga.engine import Simulation
from perga.model.compile import compile_case

CASE = Path(__file__).resolve().parents[2] / "cases" / "vertical-rotor.toml"
MASS = 0.00016  # kg: the case's granule
G = 9.80665  # m/s²: the case's gravity
CELL = (0.0, 0.17)  # m: above the axis, out of the hammers' reach (hinge 0.08 + plate 0.055)
MODELS = {
    "rigid": (),
    "soft": ('contact_model.kind="linear"', "contact_model.duration=1e-4"),
}
ENERGY = {"force law": (), "with energy": ("materials.beebread.detachment_energy=1e-3",)}


def _simulation(model: str, energy: str, bond: float) -> Simulation:
    sets = [
        "granules.count=1",
        f'granules.placement={{kind="comb", centre=[{CELL[0]}, {CELL[1]}], rows=1, columns=1, '
        "pitch=0.0054}",
        f"materials.beebread.detachment_force={bond!r}",
        *MODELS[model],
        *ENERGY[energy],
    ]
    return Simulation(compile_case(load_case(CASE, overrides=sets)))


@pytest.mark.parametrize("energy", ENERGY)
@pytest.mark.parametrize("model", MODELS)
def test_a_bond_weaker_than_the_weight_releases_the_granule_at_once(
    model: str, energy: str
) -> None:
    """A bond of 0.9·m·g: one release, at the end of the first machine step, by a reaction of
    the weight (1e-6: the rigid model's m|v|/dt of one step of gravity)."""
    sim = _simulation(model, energy, 0.9 * MASS * G)
    sim.run(20 * sim.dt)
    (release,) = sim.contacts.releases
    assert release.time == pytest.approx(sim.dt, rel=1e-9)
    assert release.force == pytest.approx(MASS * G, rel=1e-6)
    assert not sim.contacts.granule_state().held[0]


@pytest.mark.parametrize("energy", ENERGY)
@pytest.mark.parametrize("model", MODELS)
def test_a_bond_stronger_than_the_weight_holds_the_granule(model: str, energy: str) -> None:
    """A bond of 1.1·m·g: no release in 200 machine steps; the granule at rest in its cell."""
    sim = _simulation(model, energy, 1.1 * MASS * G)
    sim.run(200 * sim.dt)
    state = sim.contacts.granule_state()
    assert not sim.contacts.releases and state.held[0]
    assert math.dist(state.positions[0], CELL) < 1e-12
    assert max(abs(v) for v in state.velocities[0]) < 1e-9
