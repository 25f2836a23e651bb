"""Cost of reading granule state: ``perga.machine.batch.BodyReader`` (pymunk.batch) against a
per-body Python loop over the rigid granules' bodies (positions, velocities, spins).

Scene: the one of ``engine_vs_pymunk.py`` (rotor, 6 hinged hammers, chamber), after 20 steps so
that the state is not the initial one. Reported: median µs per read over --repeats reads.

    python benchmarks/state_read.py                      # ~10 s
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from perga.engine import Simulation
from perga.machine.batch import BodyReader

sys.path.insert(0, str(Path(__file__).parent))
from engine_vs_pymunk import perga_spec


def median_us(read: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        read()
        times.append(time.perf_counter() - t0)
    return 1e6 * statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[1000, 5000])
    p.add_argument("--repeats", type=int, default=50)
    args = p.parse_args(argv)
    print(
        "| granules | loop: positions + velocities + ω, µs | reader.read(), µs | speed-up |"
        " reader.positions(), µs |"
    )
    print("|---:|---:|---:|---:|---:|")
    for n in args.sizes:
        sim = Simulation(perga_spec(n, chamber=True), record_impacts=False, track_energy=False)
        for _ in range(20):
            sim.step()
        reader = BodyReader(sim.machine.space, sim.contacts.bodies.granule_bodies)
        positions, velocities, spins = reader.read()
        granules = sim.frame().granules
        assert np.array_equal(positions, granules.positions)
        assert np.array_equal(velocities, granules.velocities)
        assert np.array_equal(spins, granules.angular_velocities)
        bodies = sim.contacts.bodies.granule_bodies

        def loop(bodies: list = bodies) -> None:
            np.array([tuple(b.position) for b in bodies])
            np.array([tuple(b.velocity) for b in bodies])
            np.array([b.angular_velocity for b in bodies])

        t_loop = median_us(loop, args.repeats)
        t_batch = median_us(reader.read, args.repeats)
        t_pos = median_us(reader.positions, args.repeats)
        print(f"| {n} | {t_loop:.0f} | {t_batch:.0f} | {t_loop / t_batch:.0f}x | {t_pos:.0f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
