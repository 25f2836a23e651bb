"""Step a simulation in memory, no files: a case changed by overrides, the system built from
it, and its state read between steps (SI units).

    python examples/step_in_memory.py
"""

from pathlib import Path

import numpy as np

import perga

CASES = Path(__file__).resolve().parents[1] / "cases"

case = perga.load_case(CASES / "single-granule.toml", overrides=["rotor.rpm=900"])
sim = perga.Simulation(perga.compile_case(case))
for t in (0.01, 0.02, 0.03, 0.04):
    sim.run(t - sim.time)
    speed = np.hypot(*sim.frame().granules.velocities[0])
    print(f"t = {sim.time:.3f} s: granule speed {speed:.3f} m/s, {len(sim.impacts)} impacts")
ledger = sim.energy()
print(
    f"drive work {ledger.drive_work:.4g} J, dissipated {ledger.contact_dissipation:.4g} J, "
    f"closure {ledger.closure:+.2e}"
)
