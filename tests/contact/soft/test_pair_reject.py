"""The pair pass skips a listed pair that cannot touch within the step only while it holds no
tangential spring (``kernel._pair_range``): a spring torn apart in one step is still dropped and
its energy booked as dissipated."""

import numpy as np
import pytest

from perga.contact.soft import SoftGranules, contact_parameters, uniform_table
from perga.contact.soft.kernel import DISSIPATED_PAIRS
from perga.contact.soft.laws import P_KT

RADIUS = 2e-3  # m
MASS = 1e-4  # kg
OVERLAP = 1e-5  # m at the start
SHEAR = 0.5  # m/s each disc, opposite ways along the tangent: loads the spring
PULL = 50.0  # m/s each disc, apart along the normal: far apart after one step


def _sheared_pair() -> SoftGranules:
    """Two discs overlapping by OVERLAP and sheared against each other for three steps (their
    tangential spring loaded), then pulled apart at ±PULL. The law lets the normal force turn
    attractive (end="overlap"), so the Coulomb cap stays open and the spring loaded while the
    discs part: a clamped force would drop it at the pull's first step."""
    row = contact_parameters("linear", 0.7, k_n=1e6, friction=0.5, end="overlap")
    g = SoftGranules(
        [[0.0, 0.0], [2.0 * RADIUS - OVERLAP, 0.0]], [RADIUS, RADIUS], [MASS, MASS],
        uniform_table(row), v=[[0.0, SHEAR], [0.0, -SHEAR]],
    )  # fmt: skip
    g.step(3)
    g.v[:] = [[-PULL, 0.0], [PULL, 0.0]]
    return g


def test_a_spring_torn_apart_in_one_step_is_released_and_booked() -> None:
    """Step 1 after the pull still overlaps (the contact acts, the spring stays loaded); the discs
    then move 2·PULL·dt apart, more than the reach PULL·dt beyond touching, so step 2 finds
    the pair far: its spring must be dropped and ½ k_t ξ² (linear law) added to the pairs'
    dissipation. Relative tolerance 1e-12: the kernel's product may associate differently."""
    g = _sheared_pair()
    assert g.nbr.tolist() == [1], "the pair must stay listed (no rebuild drops it)"
    g.step(1)
    xi = g.hist[0]
    assert xi != 0.0, "the sheared contact must hold a spring before it is torn apart"
    gap = np.hypot(*(g.x[1] - g.x[0])) - 2.0 * RADIUS
    assert gap > g.dt * PULL, "the pair must be beyond the reach after the pull's first step"
    before = g.dissipated[DISSIPATED_PAIRS]
    g.step(1)
    assert g.hist[0] == 0.0
    kt = g.params[0, 0, P_KT]
    assert g.dissipated[DISSIPATED_PAIRS] - before == pytest.approx(0.5 * kt * xi**2, rel=1e-12)
    assert np.all(g.f == 0.0)
