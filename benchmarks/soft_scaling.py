"""Memory and step cost of the soft separator against the number of granules (issue 14: 50,000
granules under 1 GB, cost no faster than linear in N).

The case is benchmarks/cases/soft-separator-1000.toml with N granules, scaled in one of two
families (``--family``):

* ``larger`` (weak scaling): the same granules (r = 1.5 mm) in a machine whose lengths (rotor,
  hammers, hinge circle, placement annulus, chamber) grow by s = √(N/1000), the hammers' mass
  by s² and the rotor speed divided by s: the same tip speed, granule density and contacts per
  granule, so the same work per granule if the code is linear in N;
* ``finer``: the same machine, the granules' radius shrinking as 1.5 mm·√(1000/N), so that they
  cover the same share of the placement annulus (27 %). The default skin is 0.4 r, so at the
  same speeds the neighbour list is rebuilt more often as N grows (about as √N): the physics of
  finer granules, not the code's order.

The contact duration (20 µs) and so the step are the same at every N. Each N runs in a fresh
subprocess: build (placement and the first neighbour list), ``--warm`` untimed machine steps,
then ``--steps`` timed ones on one thread, no output; peak resident memory (``ru_maxrss``) of
the process at the end, the neighbour list's rebuilds and the share of granule steps that
coasted in the timed steps.

With ``--instructions`` each N runs under Valgrind's callgrind instead, its instrumentation
switched on for the timed steps only (client requests from a helper compiled with gcc against
``valgrind/callgrind.h``; Debian's ``valgrind``), and the table gives the instructions executed
per granule-step: a count the caches and the machine's load do not touch, so that it shows
whether the code's work is linear in N apart from what the memory hierarchy adds to the time.

    python benchmarks/soft_scaling.py                         # both, N = 12,500 to 50,000
    python benchmarks/soft_scaling.py --family larger --sizes 1000 5000 --steps 100
    python benchmarks/soft_scaling.py --instructions          # instructions, not seconds
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "benchmarks/cases/soft-separator-1000.toml"
MARKS = "SOFT_SCALING_CALLGRIND_MARKS"
"""Environment variable: the path of the helper library whose calls switch callgrind on and off."""
MARKS_SOURCE = """#include <valgrind/callgrind.h>
void steps_begin(void) { CALLGRIND_START_INSTRUMENTATION; CALLGRIND_ZERO_STATS; }
void steps_end(void) { CALLGRIND_DUMP_STATS_AT("steps"); CALLGRIND_STOP_INSTRUMENTATION; }
"""


FAMILIES = ("larger", "finer")
LENGTHS = {  # m, at 1,000 granules: the case's lengths that the ``larger`` family scales
    "rotor.radius": 0.12,
    "hammers.hinge_radius": 0.08,
    "hammers.shape.length": 0.06,
    "hammers.shape.width": 0.02,
    "hammers.shape.hinge_offset": 0.005,
    "granules.placement.inner_radius": 0.01,
    "granules.placement.outer_radius": 0.09,
    "chamber.radius": 0.2,
    "chamber.wall_thickness": 0.02,
}


def overrides(family: str, n: int) -> list[str]:
    """The case's overrides for ``n`` granules of ``family`` (module docstring)."""
    if family == "finer":
        return [f"granules.count={n}", f"granules.radius={0.0015 * (1000 / n) ** 0.5}"]
    s = (n / 1000) ** 0.5
    return [
        f"granules.count={n}",
        f"rotor.rpm={600.0 / s}",
        f"hammers.mass={0.02826 * s * s}",
        *(f"{key}={length * s}" for key, length in LENGTHS.items()),
    ]


def one(family: str, n: int, warm: int, steps: int) -> None:
    """Build the case at ``n`` granules of ``family``, step it, print JSON figures."""
    import numba

    from perga.case import load_case
    from perga.engine.simulation import Simulation
    from perga.model.compile import compile_case

    numba.set_num_threads(1)
    start = time.perf_counter()
    case = load_case(CASE, overrides=[*overrides(family, n), "solver.threads=1"])
    sim = Simulation(compile_case(case), record_impacts=True, track_energy=True)
    built = time.perf_counter() - start
    for _ in range(warm):
        sim.step()
    granules = sim.contacts.granules
    rebuilds, coasted = granules.n_rebuilds, granules.coasted
    marks = ctypes.CDLL(os.environ[MARKS]) if MARKS in os.environ else None
    if marks:
        marks.steps_begin()
    start = time.perf_counter()
    for _ in range(steps):
        sim.step()
    stepped = time.perf_counter() - start
    if marks:
        marks.steps_end()
    rebuilt = granules.n_rebuilds - rebuilds
    granule_steps = steps * sim.contacts.substeps * n
    print(
        json.dumps(
            {
                "n": n,
                "granule_steps": granule_steps,
                "radius": float(granules.r[0]),
                "rebuilds_per_1000": 1e3 * rebuilt / (steps * sim.contacts.substeps),
                "coasted": (granules.coasted - coasted) / granule_steps,
                "build_s": built,
                "step_ms": 1e3 * stepped / steps,
                "ns_per_particle_step": 1e9 * stepped / granule_steps,
                "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                "ledger_closure": sim.energy().closure,
            }
        )
    )


