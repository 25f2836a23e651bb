"""The top-level Python API: light to import, each name where the docstring says, and its
refusals."""

import subprocess
import sys
from pathlib import Path

import pytest

import perga

ROOT = Path(__file__).resolve().parents[1]


def test_import_perga_loads_nothing_heavy():
    code = "import sys, perga; print(sorted({'numba', 'pymunk', 'scipy'} & set(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_names_and_refusals(tmp_path):
    assert set(perga.__all__) >= {"load_case", "Simulation", "simulate", "load_run", "evaluate"}
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        perga.nope  # noqa: B018
    case = ROOT / "cases" / "single-granule.toml"
    summary = perga.simulate(case, tmp_path / "run", overrides=["solver.duration=0.005"])
    assert summary.status == "completed"
    with pytest.raises(FileExistsError, match="already holds a run"):
        perga.simulate(case, tmp_path / "run")
    with pytest.raises(perga.CaseError, match=r"rotor\.rpm"):
        perga.simulate(case, tmp_path / "bad", overrides=["rotor.rpm=-1"])
    run = perga.load_run(tmp_path / "run")
    frame = run.dataframe("granules")
    assert (
        list(frame.columns)[:4] == ["time", "id", "x", "y"]
        and len(frame) == run.granules["id"].size
    )
    with pytest.raises(ValueError, match="no table 'trajectories'"):
        run.dataframe("trajectories")
