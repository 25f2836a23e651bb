"""``SoftGranules.contact_counts``: contacts per granule and their largest overlap, against a
brute-force NumPy count on a small scene (pairs, a round chamber, a plane, two polygons)."""

import math

import numpy as np
import pytest

from perga.contact.soft import SoftGranules, chamber, contact_parameters, plane, uniform_table
from perga.contact.soft.polygon_set import (
    FREE,
    HIST_ACTIVE,
    KINEMATIC,
    contact_table,
    polygon_set,
)

from .test_polygons import _box

R = 2e-3  # m
MASS = 1e-4  # kg
R_CHAMBER = 0.05  # m
FLOOR = -0.03  # m: plane y = FLOOR, normal +y
BOX = _box(0.02, 0.01)  # kinematic, centred at the origin
SQUARE = _box(0.008, 0.008, -0.03, 0.02)  # free, heavy

# Granule centres (m) and what each touches by construction (overlaps in m).
CENTRES = [
    (0.0, 0.005 + R - 2e-4),  # box top face, 2e-4
    (0.01 + 0.0012, 0.005 + 0.0012),  # box corner (0.01, 0.005), R - 0.0012√2
    (0.02, 0.02),  # the next two, 1e-4 and 2e-4
    (0.02 + 2 * R - 1e-4, 0.02),
    (0.02, 0.02 + 2 * R - 2e-4),
    (-0.02, FLOOR + R - 1e-4),  # floor, 1e-4
    (R_CHAMBER - R + 1e-4, 0.0),  # chamber, 1e-4
    (0.0, -0.005 - R - 5e-4),  # 0.5 mm below the box: no contact
    (-0.01 - R + 5e-4, 0.0),  # box left face, 5e-4, and the next granule, 1e-4
    (-0.01 - 3 * R + 6e-4, 0.0),
    (-0.026 + R - 2e-4, 0.02),  # square's right face, 2e-4
    (0.03, -0.02),  # nothing
]


def _scene(pairs: bool = True) -> SoftGranules:
    """The granules at rest around the two polygons, no gravity; dt = 1e-8 s (t_c/6000), so
    that a step moves them by ~1e-11 m only."""
    x = np.array(CENTRES)
    n = len(x)
    polys = polygon_set(
        [BOX, SQUARE],
        np.array([[0.0, 0.0], [-0.03, 0.02]]),
        kind=[KINEMATIC, FREE],
        mass=[math.inf, 1.0],
        inertia=[math.inf, 1e-2],
    )
    row = contact_parameters("linear", 0.7, k_n=1e5, friction=0.5)
    return SoftGranules(
        x, np.full(n, R), np.full(n, MASS), uniform_table(row),
        walls=[chamber(R_CHAMBER), plane((0.0, FLOOR), (0.0, 1.0))],
        polygons=polys, polygon_table=contact_table(1e5, 2e4, 0.7, 0.5), pairs=pairs, dt=1e-8,
    )  # fmt: skip


def _signed_distance(p: np.ndarray, polygon: np.ndarray) -> float:
    """Signed distance of p from a convex counter-clockwise polygon, m (< 0 inside)."""
    a = polygon
    b = np.roll(polygon, -1, axis=0)
    e = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, e) / np.einsum("ij,ij->i", e, e), 0.0, 1.0)
    distance = np.hypot(*(a + t[:, None] * e - p).T).min()
    outward = np.column_stack([e[:, 1], -e[:, 0]]) / np.hypot(*e.T)[:, None]
    inside = np.all(np.einsum("ij,ij->i", p - a, outward) <= 0.0)
    return -distance if inside else distance


def _brute_force(g: SoftGranules, polygons: list[np.ndarray], pairs: bool = True):
    """Contacts per granule and largest overlap, every pair and wall checked directly."""
    n = g.n
    count = np.zeros(n, np.int64)
    overlap = np.zeros(n)

    def add(i, delta):
        count[i] += 1
        overlap[i] = max(overlap[i], delta)

    for i in range(n):
        for j in range(i + 1, n if pairs else 0):
            delta = g.r[i] + g.r[j] - np.hypot(*(g.x[i] - g.x[j]))
            if delta > 0.0:
                add(i, delta)
                add(j, delta)
        chamber_delta = g.r[i] + np.hypot(*g.x[i]) - R_CHAMBER
        floor_delta = g.r[i] - (g.x[i, 1] - FLOOR)
        for delta in (chamber_delta, floor_delta):
            if delta > 0.0:
                add(i, delta)
        for k, polygon in enumerate(polygons):
            if g.polygon_hist[i, k, HIST_ACTIVE] != 0.0:
                add(i, g.r[i] - _signed_distance(g.x[i], polygon))
    return count, overlap


