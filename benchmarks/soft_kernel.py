"""Issue 14, item 2: the soft kernel alone (``SoftGranules.step``), one thread, per case.

Cases (each block starts afresh from the same state; medians over blocks):

* ``bed``: the settled 10,000-granule bed of ``beds.py`` (rows in strip order, as saved),
  ``--steps`` steps in one call: ns per particle-step;
* ``shuffled``: the same bed with its rows in a fixed random order (granules that touch are far
  apart in memory): what the kernel's memory order costs;
* ``frictionless``, ``rolling``: the bed with friction 0, or with rolling resistance μ_r = 0.05
  (the terms the kernel skips when they are zero);
* ``separator``: the bundled ``cases/soft-separator.toml`` run to t = 0.1 s by ``Simulation``,
  then ``SoftGranules.step(5)`` called ``--calls`` times (the separator's granule_substeps):
  µs per call, the per-call cost that a machine step pays.

Each block also prints a digest of the final positions and velocities, so that two source trees
can be checked for identical results. To compare two trees, run the script alternately under each
(``PYTHONPATH=<tree>/src``), the same case list, and compare the medians:

    python benchmarks/soft_kernel.py                      # all cases, ~1.5 min
    python benchmarks/soft_kernel.py --cases bed --blocks 5
"""

from __future__ import annotations

import argparse
import copy
import hashlib
import os
import statistics
import time
from pathlib import Path

import beds
import numpy as np

from perga.case import load_case
from perga.contact.soft import SoftGranules
from perga.contact.soft.laws import P_MU, P_MUR
from perga.engine import Simulation
from perga.model.compile import compile_case

SEPARATOR = Path(__file__).resolve().parents[1] / "cases" / "soft-separator.toml"


def digest(g: SoftGranules) -> str:
    """First 12 hex digits of a hash of x and v."""
    return hashlib.sha1(g.x.tobytes() + g.v.tobytes()).hexdigest()[:12]


def bed_block(
    x: np.ndarray, width: float, steps: int, mu: float = beds.FRICTION, mur: float = 0.0
) -> tuple[float, str]:
    """ns per particle-step of ``steps`` steps of the bed at x with friction mu and rolling
    resistance mur, and the final digest."""
    g = beds.soft_bed(x, width, threads=1)
    g.params[..., P_MU] = mu
    g.params[..., P_MUR] = mur
    g._pairs()  # first neighbour list, untimed
    t0 = time.perf_counter()
    g.step(steps)
    seconds = time.perf_counter() - t0
    return 1e9 * seconds / (g.n * steps), digest(g)


def separator_state() -> SoftGranules:
    """The soft separator's granules at t = 0.1 s (one thread)."""
    spec = compile_case(load_case(SEPARATOR))
    sim = Simulation(spec, record_impacts=False, track_energy=False)
    g = sim.contacts.granules
    g.set_threads(1)
    while sim.time < 0.1:
        sim.step()
    return g


def separator_block(state: SoftGranules, calls: int) -> tuple[float, str]:
    """µs per ``step(5)`` call from a copy of ``state``, and the final digest."""
    g = copy.deepcopy(state)
    g.step(5)
    t0 = time.perf_counter()
    for _ in range(calls):
        g.step(5)
    return 1e6 * (time.perf_counter() - t0) / calls, digest(g)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    cases = ["bed", "shuffled", "frictionless", "rolling", "separator"]
    p.add_argument("--cases", nargs="+", choices=cases, default=cases)
    p.add_argument("--size", type=int, default=10_000, help="bed granules")
    p.add_argument("--steps", type=int, default=1000, help="bed steps per block")
    p.add_argument("--calls", type=int, default=2000, help="separator step(5) calls per block")
    p.add_argument("--blocks", type=int, default=3)
    args = p.parse_args(argv)
    bed = beds.load(args.size)
    shuffled = bed.x[np.random.default_rng(1).permutation(bed.n)]
    state = separator_state() if "separator" in args.cases else None
    blocks = {
        "bed": lambda: bed_block(bed.x, bed.width, args.steps),
        "shuffled": lambda: bed_block(shuffled, bed.width, args.steps),
        "frictionless": lambda: bed_block(bed.x, bed.width, args.steps, mu=0.0),
        "rolling": lambda: bed_block(bed.x, bed.width, args.steps, mur=0.05),
        "separator": lambda: separator_block(state, args.calls),
    }
    unit = {name: "ns/particle-step" for name in cases} | {"separator": "µs/call"}
    for name in args.cases:
        blocks[name]()  # compile or load, untimed
    print(f"load {os.getloadavg()[0]:.2f}; {args.blocks} blocks")
    figures: dict[str, list[float]] = {name: [] for name in args.cases}
    digests: dict[str, set[str]] = {name: set() for name in args.cases}
    for _ in range(args.blocks):
        for name in args.cases:
            value, dig = blocks[name]()
            figures[name].append(value)
            digests[name].add(dig)
    for name in args.cases:
        f = figures[name]
        print(
            f"{name:12s} {statistics.median(f):8.2f} {unit[name]} ({min(f):.2f}-{max(f):.2f}), "
            f"digest {','.join(sorted(digests[name]))}"
        )
    print(f"load {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
