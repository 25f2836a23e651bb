"""The impact log's look for opened and closed granule-hammer contacts
(``perga.contact.soft.impacts._contact_changes``): it reads only the rows with a candidate
entry or an open contact, and finds what reading every row finds."""

from __future__ import annotations

import numpy as np

from perga.contact.soft.impacts import _contact_changes
from perga.contact.soft.polygon_set import HIST_ACTIVE, HIST_COLUMNS

N, N_POLY = 40, 5


def _look(hist, active, is_hammer, candidates):
    """The changes (granule, polygon, opened) and ``active`` after the look."""
    active = active.copy()
    out = np.empty((active.size, 3), dtype=np.int64)
    count = _contact_changes(hist, active, is_hammer, candidates, out)
    return out[:count].tolist(), active


def _scene(seed: int):
    """Contacts before and after a call that keep the candidate list's premise: every pair in
    contact after the call is listed, and so are some others; some pairs in contact before are
    no longer listed (they closed and left the list in the call)."""
    rng = np.random.default_rng(seed)
    is_hammer = np.ones(N_POLY, dtype=bool)
    is_hammer[-1] = False  # a wall piece: never an impact
    before = rng.random((N, N_POLY)) < 0.2
    after = rng.random((N, N_POLY)) < 0.2
    listed = after | (rng.random((N, N_POLY)) < 0.1)
    hist = np.zeros((N, N_POLY, HIST_COLUMNS))
    hist[:, :, HIST_ACTIVE] = after
    active = before & is_hammer
    candidates = np.concatenate([[0], np.cumsum(listed.sum(axis=1))]).astype(np.int64)
    return hist, active, is_hammer, candidates


def test_the_listed_and_open_rows_give_every_change_in_row_order() -> None:
    """On scenes that keep the list's premise the look finds the same changes, in the same
    order, as reading every row (no list: ``candidates`` of another length), and leaves
    ``active`` the same; the scenes have closes of pairs no longer listed."""
    unlisted_closes = 0
    for seed in range(20):
        hist, active, is_hammer, candidates = _scene(seed)
        full = _look(hist, active, is_hammer, np.zeros(0, dtype=np.int64))
        restricted = _look(hist, active, is_hammer, candidates)
        assert restricted[0] == full[0]
        assert np.array_equal(restricted[1], full[1])
        rows = {i for i, _, opened in full[0] if not opened}
        unlisted_closes += sum(candidates[i + 1] == candidates[i] for i in rows)
        assert full[0] == sorted(full[0])
    assert unlisted_closes > 0


def test_a_contact_that_closed_off_the_list_is_found() -> None:
    """A granule with an open contact and no entry in the last call's list (its pair closed
    and left the list): its close is found; a granule with neither is not read."""
    hist = np.zeros((3, 2, HIST_COLUMNS))
    hist[2, 1, HIST_ACTIVE] = 1.0  # not listed, not open: out of the premise, so not read
    active = np.zeros((3, 2), dtype=bool)
    active[1, 0] = True
    candidates = np.zeros(4, dtype=np.int64)  # no granule listed
    changes, after = _look(hist, active, np.ones(2, dtype=bool), candidates)
    assert changes == [[1, 0, 0]]
    assert not after.any()
