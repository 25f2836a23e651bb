"""Progress off a terminal (a log file, a pipe, a batch job): whole lines, never carriage
returns; --quiet: nothing."""

from pathlib import Path

from perga.cli import main
from perga.progress import LineProgress

ROOT = Path(__file__).resolve().parents[1]


def test_a_run_logs_whole_lines(tmp_path, capsys):
    """stderr captured (not a terminal): the run's progress is one plain line at the end (the
    run is shorter than the 10 s between lines), no carriage return (tqdm wrote ~1,000 onto
    one 48 KB line of a log)."""
    args = ["run", str(ROOT / "cases" / "single-granule.toml"), "-o", str(tmp_path / "run")]
    assert main([*args, "--set", "solver.duration=0.02"]) == 0
    err = capsys.readouterr().err
    assert "\r" not in err
    (line,) = [x for x in err.splitlines() if x.startswith("perga run: ")]
    assert line.startswith("perga run: 0.02/0.02 s simulated (100%), ") and "steps/s" in line
    assert main([*args, "--set", "solver.duration=0.02", "--overwrite", "--quiet"]) == 0
    assert "perga run: " not in capsys.readouterr().err


def test_lines_come_at_their_interval(capsys):
    """every = 0: a line per update; a close after the last update adds none."""
    bar = LineProgress(4, "runs", "perga sweep", every=0.0)
    for _ in range(4):
        bar.update(1)
    bar.set_postfix_str("2 failed")
    bar.close()
    lines = capsys.readouterr().err.splitlines()
    assert [x.split(",")[0] for x in lines] == [f"perga sweep: {k}/4 runs ({k / 4:.0%})" for k in
                                               range(1, 5)]  # fmt: skip
