"""Coasting granules (``perga.contact.soft.coasting``) take a call's steps at once with the
same floats as step by step: every comparison here is bit for bit (``np.array_equal``), the
only tolerance an exact method has. Each scene is stepped twice from one state, with
``SoftGranules.coasting`` on and off, and each checks that granules did coast."""

import copy
import math
from pathlib import Path

import numpy as np
import pytest

from perga.case import load_case
from perga.contact.soft import SoftGranules, contact_parameters, uniform_table
from perga.contact.soft.granules import looks_for_coasting, pace_coasting
from perga.contact.soft.polygon_set import KINEMATIC, contact_table, polygon_set
from perga.engine import Simulation
from perga.model.compile import compile_case

from .helpers import MASS, RADIUS, chamber_gas
from .test_polygons import _box

ROOT = Path(__file__).resolve().parents[3]
STATE = ("x", "v", "w", "a_prev", "f", "tq", "hist", "wall_hist", "dissipated", "counts")


def _both(g: SoftGranules, calls: int, steps: int, **kwargs) -> tuple[SoftGranules, SoftGranules]:
    """g stepped ``calls`` calls of ``steps`` steps with coasting on, and a copy with it off."""
    on, off = copy.deepcopy(g), copy.deepcopy(g)
    off.coasting = False
    for _ in range(calls):
        on.step(steps, **kwargs)
        off.step(steps, **kwargs)
    return on, off


def _assert_same(on: SoftGranules, off: SoftGranules) -> None:
    for name in STATE:
        assert np.array_equal(getattr(on, name), getattr(off, name)), name
    assert on.n_rebuilds == off.n_rebuilds
    assert off.coasted == 0


@pytest.mark.parametrize("chunks", [1, 2])
@pytest.mark.parametrize("gravity", [(0.0, 0.0), (0.0, -9.81)])
def test_a_gas_coasts_to_the_floats_of_steps_one_by_one(gravity, chunks) -> None:
    """60 granules at about 7 m/s in a chamber, with friction, a wall and gravity or not: 40
    calls of 12 steps rebuild the neighbour list more often than once a call (so also within
    calls) and collide granules with each other and the wall, so the coasting granules are
    rewound (before rebuilds, new flags and after a granule outran the speed bound). Two
    chunks: the pair forces summed per chunk."""
    row = contact_parameters("linear", 0.6, k_n=1e4, friction=0.4)
    g = chamber_gas(60, 3, row, speed=5.0, chunks=chunks)
    g.gravity[:] = gravity
    on, off = _both(g, 40, 12)
    _assert_same(on, off)
    assert on.n_rebuilds > 40
    assert on.coasted > 0.3 * on.n * on.steps
    assert on.dissipated[0] > 0.0 and on.dissipated[1] > 0.0  # pairs and wall contacts


def test_a_pushed_row_rewinds_when_a_granule_outruns_the_bound() -> None:
    """Granules at rest in a row, 0.05 mm apart, the first two overlapping: at rest the speed
    bound is 0, so every other granule coasts, and the pushed pair outruns the bound in the
    first step. Each rewind must put the coasting granules back before the pair pass reaches
    them: the push travels down the row within a few calls."""
    n = 12
    r = np.full(n, RADIUS)
    x = np.zeros((n, 2))
    x[:, 0] = np.arange(n) * (2 * RADIUS + 5e-5)
    x[0, 0] = x[1, 0] - 1.8 * RADIUS
    row = contact_parameters("linear", 0.8, k_n=1e4)
    g = SoftGranules(x, r, np.full(n, MASS), uniform_table(row))
    on, off = _both(g, 30, 20)
    _assert_same(on, off)
    assert np.count_nonzero(np.hypot(*on.v.T) > 0.0) == n  # the push reached the row's end
    assert on.coasted > 0


