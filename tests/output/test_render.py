"""perga render: preview PNGs of a run from its tables (matplotlib, no OpenGL)."""

from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest

from perga.cli import main
from perga.output.render import TRACKS, draw, render, sample_tracks, speed_range

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


def test_trajectories_stop_at_the_time_asked(tmp_path):
    """--time with --trajectories draws the paths up to that frame: the granule, struck at
    about 22 ms, has a shorter path at 30 ms (measured 251 coloured pixels) than at the end,
    40 ms (522), and as long at the end as without a time (it drew the whole path whatever the
    time before)."""
    run = _run(tmp_path)
    early, end, whole = (tmp_path / f"{n}.png" for n in ("early", "end", "whole"))
    assert abs(render(run, early, time=0.03, trajectories=True, colorbar=False) - 0.03) < 2e-4
    render(run, end, time=0.04, trajectories=True, colorbar=False)
    render(run, whole, trajectories=True, colorbar=False)
    assert 10 < _coloured_pixels(early) < _coloured_pixels(end) == _coloured_pixels(whole)


def test_speeds_are_coloured_from_zero():
    """The colour scale starts at 0 m/s; at rest (t = 0) it spans 0-1 m/s, never negative."""
    assert speed_range(np.array([0.5, 2.0])) == (0.0, 2.0)
    assert speed_range(np.zeros(3)) == (0.0, 1.0)
    assert speed_range(np.array([])) == (0.0, 1.0)


def test_cli_writes_the_preview_and_refuses_a_missing_table(tmp_path, capsys):
    run = _run(tmp_path)
    assert main(["render", str(run)]) == 0
    assert (run / "preview.png").exists()
    (run / "hammers.csv").unlink()
    assert main(["render", str(run)]) == 2
    assert "hammers.csv: missing" in capsys.readouterr().err


def _track_ends(fig) -> int:
    """The granule paths drawn: one dot where each ends (gid "track ends")."""
    (ends,) = [c for c in fig.axes[0].collections if c.get_gid() == "track ends"]
    return len(ends.get_offsets())


def test_a_one_granule_run_draws_its_track(tmp_path):
    """Asked for the default handful of paths, a run of one granule draws that one."""
    fig, _ = draw(_run(tmp_path), trajectories=True)
    assert TRACKS > 1 and _track_ends(fig) == 1


def test_trajectories_draw_as_many_tracks_as_asked(tmp_path):
    """Of the separator's 300 granules (its first 10 ms, before any impact: spread by id) the
    paths drawn are as many as asked, and never more than the granules."""
    case = str(ROOT / "cases" / "separator.toml")
    out = tmp_path / "sep"
    sets = ["solver.duration=0.01", "output.checkpoint_every=0",
            'output.record=["granules", "hammers", "impacts"]']  # fmt: skip
    overrides = [a for s in sets for a in ("--set", s)]
    assert main(["run", case, "-o", str(out), "--quiet", *overrides]) == 0
    for tracks in (1, 3, 8):
        fig, _ = draw(out, trajectories=True, tracks=tracks)
        assert _track_ends(fig) == tracks
    fig, _ = draw(out, trajectories=True, tracks=1000)
    assert _track_ends(fig) == 300
    assert main(["render", str(out), "--trajectories", "--tracks", "1"]) == 0
    with pytest.raises(SystemExit) as refused:
        main(["render", str(out), "--trajectories", "--tracks", "0"])
    assert refused.value.code == 2


def test_tracks_are_the_granules_most_struck_else_spread_by_id():
    """The granules with the most impacts first, ties by id; without impacts, ids evenly
    spread from the first to the last; a count below 1 is refused."""
    ids = np.arange(10, 20)
    impacts = np.zeros(6, dtype=[("granule", float)])
    impacts["granule"] = [15, 15, 15, 12, 12, 17]
    assert sample_tracks(ids, impacts, 2).tolist() == [12, 15]
    assert sample_tracks(ids, impacts, 4).tolist() == [10, 12, 15, 17]
    assert sample_tracks(ids, impacts[:0], 3).tolist() == [10, 14, 19]
    assert sample_tracks(ids, None, 30).tolist() == ids.tolist()
    with pytest.raises(ValueError, match="tracks must be >= 1"):
        sample_tracks(ids, None, 0)
