"""The real client: ParaView (its GUI, ``paraview``, and ``pvbatch``) opens a run written by perga
and renders it (skipped, saying why, where ParaView or xvfb-run is absent, failed under
``CI=true``: .ci/run installs Debian's paraview, python3-paraview and xvfb)."""

import subprocess
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest

from perga.cli import main
from tests.tools import require

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "postprocess" / "paraview" / "render_run.py"
OUTPUT_3D = "\n[output]\nvtk_3d = true\n"

PROGRAMS = ("paraview", "pvbatch", "xvfb-run")
INSTALL = "apt-get install paraview python3-paraview xvfb"


@pytest.fixture(autouse=True, scope="module")
def _paraview() -> None:
    """Every test here needs ParaView and a virtual display (tests/tools.py)."""
    require(*PROGRAMS, install=INSTALL)


GUI_DRIVER = """
import os
from paraview import simple as pv
state = open({state!r}).read()
# as File > Load State does: its text, with __file__ the state's path
exec(compile(state, "<state>", "exec"), {{"__name__": "__main__", "__file__": {state!r}}})
scene = pv.GetAnimationScene()
times = list(scene.TimeKeeper.TimestepValues)
open({times!r}, "w").write(f"{{scene.AnimationTime!r}} {{times[0]!r}} {{times[-1]!r}}")
pv.SaveScreenshot({png!r}, pv.GetActiveView(), ImageResolution=[900, 900])
open({names!r}, "w").write("\\n".join(sorted(k[0] for k in pv.GetSources())))
os._exit(0)  # the GUI would wait for its user
"""


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """The separator for 20 ms with the 3-D view on."""
    tmp_path = tmp_path_factory.mktemp("paraview")
    text = (ROOT / "cases" / "separator.toml").read_text()
    case = tmp_path / "case.toml"
    case.write_text(text.replace("duration = 0.5", "duration = 0.02") + OUTPUT_3D)
    run = tmp_path / "run"
    assert main(["run", str(case), "-o", str(run), "--quiet"]) == 0
    return run