@pytest.mark.parametrize("pairs", [True, False])
def test_contact_counts_match_a_brute_force_count(pairs):
    """Counts exact, overlaps to round-off, after one step (polygon contacts active)."""
    g = _scene(pairs)
    g.step(1)
    counts, overlaps = g.contact_counts()
    assert counts.dtype == np.int32 and overlaps.dtype == np.float64
    assert counts.shape == overlaps.shape == (g.n,)
    polygons = [g.polygons.vertices[:4], g.polygons.vertices[4:]]
    expected_counts, expected_overlaps = _brute_force(g, polygons, pairs)
    np.testing.assert_array_equal(counts, expected_counts)
    np.testing.assert_allclose(overlaps, expected_overlaps, rtol=1e-12, atol=1e-15)
    # The scene's contacts as built.
    active = g.polygon_hist[:, :, HIST_ACTIVE] != 0.0
    assert sorted(map(tuple, np.argwhere(active))) == [(0, 0), (1, 0), (8, 0), (10, 1)]
    built = [1, 1, 2, 1, 1, 1, 1, 0, 2, 1, 1, 0] if pairs else [1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 0]
    np.testing.assert_array_equal(counts, built)
    corner = R - 0.0012 * math.sqrt(2.0)
    by_hand = [2e-4, corner, 2e-4, 1e-4, 2e-4, 1e-4, 1e-4, 0.0, 5e-4, 1e-4, 2e-4, 0.0]
    if not pairs:
        by_hand[2:5] = [0.0, 0.0, 0.0]
        by_hand[9] = 0.0
    np.testing.assert_allclose(overlaps, by_hand, rtol=1e-5, atol=1e-12)


def test_contact_counts_without_contacts_or_polygons():
    """Granules apart in an empty chamber: zero counts and overlaps."""
    row = contact_parameters("linear", 0.7, k_n=1e5)
    g = SoftGranules(
        [[0.0, 0.0], [0.01, 0.0]], [R, R], [MASS, MASS], uniform_table(row),
        walls=[chamber(R_CHAMBER)],
    )  # fmt: skip
    counts, overlaps = g.contact_counts()
    np.testing.assert_array_equal(counts, [0, 0])
    np.testing.assert_array_equal(overlaps, [0.0, 0.0])


def test_overlapping_pairs_and_wall_overlaps_equal_numpy_bit_for_bit():
    """The compiled scans give the floats of the NumPy expressions they replace (the ledger's
    spring energy reads them: same bits, same tables) on a packed bed after 20 steps, with
    and without the pairs that only hold a spring (a few list entries apart given one)."""
    rng = np.random.default_rng(3)
    x = rng.uniform(-0.02, 0.02, (400, 2))
    row = contact_parameters("linear", 0.7, k_n=1e5, friction=0.5)
    g = SoftGranules(
        x, np.full(400, R), np.full(400, MASS), uniform_table(row),
        walls=[chamber(0.021), plane((0.0, -0.019), (0.3, 1.0))], dt=1e-7,
    )  # fmt: skip
    g.step(20)
    i_all = np.repeat(np.arange(g.n), np.diff(g.start))
    d = np.linalg.norm(g.x[i_all] - g.x[g.nbr], axis=1)
    delta_all = g.r[i_all] + g.r[g.nbr] - d
    g.hist[np.flatnonzero(delta_all <= 0)[::50]] = 1e-9
    for springs in (False, True):
        k = np.flatnonzero((delta_all > 0) | (springs & (g.hist != 0)))
        i, j, delta, entries = g._pairs(springs=springs)
        np.testing.assert_array_equal(entries, k)
        np.testing.assert_array_equal(i, i_all[k])
        np.testing.assert_array_equal(j, g.nbr[k])
        assert delta.tobytes() == delta_all[k].tobytes()
    assert 0 < len(g._pairs()[0]) < len(g._pairs(springs=True)[0])
    walls = g._walls_overlap()
    assert walls[:, 0].tobytes() == (g.r + np.hypot(g.x[:, 0], g.x[:, 1]) - 0.021).tobytes()
    c, s = g.walls[1, 3], g.walls[1, 4]
    assert walls[:, 1].tobytes() == (g.r - (g.x[:, 0] * c + (g.x[:, 1] + 0.019) * s)).tobytes()
    assert (walls > 0).sum(axis=0).min() > 0
