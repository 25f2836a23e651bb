"""Contact values on the shapes: the factorised pair table reproduces every pair, and a table
that cannot be split keeps its exact values through the per-contact setter."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from tests.engine.helpers import plate

from perga.contact.rigid.bodies import factor_pair_table
from perga.engine import Simulation
from perga.model import ContactSpec, GranuleSpec, RotorSpec, System

ULP4 = 4 * 2.2e-16  # the factorisation promises the pair value to 4 ulp (two roundings + slack)

values = st.floats(min_value=1e-3, max_value=2.0)


@settings(max_examples=300, deadline=None)
@given(gg=values, gh=values, gw=values)
def test_one_granule_material_always_splits(gg, gh, gw):
    table = {
        frozenset(("bb",)): gg,
        frozenset(("bb", "steel")): gh,
        frozenset(("bb", "glass")): gw,
    }
    factors, unsplit = factor_pair_table(table)
    assert unsplit == set()
    for pair, value in table.items():
        a, b = sorted(pair)[0], sorted(pair)[-1]
        assert math.isclose(factors[a] * factors[b], value, rel_tol=ULP4)


def test_inconsistent_table_is_reported_unsplit():
    # two granule materials colliding with each other and one wall: 4 pairs, 3 factors
    table = {
        frozenset(("a",)): 0.5,
        frozenset(("b",)): 0.5,
        frozenset(("a", "b")): 0.9,
        frozenset(("a", "steel")): 0.7,
        frozenset(("b", "steel")): 0.7,
    }
    factors, unsplit = factor_pair_table(table)
    assert unsplit  # 5 pairs, 3 factors, no exact solution
    for pair in set(table) - unsplit:
        a, b = sorted(pair)[0], sorted(pair)[-1]
        assert math.isclose(factors[a] * factors[b], table[pair], rel_tol=ULP4)


def test_unsplit_pair_still_gets_its_exact_restitution():
    # the table above cannot be split; two b granules meet head on, an a granule waits apart
    v = 2.0
    granules = (
        GranuleSpec((-0.01, 0.3), (v, 0.0), 0.002, 1e-4, "b"),
        GranuleSpec((0.01, 0.3), (-v, 0.0), 0.002, 1e-4, "b"),
        GranuleSpec((0.2, -0.3), (0.0, 0.0), 0.002, 1e-4, "a"),
    )
    contacts = (
        ContactSpec("a", "a", 0.5, 0.0),
        ContactSpec("b", "b", 0.5, 0.0),
        ContactSpec("a", "b", 0.9, 0.0),
        ContactSpec("a", "steel", 0.7, 0.0),
        ContactSpec("b", "steel", 0.7, 0.0),
    )
    hammer = plate(
        0.0,
        0.02,
        -0.005,
        0.005,
        0.01,
        hinge_radius=0.05,
        angle_on_rotor=0.0,
        mount="welded",
        material="steel",
    )
    spec = System(
        RotorSpec(1e-6, 0.05),
        (hammer,),
        granules,
        contacts,
        granule_dt=1e-5,
        granule_collisions=True,
    )
    sim = Simulation(spec)
    sim.run(0.01)
    _, unsplit = factor_pair_table({c.key: c.restitution for c in contacts})
    assert frozenset(("b",)) in unsplit  # this pair really goes through the setter
    after = sim.frame().granules.velocities[:2, 0]
    # equal masses, head on: each leaves at e_bb·v (exact impulse law, 1e-12 for round-off),
    # not at the product of shape values
    assert after == pytest.approx([-0.5 * v, 0.5 * v], rel=1e-12)
