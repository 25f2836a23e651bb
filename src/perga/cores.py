"""The CPU cores free to this process: the cores it may run on less what other processes use.

On Linux the figure is measured: the busy time of those cores in the kernel's counters
(``/proc/stat``: user, nice, system, irq, softirq and steal) over an interval, less this
process's own CPU time over it (``time.process_time``), divided by the interval. It is the load
of the last interval, where the one-minute load average (the fallback elsewhere) still counts a
job that ended a minute ago and barely counts one that started seconds ago.
"""

from __future__ import annotations

import os
import time

FIRST_WINDOW = 0.1
"""Interval of a monitor's first look, s (at 100 clock ticks a second and two cores, 20 ticks:
the busy cores to ±0.1)."""

_BUSY_FIELDS = (0, 1, 2, 5, 6, 7)
"""Columns of a ``/proc/stat`` cpu line that are busy time: user, nice, system, irq, softirq,
steal (guest time is inside user; idle and iowait are free)."""


def allowed_cores() -> set[int]:
    """The CPUs this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return set(os.sched_getaffinity(0))
    return set(range(os.cpu_count() or 1))


def busy_seconds(cpus: set[int], stat: str) -> float:
    """Busy CPU-seconds since boot of the CPUs ``cpus`` in the text of ``/proc/stat``."""
    ticks = 0
    for line in stat.splitlines():
        name, _, rest = line.partition(" ")
        if name.startswith("cpu") and name[3:].isdigit() and int(name[3:]) in cpus:
            values = rest.split()
            ticks += sum(int(values[k]) for k in _BUSY_FIELDS if k < len(values))
    return ticks / os.sysconf("SC_CLK_TCK")


def _read_stat() -> str | None:
    try:
        with open("/proc/stat", encoding="ascii") as f:
            return f.read()
    except OSError:
        return None


class CoreMonitor:
    """Free cores over the interval since the monitor's last look (the first look waits
    ``FIRST_WINDOW``): cores − round(the others' busy CPU-seconds / the interval's seconds), at
    least 1. Without ``/proc/stat``: cores − round(the one-minute load average), at least 1."""

    def __init__(self) -> None:
        self.cores = allowed_cores()
        self._last: tuple[float, float, float] | None = None

    def _look(self) -> tuple[float, float, float] | None:
        stat = _read_stat()
        if stat is None:
            return None
        return time.monotonic(), busy_seconds(self.cores, stat), time.process_time()

    def free(self) -> int:
        """The free cores now (class doc)."""
        now = self._look()
        if now is not None and self._last is None:
            time.sleep(FIRST_WINDOW)
            self._last, now = now, self._look()
        if now is None or self._last is None:
            try:
                load = os.getloadavg()[0]
            except OSError:
                load = 0.0
            return max(1, len(self.cores) - round(load))
        (wall0, busy0, own0), (wall1, busy1, own1) = self._last, now
        self._last = now
        others = max(0.0, (busy1 - busy0) - (own1 - own0)) / max(wall1 - wall0, 1e-9)
        return max(1, len(self.cores) - round(others))


def free_cores() -> int:
    """The free cores now, measured over ``FIRST_WINDOW`` (``CoreMonitor``)."""
    return CoreMonitor().free()