def test_a_slow_row_coasts_beside_a_fast_granule_and_rewinds_when_pushed() -> None:
    """The pushed row above with a granule flying at 5 m/s far from it: the call's bound V is
    then 10 m/s, which would keep the whole row from coasting (a call moves a granule up to
    20·dt·V, far more than the row's 0.05 mm gaps). Each row granule's own bound, from its
    speed and its partners', lets the row coast, so the push must be caught by the row
    granules' own bounds (``coasting.outruns``), not by V."""
    n = 12
    r = np.full(n + 1, RADIUS)
    x = np.zeros((n + 1, 2))
    x[:n, 0] = np.arange(n) * (2 * RADIUS + 5e-5)
    x[0, 0] = x[1, 0] - 1.8 * RADIUS
    x[n] = (0.0, 50 * RADIUS)
    row = contact_parameters("linear", 0.8, k_n=1e4)
    g = SoftGranules(x, r, np.full(n + 1, MASS), uniform_table(row))
    g.v[n] = (5.0, 0.0)
    assert 20 * g.dt * 10.0 > 5e-5  # V alone would keep the row from coasting
    on, off = _both(g, 30, 20)
    _assert_same(on, off)
    assert np.count_nonzero(np.hypot(*on.v[:n].T) > 0.0) == n  # the push reached the row's end
    assert on.coasted > 2 * on.steps  # more than the flying granule alone


@pytest.mark.parametrize("mirrored", [False, True])
def test_a_granule_at_rest_keeps_clear_of_the_bound_of_its_partner(mirrored) -> None:
    """Three granules in a row: A at rest, B at rest 15 µm from it, C pressed 0.1 mm into B and
    moving onto it at 1 m/s. A's own bound is 0 (it and its partner B are at rest) and B's is
    2 m/s (its partner C): the pair A-B, farther apart than dt·V, is within a call's reach of
    B's bound, so A must not coast; B, pushed by C, reaches A within the first call. Mirrored:
    the row's order reversed, so that either granule of the pair may own it in the list."""
    gap, pressed = 1.5e-5, 1e-4
    x = np.array([[0.0, 0.0], [2 * RADIUS + gap, 0.0], [4 * RADIUS + gap - pressed, 0.0]])
    order = [2, 1, 0] if mirrored else [0, 1, 2]
    row = contact_parameters("linear", 0.8, k_n=1e4)
    g = SoftGranules(x[order], np.full(3, RADIUS), np.full(3, MASS), uniform_table(row))
    g.v[order.index(2)] = (-1.0, 0.0)
    assert 2 * 1.0 * g.dt < gap < 20 * g.dt * 2 * 1.0  # beyond dt·V, within 20 steps of B's bound
    on, off = _both(g, 5, 20)
    _assert_same(on, off)
    assert off.v[order.index(0), 0] < 0.0  # B reached A


def test_a_granule_a_hammer_can_strike_takes_the_calls_bound() -> None:
    """A kinematic box moving at 1 m/s pressed 0.1 mm into granule B at rest, granule A at rest
    20 µm beyond B, and a third granule flying at 2 m/s far away (V = 4 m/s). B is a polygon
    candidate, so its bound is V whatever its partners' speeds: the pair A-B is within a call's
    reach of it and A must not coast. Struck, B reaches A within the first call, slower than V,
    which the call's own check does not catch."""
    gap, pressed = 2e-5, 1e-4
    x = np.array([[0.0, 0.0], [2 * RADIUS + gap, 0.0], [0.0, 50 * RADIUS]])
    box = _box(0.01, 0.01, 3 * RADIUS + gap + 0.005 - pressed, 0.0)
    polys = polygon_set(
        [box], np.array([box.mean(axis=0)]), kind=[KINEMATIC], mass=[math.inf],
        inertia=[math.inf], velocity=np.array([[-1.0, 0.0]]),
    )  # fmt: skip
    row = contact_parameters("linear", 0.8, k_n=1e4)
    g = SoftGranules(
        x, np.full(3, RADIUS), np.full(3, MASS), uniform_table(row), polygons=polys,
        polygon_table=contact_table(1e4, 2e3, 0.8, 0.0),
    )  # fmt: skip
    g.v[2] = (2.0, 0.0)
    assert 4.0 * g.dt < gap < 20 * g.dt * 4.0  # beyond dt·V, within 20 steps of V
    on, off = _both(g, 5, 20)
    _assert_same(on, off)
    assert off.v[0, 0] < 0.0  # B reached A
    assert on.coasted > 0  # the far granule


