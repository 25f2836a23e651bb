"""Every script in examples/ runs (from a scratch folder, as a user would) and exits 0; the
calibration data script makes the bundled measured.csv again, byte for byte."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted((ROOT / "examples").rglob("*.py"))
MEASURED = ROOT / "examples" / "calibration" / "measured.csv"


@pytest.mark.parametrize("script", SCRIPTS, ids=[p.name for p in SCRIPTS])
def test_example_runs(script, tmp_path):
    args = ["-o", str(tmp_path / "measured.csv"), "--workers", "1"]
    args = args if script.name == "make_data.py" else []
    done = subprocess.run([sys.executable, str(script), *args], cwd=tmp_path,
                          capture_output=True, text=True, timeout=900)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    if script.name == "make_data.py":
        assert (tmp_path / "measured.csv").read_bytes() == MEASURED.read_bytes()
