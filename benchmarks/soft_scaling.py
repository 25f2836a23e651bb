"""Memory and step cost of the soft separator against the number of granules (issue 14: 50,000
granules under 1 GB, cost no faster than linear in N).

The case is benchmarks/cases/soft-separator-1000.toml with N granules whose radius shrinks as
1/√N (r = 1.5 mm at 1,000), so that the granules cover the same share of the placement annulus
at every N (27 %): the same density, the same contacts per granule. The contact duration (20 µs)
and so the step are the same at every N. Each N runs in a fresh subprocess: build (placement and
the first neighbour list), ``--warm`` untimed machine steps, then ``--steps`` timed ones on one
thread, no output; peak resident memory (``ru_maxrss``) of the process at the end.

    python benchmarks/soft_scaling.py                         # N = 12,500, 25,000, 50,000
    python benchmarks/soft_scaling.py --sizes 1000 5000 --steps 100
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "benchmarks/cases/soft-separator-1000.toml"


def one(n: int, warm: int, steps: int) -> None:
    """Build the case at ``n`` granules, step it, print JSON figures."""
    import numba

    from perga.case import load_case
    from perga.engine.simulation import Simulation
    from perga.model.from_case import scene_spec

    numba.set_num_threads(1)
    radius = 0.0015 * (1000 / n) ** 0.5
    start = time.perf_counter()
    case = load_case(
        CASE,
        overrides=[
            f"granules.count={n}",
            f"granules.radius={radius}",
            "solver.threads=1",
        ],
    )
    sim = Simulation(scene_spec(case), record_impacts=True, track_energy=True)
    built = time.perf_counter() - start
    for _ in range(warm):
        sim.step()
    start = time.perf_counter()
    for _ in range(steps):
        sim.step()
    stepped = time.perf_counter() - start
    granule_steps = steps * sim.contacts.substeps * n
    print(
        json.dumps(
            {
                "n": n,
                "radius": radius,
                "build_s": built,
                "step_ms": 1e3 * stepped / steps,
                "ns_per_particle_step": 1e9 * stepped / granule_steps,
                "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                "ledger_closure": sim.energy().closure,
            }
        )
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[12_500, 25_000, 50_000])
    parser.add_argument("--warm", type=int, default=20)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        one(args.one, args.warm, args.steps)
        return
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    print(f"load average at start: {os.getloadavg()[0]:.2f}; cores: {os.cpu_count()}")
    print(f"{'N':>7} {'r, mm':>6} {'build s':>8} {'ms/step':>8} {'ns/particle-step':>17} "
          f"{'peak RSS, MB':>13} {'closure':>9}")  # fmt: skip
    rows = []
    for n in args.sizes:
        done = subprocess.run(
            [sys.executable, __file__, "--one", str(n), "--warm", str(args.warm),
             "--steps", str(args.steps)],
            env=env, capture_output=True, text=True, check=True,
        )  # fmt: skip
        r = json.loads(done.stdout.strip().splitlines()[-1])
        rows.append(r)
        print(f"{n:7d} {1e3 * r['radius']:6.3f} {r['build_s']:8.1f} {r['step_ms']:8.2f} "
              f"{r['ns_per_particle_step']:17.1f} {r['peak_rss_mb']:13.0f} "
              f"{r['ledger_closure']:9.1e}")  # fmt: skip
    first = rows[0]
    for r in rows[1:]:
        growth = (r["step_ms"] / first["step_ms"]) / (r["n"] / first["n"])
        print(f"cost per granule at {r['n']} / at {first['n']}: {growth:.2f} (1 = linear)")
    print(f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
