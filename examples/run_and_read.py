"""Run a bundled case from Python, then read its tables: the API of ``perga``.

python examples/run_and_read.py [OUT]     # OUT: a folder for the run (default runs/api)
"""

import sys
from pathlib import Path

import numpy as np

import perga

CASES = Path(__file__).resolve().parents[1] / "cases"
out = Path(sys.argv[1] if len(sys.argv) > 1 else "runs/api")

summary = perga.simulate(
    CASES / "separator.toml", out, overrides=["solver.duration=0.2"], overwrite=True
)
print(f"{summary.status}: {summary.impacts} impacts, ledger {summary.energy['closure']:+.3%}")

run = perga.load_run(out)
end = run.granules["time"].max()
speeds = run.granules["speed"][run.granules["time"] == end]
print(f"mean speed at {end:.3g} s: {speeds.mean():.3f} m/s")
impacts = run.dataframe("impacts")  # pandas (pip install 'perga[notebook]')
print(f"fastest normal approach: {-impacts['normal_velocity_before'].min():.2f} m/s")
print(f"ledger closure as a metric: {perga.evaluate(run, 'ledger_closure'):+.3%}")
assert np.isfinite(run.energy["closure"]).all()
