"""Every script in examples/ runs (from a scratch folder, as a user would) and exits 0; the
calibration data scripts make the bundled measured.csv and the published data again, byte for
byte."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted((ROOT / "examples").rglob("*.py"))
MEASURED = ROOT / "examples" / "calibration" / "measured.csv"
PUBLISHED = ROOT / "examples" / "calibration" / "published"


@pytest.mark.parametrize("script", SCRIPTS, ids=[p.name for p in SCRIPTS])
def test_example_runs(script, tmp_path):
    args = {
        "make_data.py": ["-o", str(tmp_path / "measured.csv"), "--workers", "1"],
        "make_kharaz2001.py": ["-o", str(tmp_path)],
    }.get(script.name, [])
    done = subprocess.run([sys.executable, str(script), *args], cwd=tmp_path,
                          capture_output=True, text=True, timeout=900)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    if script.name == "make_data.py":
        assert (tmp_path / "measured.csv").read_bytes() == MEASURED.read_bytes()
    if script.name == "make_kharaz2001.py":
        written = sorted(tmp_path.glob("*.csv"))
        assert [p.name for p in written] == sorted(p.name for p in PUBLISHED.glob("*.csv"))
        for path in written:
            assert path.read_bytes() == (PUBLISHED / path.name).read_bytes(), path.name
