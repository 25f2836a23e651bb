"""perga report: a person's path from an empty folder (issue 16's must-show), and a report of a
run that did not record everything, which says what is missing; report.html beside report.md
holds its figures and tables (tests/html_pages.py)."""

import matplotlib.image as mpimg
import numpy as np

from perga.cli import main
from perga.stats.metrics import evaluate
from perga.stats.tables import load_run
from tests.figure_data import bar_heights, lines, saved_figures
from tests.html_pages import assert_self_contained


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
    page = assert_self_contained(tmp_path / "runs" / "x" / "report" / "report.md")
    assert len(page.images) == 4 and page.tables == 1


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


def test_the_reports_figures_draw_the_runs_tables(tmp_path, monkeypatch):
    """Issue 18, item 6: each figure of `perga report` holds its table's data, not merely ink.
    The energy figure's lines are energy.csv's columns (the kinetic energy's change since the
    first frame; the closure in per cent); the speed histograms count every granule of the
    first and the last frame in the table's bins; the impact figure counts every impact and
    plots each one's approach speed. Exact: the same floats are drawn (1e-12 for the sums)."""
    monkeypatch.chdir(tmp_path)
    assert main(["new", "separator", "-o", "x.toml"]) == 0
    assert main(["run", "x.toml", "--quiet", "--set", "solver.duration=0.2"]) == 0
    saved = saved_figures(monkeypatch)
    assert main(["report", "runs/x"]) == 0
    run = load_run(tmp_path / "runs" / "x")
    e = run.energy
    terms, closure = saved["energy.png"].axes
    drawn = lines(terms)
    assert np.array_equal(drawn["kinetic energy change"][1], e["kinetic"] - e["kinetic"][0])
    for name in ("drive_work", "contact_dissipation", "friction", "joint_correction"):
        x, y = drawn[name.replace("_", " ")]
        assert np.array_equal(x, e["time"]) and np.array_equal(y, e[name]), name
    assert np.array_equal(closure.get_lines()[0].get_ydata(), 100.0 * e["closure"])
    g = run.granules
    times = np.unique(g["time"])
    bars = bar_heights(saved["speeds.png"].axes[0])
    assert len(bars) == 60  # 30 bins for each of two frames
    bins = np.linspace(0.0, g["speed"].max(), 31)
    for k, t in enumerate((times[0], times[-1])):
        counts = np.histogram(g["speed"][g["time"] == t], bins=bins)[0]
        assert np.array_equal(bars[30 * k : 30 * (k + 1)], counts)
        assert counts.sum() == np.count_nonzero(g["time"] == t)
    count, speed = saved["impacts.png"].axes
    impacts = run.impacts
    assert len(impacts["time"]) > 0 and bar_heights(count).sum() == len(impacts["time"])
    assert np.array_equal(speed.get_lines()[0].get_ydata(), -impacts["normal_velocity_before"])


def test_the_report_of_a_process_run_shows_the_process(tmp_path, monkeypatch):
    """The bee-bread separator (comb, feed, damage, screen) for 0.05 s: the report's process
    section gives the population as the summary counted it, each process metric in the
    designer's units as perga metrics gives it (or why not), and the process figure."""
    monkeypatch.chdir(tmp_path)
    assert main(["new", "fed-separator", "-o", "x.toml"]) == 0
    assert main(["run", "x.toml", "--quiet", "--set", "solver.duration=0.05"]) == 0
    assert main(["report", "runs/x"]) == 0
    report = (tmp_path / "runs" / "x" / "report" / "report.md").read_text(encoding="utf-8")
    run = load_run(tmp_path / "runs" / "x")
    section = report[report.index("## Process") :]
    for key, count in run.summary["population"].items():
        assert f"| {key.replace('_', ' ')} | {count} | granules |" in section
    assert run.summary["population"]["fed"] > run.summary["granules"]  # a feed came in
    released = evaluate(run, "released_fraction")
    assert (
        f"| released [%] | {released * 100:.4g} | share of the granules held in comb cells at t = 0"
        in section
    )
    assert "| damaged [%] | " in section and "| throughput [kg/h] | " in section
    assert "| energy [kJ/kg] | " in section
    assert "![process](process.png)" in section
    assert _coloured(tmp_path / "runs" / "x" / "report" / "process.png") > 100
    page = assert_self_contained(tmp_path / "runs" / "x" / "report" / "report.md")
    assert len(page.images) == 5 and page.tables == 2
