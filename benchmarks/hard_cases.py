"""The hard-case matrix of issue 15 (must show): the bundled rigid and soft separators pushed to
the edges a user reaches (3000 rpm, a 1:20,000 granule-to-hammer mass ratio, restitution 0.05
and 1, friction 0 and 1, a dense pack, a granule at a hinge), each run for ``--duration`` s:
refused up front (with the reason), or run, with its status and the energy ledger's closure
at the end against the project's 1 %.

    python benchmarks/hard_cases.py                    # 0.1 s each
    python benchmarks/hard_cases.py --duration 0.5
    python benchmarks/hard_cases.py --duration 10 --rows "as bundled"   # the 10 s run
"""

from __future__ import annotations

import argparse
import os
import time

from perga.case import CaseError, load_case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case

CASES = {"rigid": "cases/separator.toml", "soft": "cases/soft-separator.toml"}
HARD = {
    "as bundled": [],
    "3000 rpm": ["rotor.rpm=3000"],
    "mass ratio 1:20,000": ["hammers.mass=3.2"],
    "e = 0.05": ["contacts[0].restitution=0.05"],
    "e = 1": ["contacts[0].restitution=1.0"],
    "f = 0": ["contacts[0].friction=0.0"],
    "f = 1": ["contacts[0].friction=1.0"],
    "dense pack (380 granules)": ["granules.count=380"],
    "a granule at a hinge": [
        'granules.placement={kind="explicit", positions=[[0.08, 0.0]]}',
        "granules.count=1",
    ],
}
"""Name -> case overrides (hammers.mass 3.2 kg against the 0.16 g granule: 1:20,000)."""


def one(case: str, overrides: list[str], duration: float) -> str:
    """One row: refused (its first problem), or the run's closure and wall time."""
    try:
        system = compile_case(load_case(case, overrides=[*overrides, "solver.threads=1"]))
    except CaseError as exc:
        return f"refused: {exc.problems[0].split(': ', 1)[1][:110]}"
    sim = Simulation(system)
    start = time.perf_counter()
    try:
        sim.run(duration)
    except Exception as exc:  # a row of the table, whatever stopped the run
        return f"failed at t = {sim.time:.4g} s: {type(exc).__name__}: {exc}"[:140]
    ledger = sim.energy()
    verdict = "within 1 %" if abs(ledger.closure) <= 0.01 else "MISSES 1 %"
    wall = time.perf_counter() - start
    return (
        f"closure {ledger.closure:+.2%} of {ledger.energy_in_play:.3g} J ({verdict}; residual "
        f"{ledger.residual:+.2g} J), {len(sim.impacts)} impacts, {wall:.1f} s"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=0.1, help="simulated s per case")
    parser.add_argument(
        "--rows", nargs="+", choices=list(HARD), default=list(HARD), help="rows of the matrix"
    )
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f}; {args.duration} s each")
    print("| case | rigid | soft |\n| --- | --- | --- |")
    for name in args.rows:
        rows = [one(case, HARD[name], args.duration) for case in CASES.values()]
        print(f"| {name} | {rows[0]} | {rows[1]} |")


if __name__ == "__main__":
    main()
