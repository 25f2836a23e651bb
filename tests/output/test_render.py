"""perga render: preview PNGs of a run from its tables (matplotlib, no OpenGL)."""

from pathlib import Path

import matplotlib.image as mpimg
import numpy as np

from perga.cli import main
from perga.output.render import render

ROOT = Path(__file__).resolve().parents[2]


def _run(tmp_path: Path) -> Path:
    text = (ROOT / "cases" / "single-granule.toml").read_text()
    case = tmp_path / "case.toml"
    case.write_text(text.replace("duration = 0.2", "duration = 0.04"))
    out = tmp_path / "run"
    assert main(["run", str(case), "-o", str(out), "--quiet"]) == 0
    return out


def _coloured_pixels(png: Path) -> int:
    """Pixels of clear colour (not white, grey or black): only granules or paths are coloured
    when the colour bar is off (chamber, rotor and hammers are grey)."""
    rgb = mpimg.imread(png)[..., :3]
    return int(np.sum(rgb.max(axis=2) - rgb.min(axis=2) > 0.3))


def test_frame_and_trajectories_show_the_granules(tmp_path):
    run = _run(tmp_path)
    frame, paths = tmp_path / "frame.png", tmp_path / "paths.png"
    t = render(run, frame, time=0.02, colorbar=False)
    assert abs(t - 0.02) < 2e-4  # the recorded frame nearest 0.02 s (frames every 0.2 ms)
    render(run, paths, trajectories=True, colorbar=False)
    assert _coloured_pixels(frame) > 10  # a 2.5 mm disc at 120 dpi: about 30 pixels
    assert _coloured_pixels(paths) > _coloured_pixels(frame)  # a path covers more


def test_cli_writes_the_preview_and_refuses_a_missing_table(tmp_path, capsys):
    run = _run(tmp_path)
    assert main(["render", str(run)]) == 0
    assert (run / "preview.png").exists()
    (run / "hammers.csv").unlink()
    assert main(["render", str(run)]) == 2
    assert "hammers.csv: missing" in capsys.readouterr().err
