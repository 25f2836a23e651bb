"""How the soft kernel splits its work and how many threads do it.

The kernel sums the granule-pair forces in chunks (``perga.contact.soft.kernel``), and the
chunks fix the order of every sum: results depend on the chunk count, never on the threads that
compute the chunks. So the chunks come from the case alone (``solver.threads`` if given; "auto":
one below ``THREADED_FROM`` granules, ``AUTO_CHUNKS`` from there), and the threads from the
machine: as many as chunks, never more than the free cores (``perga.cores``, looked at again
every ``RECHECK`` seconds of a run) nor numba's own limit (``numba.get_num_threads``, which a
Dask worker sets to one). The same case gives the same bytes on an idle machine, a busy one and
a Dask worker.

Each kernel step opens several parallel regions, each with a launch cost; below
``THREADED_FROM`` granules that costs more than a second thread gains, and on a busy machine a
second thread that has no free core to run on makes a step many times slower
(docs/dev/performance.md).
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager

import numba

THREADED_FROM = 4000
"""Granule count from which "auto" splits the work (docs/dev/performance.md)."""
RECHECK = 1.0
"""Wall seconds between a run's looks at the free cores (a job started or ended meanwhile)."""
AUTO_CHUNKS = 2
"""Chunks of "auto" from ``THREADED_FROM`` granules: the gain measured on two cores
(docs/dev/performance.md); more threads need ``solver.threads``."""


def kernel_chunks(requested: int | None, granules: int) -> int:
    """The chunks of a system of ``granules`` granules: ``requested`` threads (None: "auto")."""
    if requested is None:
        return AUTO_CHUNKS if granules >= THREADED_FROM else 1
    return max(1, requested)


def kernel_threads(chunks: int, free: int) -> int:
    """The threads that compute ``chunks`` chunks with ``free`` cores free."""
    return max(1, min(chunks, free, numba.get_num_threads()))


_local = threading.local()
"""Per Python thread, as numba's own count: ``held``, the count the innermost
``numba_threads`` block of this thread holds."""


@contextmanager
def numba_threads(threads: int) -> Iterator[None]:
    """Run the block's compiled parallel loops on ``threads`` threads, then restore the count.
    Everything parallel a soft run calls goes through here or ``SoftGranules.step``: a parallel
    loop on a second thread that has no free core waits for one (docs/dev/performance.md). Inside
    the block ``held_threads()`` is ``threads``: a kernel call that needs that count then takes
    it as set, without asking numba."""
    previous = numba.get_num_threads()
    outer = held_threads()
    if previous != threads:
        numba.set_num_threads(threads)
    _local.held = threads
    try:
        yield
    finally:
        _local.held = outer
        if previous != threads:
            numba.set_num_threads(previous)


def held_threads() -> int | None:
    """The thread count the innermost ``numba_threads`` block of this Python thread holds
    (numba's count is per thread too), None outside one."""
    return getattr(_local, "held", None)
