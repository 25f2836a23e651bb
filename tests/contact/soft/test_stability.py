"""Closed passive systems lose energy; dense overlapping packings are released gently; the
neighbour list (rebuilds, history carry-over) and the thread count do not change the physics."""

import math

import numpy as np
import pytest

from perga.contact.soft import (
    SoftGranules,
    chamber,
    contact_duration,
    contact_parameters,
    uniform_table,
)

from .helpers import MASS, R_CHAMBER, RADIUS, chamber_gas
from .marks import TWO_THREADS


def _chamber_gas(n, seed, *, overlapping=False, e=0.7, friction=0.5, rolling=0.0, speed=1.0):
    """``helpers.chamber_gas`` with a linear contact (k_n = 1e6 N/m) of e, friction, rolling."""
    row = contact_parameters("linear", e, k_n=1e6, friction=friction, rolling=rolling)
    return chamber_gas(n, seed, row, speed=speed, overlapping=overlapping)


@pytest.mark.parametrize("rolling", [0.0, 0.1])
def test_energy_never_rises_in_a_closed_passive_system(rolling):
    """Granules in the chamber, e = 0.7, f = 0.5, no gravity, 2,000 steps.

    E = kinetic + elastic (normal and tangential springs), sampled every step. Symplectic Euler
    conserves a shadow energy, not E itself: within an elastic, frictionless contact E wobbles by
    O((ω dt)²) ≈ 0.4 % of the contact's energy at t_c/50 and comes back. Tolerance: no sample
    exceeds any earlier one by more than 1e-3 of E(0), and E falls overall.
    """
    g = _chamber_gas(150, 1, rolling=rolling, speed=3.0)
    energies = [g.energy()]
    for _ in range(2000):
        g.step(1)
        energies.append(g.energy())
    e = np.array(energies)
    running_max = np.maximum.accumulate(e)
    assert np.all(e <= running_max[np.r_[0, np.arange(len(e) - 1)]] + 1e-3 * e[0])
    assert e[-1] < 0.9 * e[0]
    assert np.all(np.isfinite(g.x))


def test_dense_overlapping_packing_released_gently():
    """300 granules dropped at random positions (overlaps up to ~whole radii) in the chamber.

    Released directly, the stored elastic energy flings them out at tens of m/s (design §5
    reports 485 m/s). ``relax`` (global drag ≈ ω_n plus a speed cap of 5 % of a radius per
    contact duration) removes the overlaps first; released afterwards, with e = 0.7 and no drag,
    no granule exceeds 0.05 m/s over 2,000 steps and none leaves the chamber.
    """
    raw = _chamber_gas(300, 2, overlapping=True, speed=0.0)
    assert raw.max_overlap() > 0.5 * RADIUS
    wild = _chamber_gas(300, 2, overlapping=True, speed=0.0)
    wild.step(500)
    wild_speed = np.max(np.hypot(*wild.v.T))
    assert wild_speed > 5.0

    g = _chamber_gas(300, 2, overlapping=True, speed=0.0)
    steps = g.relax(v_release=0.01)
    assert steps < 50_000
    assert g.max_overlap() < 1e-3 * RADIUS
    g.step(2000)
    speed = np.max(np.hypot(*g.v.T))
    assert speed < 0.05
    assert np.all(np.hypot(*g.x.T) + g.r < R_CHAMBER + 1e-3 * RADIUS)


