"""How many threads the soft kernel uses: one unless asked or worth it, never more than free.

Each kernel step opens several parallel regions whose launch costs tens of µs; below
``THREADED_FROM`` granules that costs more than a second thread gains, and on a busy machine a
second thread that has no free core to run on makes a step many times slower
(docs/performance.md). So "auto" is one thread unless the system has ``THREADED_FROM`` granules
or more and at least two cores are free; a number asked for is honoured up to the free cores.
Neither exceeds numba's own limit (``numba.get_num_threads``), which a Dask worker sets to one.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager

import numba

THREADED_FROM = 4000
"""Granule count from which "auto" uses more than one thread (docs/performance.md)."""


def free_cores() -> int:
    """CPU cores this process may use minus the one-minute load average, at least 1."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return max(1, (cores or 1) - round(os.getloadavg()[0]))


def kernel_threads(requested: int | None, granules: int, free: int) -> int:
    """The threads to use: ``requested`` (None: "auto") for a system of ``granules`` granules
    with ``free`` cores free."""
    limit = min(free, numba.get_num_threads())
    if requested is None:
        return limit if granules >= THREADED_FROM and limit >= 2 else 1
    return max(1, min(requested, limit))


@contextmanager
def numba_threads(threads: int) -> Iterator[None]:
    """Run the block's compiled parallel loops on ``threads`` threads, then restore the count.
    Everything parallel a soft run calls goes through here or ``SoftGranules.step``: a parallel
    loop on a second thread that has no free core waits for one (a 300-granule frame's energy
    took 5.5-8 ms instead of 0.37 ms on a loaded machine, docs/performance.md)."""
    previous = numba.get_num_threads()
    if previous != threads:
        numba.set_num_threads(threads)
    try:
        yield
    finally:
        if previous != threads:
            numba.set_num_threads(previous)
