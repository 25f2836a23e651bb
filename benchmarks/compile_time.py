"""What compiling perga's soft step costs: a case built and its first machine steps taken in a
fresh process with an empty numba cache (``NUMBA_CACHE_DIR`` a new folder), optionally in
another commit too (``--against REF``, a temporary worktree), the trees alternating run by
run. Printed: the seconds to import and build, and to take the first steps (compiling), each
run, and the medians.

    python benchmarks/compile_time.py                                # soft separator, 1 thread
    python benchmarks/compile_time.py --against a18dd18 --repeats 2
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from trees import worktree

ROOT = Path(__file__).resolve().parents[1]


def first_steps(case: Path, steps: int) -> None:
    """In this process: build ``case`` on one thread and take ``steps`` machine steps; prints
    (build s, steps s) as JSON."""
    t0 = time.perf_counter()
    from perga.case import load_case
    from perga.engine import Simulation
    from perga.model.compile import compile_case

    spec = compile_case(load_case(case, overrides=["solver.threads=1"]))
    sim = Simulation(spec, record_impacts=False, track_energy=False)
    t1 = time.perf_counter()
    for _ in range(steps):
        sim.step()
    print(json.dumps([t1 - t0, time.perf_counter() - t1]))


def measured(src: Path, case: Path, steps: int) -> list[float]:
    """:func:`first_steps` run by the tree ``src`` in a fresh process with an empty cache."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "PYTHONPATH": str(src), "NUMBA_CACHE_DIR": cache}
        command = [sys.executable, __file__, "--one", str(case), "--steps", str(steps)]
        done = subprocess.run(command, check=True, capture_output=True, text=True, env=env)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", type=Path, default=ROOT / "cases" / "soft-separator.toml")
    parser.add_argument("--steps", type=int, default=3, help="machine steps taken")
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--against", help="a commit to measure alternately")
    parser.add_argument("--one", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one is not None:
        first_steps(args.one, args.steps)
        return
    trees = {"this tree": ROOT / "src"}
    if args.against:
        trees[args.against] = worktree(args.against)
    print(f"{args.case.name}: {args.steps} machine steps, empty numba cache, load "
          f"{os.getloadavg()[0]:.2f}")  # fmt: skip
    runs: dict[str, list[list[float]]] = {name: [] for name in trees}
    for _ in range(args.repeats):
        for name, src in trees.items():
            runs[name].append(measured(src, args.case, args.steps))
            build, steps = runs[name][-1]
            print(f"  {name:>10}: build {build:5.1f} s, first steps {steps:5.1f} s")
    for name, done in runs.items():
        build = statistics.median(b for b, _ in done)
        steps = statistics.median(s for _, s in done)
        print(f"{name:>12}: median build {build:.1f} s, first steps {steps:.1f} s")
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