def test_tangential_history_survives_rebuilds():
    """Same gas with a default skin (few builds) and a tiny skin (a rebuild every step).

    Both runs see the same contacts with the same springs if the history is carried over;
    only the summation order differs (round-off, ~1e-16 relative, grown over 300 steps of a
    chaotic gas to < 1e-12 m).
    """
    a = _chamber_gas(200, 5, speed=3.0)
    b = _chamber_gas(200, 5, speed=3.0)
    b.skin = 1e-9
    sticking = 0
    for _ in range(30):
        a.step(10)
        b.step(10)
        sticking += int(np.count_nonzero(a.hist))
    assert sticking > 0
    assert b.n_rebuilds >= 300 > 10 * a.n_rebuilds
    np.testing.assert_allclose(b.x, a.x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(b.w, a.w, rtol=1e-9, atol=1e-9)


@TWO_THREADS
def test_the_chunks_fix_the_results_whatever_the_threads():
    """A dense gas (overlapping start, many contacts a granule) in two chunks gives the same
    bits on one thread (chunk after chunk, no parallel region) and on two; in one chunk it
    differs only by round-off (each granule's pair forces summed in another order)."""
    row = contact_parameters("linear", 0.7, k_n=1e6, friction=0.5)
    runs = {}
    for chunks, threads in ((2, 1), (2, 2), (1, 1)):
        g = chamber_gas(300, 3, row, speed=3.0, overlapping=True, chunks=chunks)
        g.set_threads(threads)
        g.step(300)
        runs[chunks, threads] = (g.x, g.v, g.w, g.dissipated)
    for a, b in zip(runs[2, 1], runs[2, 2], strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.array_equal(runs[1, 1][1], runs[2, 1][1])  # the chunks do change the sums
    np.testing.assert_allclose(runs[1, 1][0], runs[2, 1][0], rtol=0, atol=1e-10)


def test_default_step_is_fiftieth_of_shortest_contact():
    """dt = t_c/50 of the lightest pair (m_eff = m_min/2 is below the wall's m_min)."""
    g = _chamber_gas(20, 4)
    m_min, r_min = g.m.min(), g.r.min()
    t_c = contact_duration(g.params[0, 0], 0.5 * m_min, 0.5 * r_min, 0.0)
    assert g.t_c == pytest.approx(t_c, rel=1e-12)
    assert g.dt == pytest.approx(g.t_c / 50.0, rel=1e-12)


@pytest.mark.parametrize(
    ("x", "walls", "pairs", "dt", "refused"),
    [([[0.0, 0.0]], [], True, None, True), ([[0.0, 0.0]], [], True, 1e-6, False),
     ([[0.0, 0.0]], [chamber(R_CHAMBER)], True, None, False),
     ([[-0.01, 0.0], [0.01, 0.0]], [], False, None, True),
     ([[-0.01, 0.0], [0.01, 0.0]], [], True, None, False)],
)  # fmt: skip
def test_a_default_step_needs_a_contact_that_can_form(x, walls, pairs, dt, refused):
    """The default step comes from the shortest contact duration: where no contact can form
    (one granule, or pairs off, with no wall) it does not exist, and the system without dt is
    refused naming what to give; with dt, a wall or a second granule it is made."""
    n = len(x)

    def make() -> SoftGranules:
        table = uniform_table(contact_parameters("linear", 0.7, k_n=1e6))
        return SoftGranules(x, [RADIUS] * n, [MASS] * n, table, walls=walls, pairs=pairs, dt=dt)

    if refused:
        with pytest.raises(ValueError, match=r"no contact can form.*give dt"):
            make()
        return
    g = make()
    assert math.isfinite(g.dt) and g.dt > 0.0
    g.step(3)
    assert np.isfinite(g.x).all()


def test_without_pairs_granules_pass_through_each_other():
    """pairs=False (a scene without granule collisions): no pair force, no pair list; the walls
    still act."""
    row = contact_parameters("linear", 0.7, k_n=1e6, friction=0.5)
    g = SoftGranules(
        [[-0.01, 0.0], [0.01, 0.0]],
        [RADIUS, RADIUS],
        [MASS, MASS],
        uniform_table(row),
        v=[[1.0, 0.0], [-1.0, 0.0]],
        walls=[chamber(R_CHAMBER)],
        pairs=False,
    )
    n = round(0.02 / g.dt)  # about 20 mm each: they cross at t = 10 ms
    g.step(n)
    travel = n * g.dt
    assert g.x[:, 0] == pytest.approx([-0.01 + travel, 0.01 - travel], abs=1e-12)
    assert g.v[:, 0] == pytest.approx([1.0, -1.0], abs=0)
    assert g.nbr.size == 0 and g.dissipated[0] == 0.0
    assert g.contact_energy() == 0.0
