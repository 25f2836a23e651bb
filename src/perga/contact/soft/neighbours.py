"""Verlet neighbour list of granule pairs built with a cell list, in numba.

Half list in CSR form: the neighbours j > i of granule i are ``nbr[start[i]:start[i + 1]]``, all
pairs with centre distance < r_i + r_j + skin at build time. The list stays valid while no
granule has moved more than skin/2 since the build (two granules then cannot have closed a gap of
more than skin); ``kernel.advance`` checks that every step and rebuilds only then. The tangential
history of a pair (one float per list entry) is carried over a rebuild by finding j in the old
row of i (rows hold a handful of entries, so the linear search is cheap), all inside numba.
"""

import numpy as np
from numba import njit, prange

_MAX_CELLS_PER_GRANULE = 4
_ROW_CAP = 16
"""Entries of a granule's scratch row in ``build`` (a half list in 2-D holds a handful)."""


@njit(cache=True)
def _cells(x, r, skin):
    """Cell list: cell size ≥ 2 r_max + skin; returns (cell of each granule, sorted ids, starts)."""
    n = x.shape[0]
    xmin = x[0, 0]
    xmax = x[0, 0]
    ymin = x[0, 1]
    ymax = x[0, 1]
    rmax = 0.0
    for i in range(n):
        xmin = min(xmin, x[i, 0])
        xmax = max(xmax, x[i, 0])
        ymin = min(ymin, x[i, 1])
        ymax = max(ymax, x[i, 1])
        rmax = max(rmax, r[i])
    size = 2.0 * rmax + skin
    # A granule flung far away must not blow up the grid: widen the cells instead.
    while ((xmax - xmin) / size + 1.0) * ((ymax - ymin) / size + 1.0) > (
        _MAX_CELLS_PER_GRANULE * n + 16
    ):
        size *= 2.0
    ncx = int((xmax - xmin) / size) + 1
    ncy = int((ymax - ymin) / size) + 1
    cell = np.empty(n, np.int64)
    count = np.zeros(ncx * ncy + 1, np.int64)
    for i in range(n):
        cx = min(int((x[i, 0] - xmin) / size), ncx - 1)
        cy = min(int((x[i, 1] - ymin) / size), ncy - 1)
        c = cy * ncx + cx
        cell[i] = c
        count[c + 1] += 1
    for c in range(ncx * ncy):
        count[c + 1] += count[c]
    fill = count[:-1].copy()
    order = np.empty(n, np.int64)
    for i in range(n):
        c = cell[i]
        order[fill[c]] = i
        fill[c] += 1
    return cell, order, count, ncx, ncy


@njit(cache=True, inline="always")
def _scan(i, x, r, skin, cell, order, cstart, ncx, ncy, out, k0, cap):
    """Neighbours j > i of i in the 3×3 cells around it, in scan order: the first ``cap`` of
    them written to out[k0:]; returns their count."""
    cx = cell[i] % ncx
    cy = cell[i] // ncx
    xi = x[i, 0]
    yi = x[i, 1]
    k = 0
    gx0 = max(cx - 1, 0)
    gx1 = min(cx + 2, ncx)
    for gy in range(max(cy - 1, 0), min(cy + 2, ncy)):
        # the row's three cells are consecutive in the cell order: one run of granules
        for s in range(cstart[gy * ncx + gx0], cstart[gy * ncx + gx1]):
            j = order[s]
            if j <= i:
                continue
            reach = r[i] + r[j] + skin
            dx = x[j, 0] - xi
            dy = x[j, 1] - yi
            if dx * dx + dy * dy < reach * reach:
                if k < cap:
                    out[k0 + k] = j
                k += 1
    return k


@njit(cache=True, parallel=True)
def build(x, r, skin, old_start, old_nbr, old_hist):
    """New half list (start, nbr, hist) for positions x, radii r, skin (m).

    old_start, old_nbr, old_hist: the previous list and its tangential history (empty arrays
    for none); history of pairs present in both lists is copied, new pairs start at 0.

    Each granule's 3×3 cells are scanned once, granules taken cell by cell, into a scratch row
    of ``_ROW_CAP`` entries; the rows are then gathered into the list, and a longer row is
    scanned again straight into it (the same order: a row lists its neighbours in scan order
    either way).
    """
    n = x.shape[0]
    if n == 0:
        return np.zeros(1, np.int64), np.empty(0, np.int64), np.empty(0)
    cell, order, cstart, ncx, ncy = _cells(x, r, skin)
    counts = np.zeros(n + 1, np.int64)
    found = np.empty((n, _ROW_CAP), np.int64)
    for s in prange(n):
        i = order[s]  # cell by cell: the cells it scans are those just scanned, in cache
        counts[i + 1] = _scan(i, x, r, skin, cell, order, cstart, ncx, ncy, found[i], 0, _ROW_CAP)
    for i in range(n):
        counts[i + 1] += counts[i]
    nbr = np.empty(counts[n], np.int64)
    for i in prange(n):
        c = counts[i + 1] - counts[i]
        if c <= _ROW_CAP:
            for q in range(c):
                nbr[counts[i] + q] = found[i, q]
        else:  # a row longer than the scratch: scanned again, straight into the list
            _scan(i, x, r, skin, cell, order, cstart, ncx, ncy, nbr, counts[i], c)
    start = counts
    hist = np.zeros(nbr.shape[0])
    if old_hist.shape[0] > 0 and old_start.shape[0] == n + 1:
        for i in prange(n):
            o0 = old_start[i]
            o1 = old_start[i + 1]
            for k in range(start[i], start[i + 1]):
                j = nbr[k]
                for o in range(o0, o1):
                    if old_nbr[o] == j:
                        hist[k] = old_hist[o]
                        break
    return start, nbr, hist


def remap(
    start: np.ndarray, nbr: np.ndarray, hist: np.ndarray, keep: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The list (start, nbr, hist) without the granules where ``keep`` is False, the others
    renumbered in order (their pairs and tangential history kept)."""
    n = keep.shape[0]
    if start.shape[0] != n + 1:
        return empty_list(int(keep.sum()))
    i = np.repeat(np.arange(n), np.diff(start))
    entry = keep[i] & keep[nbr]
    index = np.cumsum(keep) - 1
    counts = np.bincount(index[i[entry]], minlength=int(keep.sum()))
    new_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return new_start, index[nbr[entry]].astype(np.int64), hist[entry].copy()


def empty_list(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A list with no pairs (forces a rebuild): start of zeros, empty nbr and hist."""
    return np.zeros(n + 1, np.int64), np.empty(0, np.int64), np.empty(0)


def default_skin(r: np.ndarray) -> float:
    """Default skin, m: 0.4 r_min (rebuild every few hundred steps in a dense bed)."""
    return 0.4 * float(np.min(r)) if r.size else 0.0


__all__ = ["build", "default_skin", "empty_list", "remap"]