def under_xvfb(*command: str) -> subprocess.CompletedProcess:
    """``command`` on a virtual display; the completed process (its return code checked)."""
    result = subprocess.run(
        ["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", *command],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    return result


def gui(*options: str) -> subprocess.CompletedProcess:
    """The ParaView GUI with ``options`` (user settings ignored, ``--dr``)."""
    return under_xvfb("paraview", "--dr", *options)


def coloured_pixels(png: Path, margin: int = 0) -> int:
    """Pixels of ``png`` with colour (max − min channel > 0.3): viridis granules (and a colour
    bar), never the grey machine, the dark chamber or the white background; ``margin`` px at
    each side left out."""
    rgb = mpimg.imread(png)[..., :3]
    h, w = rgb.shape[:2]
    rgb = rgb[margin : h - margin, margin : w - margin]
    return int(np.sum(rgb.max(axis=2) - rgb.min(axis=2) > 0.3))


def test_the_state_written_with_the_run_opens_in_the_paraview_gui(run, tmp_path):
    """RUN/vtk/paraview_state.py: ParaView's GUI loads it as a state (``--state``, its Load
    State path) without a Python error; executed in the GUI's Python as Load State does, it
    makes one source per file and a picture of the granules at their true size, at the run's
    last frame (at t = 0 every granule is at rest, one colour). Counted in the
    900 × 900 picture: the granules' colours in its central 600 × 600 px (the colour bar, ~8,000
    coloured px, is outside it) (300 discs 2.5 mm in radius, the 0.4 m chamber in
    ~640 px: ~8 px across, ~50 px each; asserted 30 each), the grey hammers (six 60 × 20 mm
    plates, ~3,000 px each: asserted 1,500 each)."""
    state = run / "vtk" / "paraview_state.py"
    empty = tmp_path / "empty.xml"
    empty.write_text('<?xml version="1.0" ?>\n<pqevents>\n</pqevents>\n')
    loaded = gui(f"--state={state}", f"--test-script={empty}", "--exit")
    assert "Traceback" not in loaded.stdout + loaded.stderr, loaded.stdout + loaded.stderr
    png, names, times = tmp_path / "gui.png", tmp_path / "sources.txt", tmp_path / "times.txt"
    driver = tmp_path / "driver.py"
    driver.write_text(GUI_DRIVER.format(state=str(state), png=str(png), names=str(names),
                                        times=str(times)))  # fmt: skip
    gui(f"--script={driver}")
    shown, first, last = (float(t) for t in times.read_text().split())
    assert shown == last > first  # it opens at the run's end, granules moving, not at rest
    sources = names.read_text().split("\n")
    assert sources == sorted(
        ["chamber", "granules", "granules at true size", "hammers", "rotor", "unit disc"]
    )
    assert coloured_pixels(png, margin=150) > 300 * 30  # the colour bar is outside, x > 780
    rgb = mpimg.imread(png)[..., :3]
    grey = np.all(np.abs(rgb - 0.5) < 0.03, axis=2)  # the hammers' unlit grey, 0.5
    assert int(grey.sum()) > 6 * 1500, int(grey.sum())


def pvbatch(run, *options):
    """Run the script on ``run``; the completed process (its return code checked)."""
    return under_xvfb("pvbatch", str(SCRIPT), str(run), *options)


def test_pvbatch_reads_the_series_and_renders_the_granules(run, tmp_path):
    png, state = tmp_path / "frame.png", tmp_path / "run.pvsm"
    result = pvbatch(run, "-o", str(png), "--no-bar", "--state", str(state))
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
    assert coloured_pixels(png) > 300 * 30


def test_pvbatch_renders_the_3d_machine(run, tmp_path):
    """--3d: the extruded machine from an oblique camera. Counted in the 900 × 900 image
    (measured: ~11,000 orange, ~9,000 granule, ~37,000 central grey pixels; the 2-D render has
    no orange and ~3,000 central grey): the six orange hammers (30 × 17 mm plates seen
    obliquely, ~1,800 px each; asserted 500 each), the grey disc around the granules in the
    central 240 × 240 px (asserted 10,000), the viridis cylinders of 300 granules (~30 px each;
    asserted 10 each)."""
    png = tmp_path / "machine3d.png"
    result = pvbatch(run, "--3d", "-o", str(png), "--no-bar")
    assert "time steps: 21 (0 .. 0.02 s)" in result.stdout
    assert "thickness" in result.stdout.split("granule arrays: ")[1].splitlines()[0]
    rgb = mpimg.imread(png)[..., :3]
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    hammers = int(np.sum((r > 1.3 * g) & (r > 2 * b) & (r > 0.25)))
    assert hammers > 6 * 500, hammers
    granules = int(np.sum((g > r + 0.1) | (b > r + 0.15)))
    assert granules > 300 * 10, granules
    h, w = rgb.shape[:2]
    centre = rgb[h // 2 - 120 : h // 2 + 120, w // 2 - 120 : w // 2 + 120]
    mean, spread = centre.mean(axis=2), centre.max(axis=2) - centre.min(axis=2)
    disc = int(np.sum((spread < 0.06) & (mean > 0.3) & (mean < 0.7)))
    assert disc > 10_000, disc


def test_3d_needs_a_3d_run(tmp_path):
    """A run without output.vtk_3d: --3d says what to do instead of drawing nothing."""
    case = tmp_path / "case.toml"
    text = (ROOT / "cases" / "separator.toml").read_text()
    case.write_text(text.replace("duration = 0.5", "duration = 0.001"))
    flat = tmp_path / "flat"
    assert main(["run", str(case), "-o", str(flat), "--quiet"]) == 0
    png = tmp_path / "x.png"
    result = subprocess.run(
        ["xvfb-run", "-a", "pvbatch", str(SCRIPT), str(flat), "--3d", "-o", str(png)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode != 0
    assert "output.vtk_3d = true" in result.stdout + result.stderr
