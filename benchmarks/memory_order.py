"""What the granules' order in memory costs the soft kernel (issue 14, item 2: spatial
reordering), measured before building it.

The 1,000-granule soft separator case scaled to N granules as in ``soft_scaling.py --family
finer`` (radius 1.5 mm·√(1000/N)), built three times with the same granules in three row
orders: the case's own (its placement), Morton (Z-curve) order of cells of one diameter, and a
random permutation.
Each simulation takes ``--warm`` untimed machine steps, then ``--blocks`` blocks of ``--steps``
timed ones, the three interleaved block by block, one thread; medians of the blocks, in ns per
granule-step (granule steps = machine steps x substeps x N).

    python benchmarks/memory_order.py                  # N = 12,500 and 50,000
    python benchmarks/memory_order.py --sizes 1000 --steps 50
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import time

import numba
import numpy as np
from soft_scaling import CASE, overrides

from perga.case import load_case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case


def morton_order(points: np.ndarray, cell: float) -> np.ndarray:
    """Indices of ``points`` (n, 2) sorted along the Z curve of square cells of side ``cell``."""
    q = np.floor((points - points.min(axis=0)) / cell).astype(np.uint64)

    def spread(v: np.ndarray) -> np.ndarray:  # the bits of v with a zero between each
        v = v & np.uint64(0xFFFFFFFF)
        for shift, mask in ((16, 0x0000FFFF0000FFFF), (8, 0x00FF00FF00FF00FF),
                            (4, 0x0F0F0F0F0F0F0F0F), (2, 0x3333333333333333),
                            (1, 0x5555555555555555)):  # fmt: skip
            v = (v | (v << np.uint64(shift))) & np.uint64(mask)
        return v

    return np.argsort(spread(q[:, 0]) | (spread(q[:, 1]) << np.uint64(1)), kind="stable")


def measure(n: int, warm: int, blocks: int, steps: int) -> dict[str, float]:
    """ns per granule-step of each order at ``n`` granules."""
    spec = compile_case(load_case(CASE, overrides=[*overrides("finer", n), "solver.threads=1"]))
    radius = spec.granules[0].radius
    points = np.array([g.position for g in spec.granules])
    orders = {
        "case": np.arange(n),
        "Morton": morton_order(points, 2 * radius),
        "random": np.random.default_rng(0).permutation(n),
    }
    sims = {
        name: Simulation(dataclasses.replace(spec, granules=[spec.granules[i] for i in order]))
        for name, order in orders.items()
    }
    for sim in sims.values():
        sim.run(warm * sim.dt)
    times: dict[str, list[float]] = {name: [] for name in sims}
    for _ in range(blocks):
        for name, sim in sims.items():
            start = time.perf_counter()
            for _ in range(steps):
                sim.step()
            times[name].append((time.perf_counter() - start) / steps)
    substeps = next(iter(sims.values())).contacts.substeps
    return {name: 1e9 * statistics.median(t) / (n * substeps) for name, t in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[12_500, 50_000])
    parser.add_argument("--warm", type=int, default=10)
    parser.add_argument("--blocks", type=int, default=5)
    parser.add_argument("--steps", type=int, default=10)
    args = parser.parse_args()
    numba.set_num_threads(1)
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    print(f"{'N':>8} {'case order':>11} {'Morton':>8} {'random':>8}   ns per granule-step")
    for n in args.sizes:
        r = measure(n, args.warm, args.blocks, args.steps)
        print(f"{n:>8} {r['case']:11.1f} {r['Morton']:8.1f} {r['random']:8.1f}")
    print(f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