def test_a_granule_falling_onto_a_held_one_meets_it_within_a_call() -> None:
    """Two granules at rest, the lower held by a bond, the upper 10 µm above it under a gravity
    that makes it fall 50 µm in a call of 10 steps: at rest the speed bound is gravity's part
    alone, which must keep the upper one from coasting through the contact. A third granule,
    far from both, coasts."""
    row = contact_parameters("linear", 0.8, k_n=1e4)
    gap = 1e-5
    g = SoftGranules(
        [[0.0, 0.0], [0.0, 2 * RADIUS + gap], [20 * RADIUS, 0.0]], [RADIUS] * 3, [MASS] * 3,
        uniform_table(row), held=[True, False, False], bond_force=[np.inf, 0.0, 0.0],
    )  # fmt: skip
    g.gravity[:] = (0.0, -2 * 5 * gap / (10 * g.dt) ** 2)  # ½ g (10 dt)² = 5 gaps
    on, off = _both(g, 3, 10)
    _assert_same(on, off)
    assert off.dissipated[0] > 0.0  # they met
    assert 0 < on.coasted <= on.steps  # the far granule alone


def test_relax_coasts_to_the_same_floats() -> None:
    """``relax``: a finite speed cap and a drag in every step."""
    row = contact_parameters("linear", 0.6, k_n=1e4, friction=0.4)
    g = chamber_gas(40, 8, row, overlapping=True)
    on, off = copy.deepcopy(g), copy.deepcopy(g)
    off.coasting = False
    assert on.relax(block=20) == off.relax(block=20)
    _assert_same(on, off)
    assert on.coasted > 0


def test_the_soft_separator_coasts_to_the_same_frames() -> None:
    """The bundled soft separator (300 granules, hammers as polygons, the chamber wall, floor
    friction and hinge friction), 600 machine steps from rest."""
    case = load_case(ROOT / "cases/soft-separator.toml", ["solver.threads=1"])
    on, off = (Simulation(compile_case(case), track_energy=True) for _ in range(2))
    off.contacts.granules.coasting = False
    for _ in range(600):
        on.step()
        off.step()
    for name in ("x", "v", "w", "f", "polygon_hist"):
        assert np.array_equal(
            getattr(on.contacts.granules, name), getattr(off.contacts.granules, name)
        ), name
    a, b = on.frame().machine, off.frame().machine
    assert np.array_equal(a.swing_angles, b.swing_angles)
    assert len(on.impacts) == len(off.impacts)
    granules = on.contacts.granules
    assert granules.coasted > 0.3 * granules.n * granules.steps


@pytest.mark.parametrize(("share", "waits"), [(0.1, 0), (0.0999, 1)], ids=["a tenth", "less"])
def test_looking_for_coasting_granules_pauses_where_few_coast(share, waits) -> None:
    """A call in which fewer than a tenth of the granule steps coasted pauses the search for
    1, then 2, 4, … calls; a tenth or more keeps it on."""
    row = contact_parameters("linear", 0.6, k_n=1e4)
    g = chamber_gas(10, 1, row)
    pace_coasting(g.coast_pacing, True, round(share * 10 * 10_000), g.n, 10_000)
    assert g.coast_pacing[0] == waits
    pace_coasting(g.coast_pacing, True, 0, g.n, 10_000)
    assert g.coast_pacing[0] == (2 if waits else 1)


@pytest.mark.parametrize(
    ("coasting", "waits", "n_steps", "looks"),
    [(True, 0, 2, True), (True, 1, 2, False), (True, 0, 1, False), (False, 0, 2, False)],
    ids=["on", "paused", "one step", "off"],
)
def test_a_call_looks_for_coasting_granules_only_when_on_unpaused_and_longer_than_a_step(
    coasting, waits, n_steps, looks
) -> None:
    """The rule both the Python step and the compiled steps ask (``looks_for_coasting``)."""
    pacing = np.array([waits, 1], dtype=np.int64)
    assert looks_for_coasting(coasting, pacing, n_steps) is looks
