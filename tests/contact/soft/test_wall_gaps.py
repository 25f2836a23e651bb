"""The kernel skips the walls of a granule that cannot reach one (``kernel.wall_gaps``).

Skipping is exact: a skipped granule's wall force would have been zero and its springs empty. So
the rule is checked against closed-form gaps, and a strike that one long call makes from far
beyond the skin (its walls skipped at first, by the gap at the list's build) must give the
same floats, bit for bit, as the same strike taken one step a call.
"""

import math

import numpy as np
import pytest

from perga.contact.soft import SoftGranules, chamber, contact_parameters, plane, uniform_table
from perga.contact.soft.kernel import WALL_PLANE, wall_gaps

R = 2e-3
MASS = 1e-4
R_CHAMBER = 0.05


def test_gaps_are_the_distance_to_the_nearest_wall_less_the_radius() -> None:
    """Closed form: chamber R − |x − c| − r, plane (x − p)·n − r, the smaller of them, stored
    1e-9 r short; −inf for a granule whose wall spring is loaded. Tolerance 1e-15 m: the same
    arithmetic in another order, on positions of 0.05 m."""
    rows = np.array([chamber(R_CHAMBER, (0.01, 0.0)), plane((0.0, -0.02), (0.0, 1.0))])
    x = np.array([[0.01, 0.0], [0.05, 0.0], [0.0, -0.015], [0.0, 0.0]])
    r = np.array([R, R, R, 0.5 * R])
    hist = np.zeros((4, 2))
    hist[3, 1] = 1e-7
    gap = np.empty(4)
    wall_gaps(x, r, rows, hist, gap)
    expected = [
        min(R_CHAMBER - 0.0 - R, 0.02 - R),
        min(R_CHAMBER - 0.04 - R, 0.02 - R),
        min(R_CHAMBER - math.hypot(0.01, 0.015) - R, 0.005 - R),
    ]
    assert gap[:3] == pytest.approx(np.array(expected) - 1e-9 * r[:3], abs=1e-15)
    assert gap[3] == -math.inf


def strike(wall: np.ndarray, x0, v0, calls: int, skin: float) -> SoftGranules:
    """A frictional granule flying at wall from x0 with velocity v0 (m/s, spinning), 24,000 steps
    taken in ``calls`` equal calls, with the given skin (m)."""
    row = contact_parameters("linear", 0.7, k_n=1e6, friction=0.3)
    g = SoftGranules(
        [x0], [R], [MASS], uniform_table(row), v=[v0], w=[50.0], walls=[wall], v_max=5.0, skin=skin
    )
    for _ in range(calls):
        g.step(24_000 // calls)
    return g


@pytest.mark.parametrize(
    ("wall", "x0", "v0"),
    [
        (plane((0.0, 0.0), (0.0, 1.0)), (0.0, 12 * R), (0.4, -2.0)),
        (chamber(R_CHAMBER), (0.0, R_CHAMBER - 13 * R), (-0.5, 2.0)),
    ],
    ids=["plane", "chamber"],
)
def test_a_strike_from_beyond_the_skin_in_one_call_is_the_strike_step_by_step(wall, x0, v0) -> None:
    """One call whose list is never rebuilt (skin 1 m): the walls are skipped while the granule
    is far and must be evaluated by the time it arrives, from its displacement since the build.
    Against 24,000 calls of one step with the default skin: equal floats (the kernel is
    deterministic, and a single granule's steps do not depend on its list). The granule must
    have struck (its normal velocity reversed) and slipped (friction engaged its spring)."""
    one = strike(wall, x0, v0, calls=1, skin=1.0)
    assert one.n_rebuilds == 1
    steps = strike(wall, x0, v0, calls=24_000, skin=None)
    assert np.array_equal(one.x, steps.x)
    assert np.array_equal(one.v, steps.v)
    assert np.array_equal(one.w, steps.w)
    normal = wall[3:5] if wall[0] == WALL_PLANE else -one.x[0] / np.linalg.norm(one.x[0])
    assert float(one.v[0] @ normal) > 0.0
    assert one.w[0] != 50.0


def _fall(gap: float, calls: int) -> SoftGranules:
    """A granule at rest with its edge ``gap`` skins above a plane, under a gravity that makes
    it fall 0.3 skin in its first step; three steps in ``calls`` equal calls."""
    row = contact_parameters("linear", 0.7, k_n=1e6, friction=0.3)
    floor = plane((0.0, 0.0), (0.0, 1.0))
    probe = SoftGranules([[0.0, 0.0]], [R], [MASS], uniform_table(row), walls=[floor], v_max=5.0)
    g = SoftGranules(
        [[0.0, R + gap * probe.skin]], [R], [MASS], uniform_table(row), walls=[floor],
        v_max=5.0, gravity=(0.0, -0.3 * probe.skin / probe.dt**2), skin=probe.skin,
    )  # fmt: skip
    for _ in range(calls):
        g.step(3 // calls)
    return g


def test_a_granule_the_call_did_not_flag_gets_its_walls_once_the_reach_outgrows_them() -> None:
    """The per-granule pass takes a granule's walls only if ``mark_special`` flagged it: at a
    call's first step those within ``SPECIAL_MARGIN`` skins of the reach then. Here the reach
    outgrows that within the call: the granule starts at rest 0.51 skin above the plane (not
    flagged) and falls 0.3 skin in the first step and 0.6 in the second (about 1,000 m/s: far
    beyond anything physical, the only way past the margin before the list is rebuilt). The
    set must be flagged again, so that the plane acts in the second step: one call of three
    steps equals three calls of one step (each flags afresh) bit for bit, and the plane has
    slowed the fall (free fall would be 3 g dt after three steps)."""
    one = _fall(0.51, calls=1)
    steps = _fall(0.51, calls=3)
    assert np.array_equal(one.x, steps.x)
    assert np.array_equal(one.v, steps.v)
    assert one.n_rebuilds == 2  # the list is rebuilt only before the third step
    free = -3 * 0.3 * one.skin / one.dt  # 3 g dt
    assert one.v[0, 1] > free * (1 + 1e-12)  # slower than free fall (1e-12: its kicks' rounding)
