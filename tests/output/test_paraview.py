"""The real client: ParaView's pvbatch opens a run written by perga and renders it (skipped,
saying why, where ParaView or xvfb-run is absent; .ci/run installs Debian's paraview and xvfb)."""

import shutil
import subprocess
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest

from perga.cli import main

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "postprocess" / "paraview" / "render_run.py"

pytestmark = pytest.mark.skipif(
    shutil.which("pvbatch") is None or shutil.which("xvfb-run") is None,
    reason="ParaView's pvbatch or xvfb-run is not installed (apt-get install paraview xvfb)",
)


def test_pvbatch_reads_the_series_and_renders_the_granules(tmp_path):
    text = (ROOT / "cases" / "separator.toml").read_text()
    case = tmp_path / "case.toml"
    case.write_text(text.replace("duration = 0.5", "duration = 0.02"))
    run = tmp_path / "run"
    assert main(["run", str(case), "-o", str(run), "--quiet"]) == 0
    png, state = tmp_path / "frame.png", tmp_path / "run.pvsm"
    options = ["-o", str(png), "--no-bar", "--state", str(state)]
    result = subprocess.run(
        ["xvfb-run", "-a", "pvbatch", str(SCRIPT), str(run), *options],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    saved = state.read_text()
    assert "PVDReader" in saved and str(run / "vtk" / "granules.pvd") in saved
    # frames every 1 ms from 0 to 20 ms: 21 time steps, as the .pvd lists them
    assert "time steps: 21 (0 .. 0.02 s)" in result.stdout
    arrays = result.stdout.split("granule arrays: ")[1].splitlines()[0].split(", ")
    for name in ("radius", "velocity", "angular_velocity", "speed", "kinetic_energy", "id"):
        assert name in arrays
    # without the colour bar the granules (viridis: no greys) are the only coloured things
    # (hammers, rotor outline, chamber grey, background white): 300 discs 2.5 mm in radius, the
    # 0.4 m chamber fitted into ~640 px, are ~8 px across, ~50 px each; asserted: 30 each
    rgb = mpimg.imread(png)[..., :3]
    coloured = int(np.sum(rgb.max(axis=2) - rgb.min(axis=2) > 0.3))
    assert coloured > 300 * 30, coloured
