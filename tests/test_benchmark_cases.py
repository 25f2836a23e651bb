"""The benchmarks' bundled case files (benchmarks/cases/) are valid cases that run."""

from pathlib import Path

import numpy as np
import pytest

from perga.case import load_case
from perga.engine import Simulation
from perga.model.compile import compile_case

CASES = sorted((Path(__file__).resolve().parents[1] / "benchmarks" / "cases").glob("*.toml"))


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_benchmark_case_runs(path: Path) -> None:
    """Valid, and 20 machine steps leave every granule finite with the energy ledger closing
    within the project's 1 % (the ledger is measured from the start)."""
    sim = Simulation(compile_case(load_case(path, overrides=["solver.threads=1"])))
    sim.run(20 * sim.dt)
    assert np.isfinite(sim.frame().granules.positions).all()
    assert np.isfinite(sim.frame().granules.velocities).all()
    assert abs(sim.energy().closure) < 0.01
