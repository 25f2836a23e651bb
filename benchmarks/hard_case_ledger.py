"""Why the rigid separator's energy ledger misses at high rotor speed (issue 15, item 2): the
closure after 0.1 s of ``cases/separator.toml`` (no impact happens in that time) against rotor
speed and time step, and against the error bias of Chipmunk's joints (the fraction of a joint's
position error left after one internal time unit, 1 ms; Pymunk's default pow(0.9, 60)).

    python benchmarks/hard_case_ledger.py
"""

from __future__ import annotations

from perga.case import load_case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case

CASE = "cases/separator.toml"


def ledger(rpm: float, dt: float, error_bias: float | None = None) -> str:
    """The ledger after 0.1 s at ``rpm`` and ``dt`` (s), with every joint's error bias set."""
    overrides = [f"rotor.rpm={rpm}", f"solver.dt={dt}", "solver.threads=1"]
    sim = Simulation(compile_case(load_case(CASE, overrides=overrides)))
    if error_bias is not None:
        for constraint in sim.machine.space.constraints:
            constraint.error_bias = error_bias
    sim.run(0.1)
    e = sim.energy()
    return (
        f"closure {e.closure:+.4f}, drive work {e.drive_work:.4f} J, "
        f"ΔKE {e.kinetic - e.kinetic_initial:+.4f} J, friction {e.friction:.4f} J, "
        f"KE {e.kinetic:.2f} J"
    )


def main() -> None:
    print("rotor speed and time step (Pymunk's default error bias):")
    for rpm in (600, 1500, 3000):
        for dt in (4e-5, 2e-5, 1e-5):
            print(f"  {rpm:>5} rpm, dt {dt:g} s: {ledger(rpm, dt)}")
    print("3000 rpm, dt 4e-5 s, the joints' error bias:")
    for bias in (None, 0.5, 1.0):
        label = "default" if bias is None else f"{bias:g}"
        print(f"  {label:>8}: {ledger(3000, 4e-5, bias)}")


if __name__ == "__main__":
    main()