def instructions(family: str, n: int, args: argparse.Namespace, folder: Path) -> dict:
    """The figures of ``n`` granules of ``family`` stepped under callgrind, with the instructions
    of the timed steps (``instructions``)."""
    out = folder / f"{family}.{n}"
    done = subprocess.run(
        ["valgrind", "--tool=callgrind", "--instr-atstart=no", f"--callgrind-out-file={out}",
         sys.executable, __file__, "--one", str(n), "--family", family,
         "--warm", str(args.warm), "--steps", str(args.steps)],
        env=dict(os.environ, NUMBA_NUM_THREADS="1", **{MARKS: str(folder / "marks.so")}),
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    figures = json.loads(done.stdout.strip().splitlines()[-1])
    dump = Path(f"{out}.1").read_text().splitlines()
    figures["instructions"] = int(next(line for line in dump if line.startswith("summary:"))[8:])
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--family", choices=FAMILIES, nargs="+", default=list(FAMILIES))
    parser.add_argument("--sizes", type=int, nargs="+", default=[12_500, 25_000, 50_000])
    parser.add_argument("--warm", type=int, default=20)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--instructions", action="store_true", help="count, under callgrind")
    parser.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        one(args.family[0], args.one, args.warm, args.steps)
        return
    if args.instructions:
        count_instructions(args)
        return
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    print(f"load average at start: {os.getloadavg()[0]:.2f}; cores: {os.cpu_count()}")
    for family in args.family:
        print(f"\n{family}:")
        print(f"{'N':>7} {'r, mm':>6} {'build s':>8} {'ms/step':>8} {'ns/particle-step':>17} "
              f"{'rebuilds/1000':>14} {'coasted':>8} {'peak RSS, MB':>13} "
              f"{'closure':>9}")  # fmt: skip
        rows = []
        for n in args.sizes:
            done = subprocess.run(
                [sys.executable, __file__, "--one", str(n), "--family", family,
                 "--warm", str(args.warm), "--steps", str(args.steps)],
                env=env, capture_output=True, text=True, check=True,
            )  # fmt: skip
            r = json.loads(done.stdout.strip().splitlines()[-1])
            rows.append(r)
            print(f"{n:7d} {1e3 * r['radius']:6.3f} {r['build_s']:8.1f} {r['step_ms']:8.2f} "
                  f"{r['ns_per_particle_step']:17.1f} {r['rebuilds_per_1000']:14.1f} "
                  f"{100 * r['coasted']:7.0f}% {r['peak_rss_mb']:13.0f} "
                  f"{r['ledger_closure']:9.1e}")  # fmt: skip
        growth(rows, "step_ms")
    print(f"\nload average at end: {os.getloadavg()[0]:.2f}")


def count_instructions(args: argparse.Namespace) -> None:
    """The instructions table (``--instructions``)."""
    missing = [tool for tool in ("valgrind", "gcc") if shutil.which(tool) is None]
    if not Path("/usr/include/valgrind/callgrind.h").exists():
        missing.append("valgrind/callgrind.h")
    if missing:
        sys.exit(f"--instructions needs {', '.join(missing)}: apt-get install valgrind gcc")
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        (folder / "marks.c").write_text(MARKS_SOURCE)
        subprocess.run(
            ["gcc", "-O2", "-shared", "-fPIC", "-o", folder / "marks.so", folder / "marks.c"],
            check=True,
        )
        for family in args.family:
            print(f"\n{family}, instructions of {args.steps} machine steps under callgrind:")
            print(f"{'N':>7} {'rebuilds/1000':>14} {'coasted':>8} "
                  f"{'instructions/particle-step':>27}")  # fmt: skip
            rows = []
            for n in args.sizes:
                r = instructions(family, n, args, folder)
                rows.append(r)
                print(f"{n:7d} {r['rebuilds_per_1000']:14.1f} {100 * r['coasted']:7.0f}% "
                      f"{r['instructions'] / r['granule_steps']:27.1f}")  # fmt: skip
            growth(rows, "instructions")


def growth(rows: list[dict], figure: str) -> None:
    """Print ``figure`` per granule at each size against the first size's."""
    first = rows[0]
    for r in rows[1:]:
        ratio = (r[figure] / first[figure]) / (r["n"] / first["n"])
        print(f"{figure} per granule at {r['n']} / at {first['n']}: {ratio:.2f} (1 = linear)")


if __name__ == "__main__":
    main()
