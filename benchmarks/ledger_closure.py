"""Issue 15, item 2, and issue 17, item 5: the energy ledger's closure of every bundled case
with a chamber at 0.1 ms, 1 ms, 10 ms and the case's end (its own duration): the residual (J),
the energy in play it is judged against (J), the kinetic energy at the start and now, the
drive's work and the contacts' dissipation (J); the joints' correction work booked
(``joint_correction``); and, for comparison, the residual over all the kinetic and elastic
energy present, the machine's included (the denominator not chosen: docs/dev/reliability.md).

    python benchmarks/ledger_closure.py                    # every bundled case, ~4 min
    python benchmarks/ledger_closure.py separator vertical-rotor
    python benchmarks/ledger_closure.py vertical-rotor --set solver.substeps=2
"""

from __future__ import annotations

import argparse
from pathlib import Path

from perga.case import load_case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cases", nargs="*", help="bundled cases by name (default: all)")
    parser.add_argument("--set", action="append", default=[], help="override KEY=VALUE")
    args = parser.parse_args()
    names = args.cases or [p.stem for p in sorted(Path("cases").glob("*.toml"))]
    for name in names:
        case = load_case(Path("cases") / f"{name}.toml", overrides=args.set)
        if case.chamber is None:
            continue  # a parameter set, not a scene
        sim = Simulation(compile_case(case))
        rows = []
        with sim.running():
            for t in (1e-4, 0.001, 0.01, case.solver.duration):
                if t > case.solver.duration + 1e-12:
                    continue
                sim.run(t - sim.time)
                e = sim.energy()
                everything = max(e.energy_in_play, e.kinetic + e.elastic)
                rows.append(
                    f"t = {t:g} s: {e.closure:+.2%} of {e.energy_in_play:.3g} J, residual "
                    f"{e.residual:+.2g} J ({e.residual / everything:+.3%} of all energy present; "
                    f"KE {e.kinetic_initial:.3g} -> "
                    f"{e.kinetic:.3g} J, drive {e.drive_work:.3g} J, contacts "
                    f"{e.contact_dissipation:.3g} J, joints {e.joint_correction:.3g} J)"
                )
        print(f"{name}: " + " | ".join(rows), flush=True)


if __name__ == "__main__":
    main()
