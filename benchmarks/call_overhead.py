"""What a soft kernel call costs beyond its steps: a free gas (no granule within reach of
another, no walls, no polygons) stepped in calls of 1, 5 and 50 steps from compiled code, as
the soft model's whole machine steps call the kernel (``perga.contact.soft.machine_steps``),
so that numba's dispatch from Python is not counted.

The gas: 1,000 granules of the 1,000-granule separator's size (r = 1.5 mm, 57 mg) on a square
grid 10 mm apart, velocities normal with sd 1 m/s (seed 1), the separator's step (0.274 µs).
Every granule coasts when coasting is on (``perga.contact.soft.coasting``). Printed: ns a
granule-step, median and range over ``--blocks`` blocks of 4,000 granule steps each from a
copy of the state, and the share of granule steps coasted; the difference between calls of 5
and of 50 steps, times 5, is what a call costs a granule beyond its steps.

    python benchmarks/call_overhead.py
    python benchmarks/call_overhead.py --granules 3000 --blocks 7
"""

from __future__ import annotations

import argparse
import copy
import os
import statistics
import time

import numba
import numpy as np
from numba import njit

from perga.contact.soft import SoftGranules, contact_parameters, kernel, uniform_table
from perga.contact.soft.granules import opening_of

RADIUS = 1.5e-3  # m
MASS = 5.7e-5  # kg
SPACING = 0.01  # m
DT = 2.737e-7  # s: the 1,000-granule separator's granule step


@njit
def calls_of(count, call, opening):
    """``count`` kernel calls with the arguments ``call`` (``SoftGranules.call_arguments``, its
    settings' coast as given), the neighbour list carried from call to call; returns the
    granule steps coasted."""
    settings, granules, props, bonds, params, walls, polygons, nbrs, work = call
    n_steps, dt, gravity, skin, drag, v_cap, pairs, _, first, coast = settings
    start, nbr, hist, x_ref = nbrs
    coasted = 0
    for c in range(count):
        out = kernel.advance(
            (n_steps, dt, gravity, skin, drag, v_cap, pairs, False, first + c * n_steps, coast),
            granules, props, bonds, params, walls, polygons, (start, nbr, hist, x_ref), work,
            opening,
        )  # fmt: skip
        start, nbr, hist = out[0], out[1], out[2]
        coasted += out[7]
    return coasted


def gas(n: int) -> SoftGranules:
    """The free gas of the module doc, one step taken (the neighbour list built)."""
    side = int(np.ceil(np.sqrt(n)))
    x = np.array([(i % side, i // side) for i in range(n)], float) * SPACING
    row = contact_parameters("linear", 0.7, k_n=1e4, friction=0.4)
    g = SoftGranules(x, np.full(n, RADIUS), np.full(n, MASS), uniform_table(row), dt=DT)
    g.v[:] = np.random.default_rng(1).normal(0.0, 1.0, (n, 2))
    g.set_threads(1)
    g.step(1)
    return g


def block(g: SoftGranules, n_steps: int, coast: bool) -> tuple[float, float]:
    """(ns a granule-step, share coasted) of 4,000 granule steps per granule in calls of
    ``n_steps`` on g, which it uses up."""
    call = g.call_arguments(n_steps)
    call = ((*call[0][:-1], coast), *call[1:])
    count = 4000 // n_steps
    start = time.perf_counter()
    coasted = calls_of(count, call, opening_of(None, None))
    seconds = time.perf_counter() - start
    steps = count * n_steps * g.n
    return seconds / steps * 1e9, coasted / steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--granules", type=int, default=1000)
    parser.add_argument("--blocks", type=int, default=5)
    args = parser.parse_args()
    numba.set_num_threads(1)
    print(f"load average at start: {os.getloadavg()[0]:.2f}; one thread")
    state = gas(args.granules)
    block(copy.deepcopy(state), 5, True)  # compile
    per_step = {}
    for coast in (True, False):
        for n_steps in (1, 5, 50):
            results = [block(copy.deepcopy(state), n_steps, coast) for _ in range(args.blocks)]
            ns = [r[0] for r in results]
            per_step[coast, n_steps] = statistics.median(ns)
            print(
                f"calls of {n_steps:>2} steps, coasting {'on ' if coast else 'off'}: "
                f"{statistics.median(ns):6.2f} ns a granule-step ({min(ns):.2f}-{max(ns):.2f}), "
                f"coasted {results[-1][1]:.2f}"
            )
    for coast in (True, False):
        beyond = 5 * (per_step[coast, 5] - per_step[coast, 50])
        print(
            f"coasting {'on ' if coast else 'off'}: a call costs {beyond:.1f} ns a granule beyond "
            f"its steps ({beyond * args.granules / 1e3:.1f} µs for {args.granules} granules), "
            f"{beyond / (5 * per_step[coast, 5]):.0%} of a call of 5 steps"
        )
    print(f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
