"""perga report: a person's path from an empty folder (issue 16's must-show), and a report of a
run that did not record everything, which says what is missing."""

import matplotlib.image as mpimg
import numpy as np

from perga.cli import main


def _coloured(png) -> int:
    """Pixels of clear colour (not white, grey or black): the data drawn. A figure's axes,
    ticks and labels are black and grey: empty axes of the report's size have 0 of them (and
    14,000 non-white pixels, so counting ink alone could not tell an empty figure)."""
    rgb = mpimg.imread(png)[..., :3]
    return int(np.sum(rgb.max(axis=2) - rgb.min(axis=2) > 0.3))


def test_new_run_report_from_an_empty_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["new", "separator", "-o", "x.toml"]) == 0
    assert main(["run", "x.toml", "--quiet"]) == 0
    assert main(["report", "runs/x"]) == 0
    report = (tmp_path / "runs" / "x" / "report" / "report.md").read_text(encoding="utf-8")
    assert "| status | completed |" in report and "| granule-hammer impacts | " in report
    for name in ("energy", "speeds", "impacts", "paths"):
        assert f"![{name}]({name}.png)" in report
        assert _coloured(tmp_path / "runs" / "x" / "report" / f"{name}.png") > 100, name


def test_a_report_says_what_the_run_did_not_record(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["new", "single-impact", "-o", "x.toml"]) == 0
    sets = ["--set", 'output.record=["granules", "hammers"]', "--set", "solver.duration=0.01"]
    assert main(["run", "x.toml", "--quiet", *sets]) == 0
    assert main(["report", "runs/x", "-o", "rep"]) == 0
    report = (tmp_path / "rep" / "report.md").read_text(encoding="utf-8")
    assert "no energy figure: energy.csv was not recorded" in report
    assert "no impact figure: impacts.csv was not recorded" in report
    assert "energy ledger closure | not kept" in report
    assert main(["report", "nowhere"]) == 2
