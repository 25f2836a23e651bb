"""The free cores (``perga.cores``): the cores allowed less the others' busy time, measured."""

from __future__ import annotations

import os
from types import SimpleNamespace

import pytest

from perga import cores

TICK = os.sysconf("SC_CLK_TCK")


def stat(busy: dict[int, float]) -> str:
    """A ``/proc/stat`` with CPUs 0-2: cpu k busy ``busy[k]`` seconds, spread over user, system
    and steal, and 1,000 s idle and 7 s iowait; the total line and a non-cpu line first."""
    lines = ["cpu  1 2 3 4 5 6 7 8 9 10", "intr 12345 6 7"]
    for k in range(3):
        ticks = round(busy.get(k, 0.0) * TICK)
        user, system, steal = ticks // 2, ticks // 4, ticks - ticks // 2 - ticks // 4
        lines.append(f"cpu{k} {user} 0 {system} {1000 * TICK} {7 * TICK} 0 0 {steal} 99 99")
    return "\n".join(lines) + "\n"


def test_busy_seconds_count_the_busy_columns_of_the_allowed_cpus_only() -> None:
    """user + nice + system + irq + softirq + steal of cpu0 and cpu1; not idle, iowait, guest
    (already in user), cpu2 or the total line."""
    text = stat({0: 3.0, 1: 5.0, 2: 11.0})
    assert cores.busy_seconds({0, 1}, text) == pytest.approx(8.0, abs=2.0 / TICK)


class Clock:
    """The monitor's ``time``: wall and own CPU seconds advanced by hand; sleep moves the wall."""

    def __init__(self) -> None:
        self.wall = 100.0
        self.own = 5.0

    def namespace(self) -> SimpleNamespace:
        def sleep(seconds: float) -> None:
            self.wall += seconds

        return SimpleNamespace(
            monotonic=lambda: self.wall, process_time=lambda: self.own, sleep=sleep
        )


@pytest.mark.parametrize(
    ("others", "own", "free"),
    [(0.0, 0.0, 2), (0.49, 0.0, 2), (0.51, 0.0, 1), (0.4, 1.5, 2), (0.6, 1.4, 1), (1.9, 0.0, 1),
     (2.0, 0.0, 1)],
)  # fmt: skip
def test_free_cores_are_the_cores_less_the_others_busy_time(monkeypatch, others, own, free):
    """Two cores allowed; over a 2 s interval the others keep ``others`` cores busy and this
    process ``own``: the busy counters count both, the process's own CPU time is taken off, and
    the rest is rounded (either side of 0.5), at least 1 left free."""
    clock = Clock()
    busy = {0: 10.0, 1: 20.0}
    monkeypatch.setattr(cores, "time", clock.namespace())
    monkeypatch.setattr(cores, "allowed_cores", lambda: {0, 1})
    monkeypatch.setattr(cores, "_read_stat", lambda: stat(busy))
    monitor = cores.CoreMonitor()
    assert monitor.free() == 2  # the first look: nothing busy over its window
    clock.wall += 2.0
    clock.own += 2.0 * own
    busy[0] += 2.0 * (others + own)
    assert monitor.free() == free


def test_without_proc_stat_the_load_average_counts(monkeypatch) -> None:
    """Where ``/proc/stat`` cannot be read: the cores less the one-minute load average."""
    monkeypatch.setattr(cores, "allowed_cores", lambda: {0, 1})
    monkeypatch.setattr(cores, "_read_stat", lambda: None)
    for load, free in ((0.2, 2), (0.6, 1), (1.4, 1), (3.0, 1)):
        monkeypatch.setattr(cores.os, "getloadavg", lambda load=load: (load, 0.0, 0.0))
        assert cores.CoreMonitor().free() == free


def test_this_machine_has_between_one_and_all_its_cores_free() -> None:
    assert 1 <= cores.free_cores() <= len(cores.allowed_cores())
