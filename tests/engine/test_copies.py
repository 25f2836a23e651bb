"""A simulation copied (``copy.deepcopy``) or pickled and read back steps as the original. The
machine carries Chipmunk's state that pymunk's pickle misses (``Machine.__getstate__``,
``perga.machine.chipmunk_state``): without it a hinged hammer comes back displaced and its
joints start cold (the soft separator's copied granules were up to 0.27 m from the original's
3,000 steps later)."""

from __future__ import annotations

import copy
import pickle
from pathlib import Path

import numpy as np
import pytest

from perga.case import load_case
from perga.engine.simulation import Simulation
from perga.machine.chipmunk_state import capture
from perga.model.compile import compile_case

CASES = Path(__file__).resolve().parents[2] / "cases"
COPIES = {
    "deepcopy": copy.deepcopy,
    "pickle": lambda sim: pickle.loads(pickle.dumps(sim)),
}


def stepped(case: str, seconds: float) -> Simulation:
    sim = Simulation(compile_case(load_case(CASES / case)))
    sim.run(seconds)
    return sim


def state(sim: Simulation) -> list[np.ndarray]:
    """What the copies are compared on: the granules' positions, velocities and spins, the
    machine's raw Chipmunk state (bodies, and joints' accumulated impulses)."""
    chipmunk = capture(sim.machine.space)
    return [
        sim.frame().granules.positions,
        sim.frame().granules.velocities,
        sim.frame().granules.angular_velocities,
        chipmunk.bodies,
        chipmunk.joints,
    ]


@pytest.mark.parametrize("how", COPIES)
def test_a_copied_soft_separator_steps_as_the_original_bit_for_bit(how: str) -> None:
    """The soft separator (300 granules, hinged hammers, floor friction) copied at 0.11 s,
    just before the first impacts, both run 0.02 s more: every array and impact equal. A soft
    run's round trip is exact (the granules are arrays; Chipmunk has no granule contacts to
    re-order)."""
    sim = stepped("soft-separator.toml", 0.11)
    twin = COPIES[how](sim)
    sim.run(0.02)
    twin.run(0.02)
    for a, b in zip(state(sim), state(twin), strict=True):
        assert np.array_equal(a, b)
    assert repr(sim.impacts) == repr(twin.impacts)  # floats' repr is exact; nan equals nan
    assert len(sim.impacts) > 0


@pytest.mark.parametrize("how", COPIES)
def test_a_copied_rigid_separator_starts_from_the_same_state(how: str) -> None:
    """The rigid separator copied at 0.03 s: its granules and machine bit for bit the
    original's. (Its later steps may differ at round-off: Chipmunk's broad phase is rebuilt,
    and with it the order the solver takes the contacts in; ``perga.run.checkpoints``.)"""
    sim = stepped("separator.toml", 0.03)
    for a, b in zip(state(sim), state(COPIES[how](sim)), strict=True):
        assert np.array_equal(a, b)
