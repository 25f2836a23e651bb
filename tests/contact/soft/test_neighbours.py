"""The Verlet half list (``perga.contact.soft.neighbours.build``) against a brute-force search:
its pairs, the order of each row, and the tangential history it carries over."""

import numpy as np
import pytest

from perga.contact.soft.neighbours import _ROW_CAP, _cells, build, empty_list

SKIN = 0.4e-3  # m
BIG = 5  # the granule with a long row


def _granules() -> tuple[np.ndarray, np.ndarray]:
    """400 granules of radius 0.5-1.5 mm strewn over a 60 mm square, and one of 5 mm among
    them ringed by 30 of 0.5 mm: granule BIG, with more neighbours j > BIG than a scratch row
    holds (``_ROW_CAP``), its row not the first."""
    rng = np.random.default_rng(3)
    x = rng.uniform(0.0, 0.06, (400, 2))
    r = rng.uniform(0.5e-3, 1.5e-3, 400)
    ring = np.linspace(0.0, 2.0 * np.pi, 30, endpoint=False)
    x[BIG + 1 : BIG + 31] = 0.03 + 5.6e-3 * np.column_stack([np.cos(ring), np.sin(ring)])
    r[BIG + 1 : BIG + 31] = 0.5e-3
    x[BIG], r[BIG] = (0.03, 0.03), 5e-3
    return x, r


def _rows(start: np.ndarray, nbr: np.ndarray) -> list[list[int]]:
    return [nbr[start[i] : start[i + 1]].tolist() for i in range(start.shape[0] - 1)]


def test_the_list_holds_exactly_the_pairs_within_the_skin_in_scan_order():
    """Row i holds every j > i with |x_i − x_j| < r_i + r_j + skin and nothing else (brute
    force over all pairs), once each, in the cell scan's order (cell row, cell column, then
    index within the cell); granule BIG's row is longer than a scratch row."""
    x, r = _granules()
    start, nbr, hist = build(x, r, SKIN, *empty_list(0))
    d = np.hypot(*(x[:, None, :] - x[None, :, :]).transpose(2, 0, 1))
    within = d < r[:, None] + r[None, :] + SKIN
    cell, _, _, ncx, _ = _cells(x, r, SKIN)
    rows = _rows(start, nbr)
    assert len(rows[BIG]) > _ROW_CAP
    for i, row in enumerate(rows):
        expected = [j for j in range(i + 1, len(x)) if within[i, j]]
        assert sorted(row) == expected, i
        assert row == sorted(row, key=lambda j: (cell[j] // ncx, cell[j] % ncx, j)), i
    assert np.all(hist == 0.0)


def test_the_history_of_pairs_kept_is_carried_over_and_new_pairs_start_at_zero():
    """Each entry's history set to a number naming its pair, the granules moved by a fifth of
    the skin in random directions, the list rebuilt: a pair in both lists keeps its number,
    a pair new to the list starts at 0."""
    x, r = _granules()
    start, nbr, _ = build(x, r, SKIN, *empty_list(0))
    i = np.repeat(np.arange(len(x)), np.diff(start))
    hist = (1000.0 * i + nbr).astype(float)
    rng = np.random.default_rng(4)
    angle = rng.uniform(0.0, 2.0 * np.pi, len(x))
    moved = x + 0.2 * SKIN * np.column_stack([np.cos(angle), np.sin(angle)])
    new_start, new_nbr, new_hist = build(moved, r, SKIN, start, nbr, hist)
    old = set(zip(i.tolist(), nbr.tolist(), strict=True))
    new_i = np.repeat(np.arange(len(x)), np.diff(new_start))
    kept = 0
    for a, b, h in zip(new_i.tolist(), new_nbr.tolist(), new_hist.tolist(), strict=True):
        assert h == (1000.0 * a + b if (a, b) in old else 0.0)
        kept += (a, b) in old
    assert 0 < kept < len(new_nbr)  # both kinds were checked


@pytest.mark.parametrize("n", [0, 1])
def test_no_pairs_for_fewer_than_two_granules(n: int):
    """No granule or one: an empty list whose start is all zeros."""
    x, r = np.zeros((n, 2)), np.full(n, 1e-3)
    start, nbr, hist = build(x, r, SKIN, *empty_list(0))
    assert start.tolist() == [0] * (n + 1) and nbr.size == 0 and hist.size == 0
